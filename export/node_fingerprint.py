"""What a node tree's output depends on, as a value to compare: every
node's settings and unlinked inputs, and every link. A bake of the tree
(a world's, a receiver's colour) is kept while its fingerprint stays."""

from __future__ import annotations

import bpy
import numpy as np

# Node properties that change only how the node looks in the editor.
_LOOKS = {"rna_type", "location", "location_absolute", "width", "height", "dimensions", "name", "label", "select",
          "show_options", "show_preview", "show_texture", "hide", "use_custom_color", "color", "color_tag",
          "warning_propagation", "parent", "inputs", "outputs", "internal_links", "type"}


def _values(struct, depth: int = 0) -> tuple:
    """The values of a node's (or a texture mapping's) RNA properties, IDs by name."""
    values = []
    for prop in struct.bl_rna.properties:
        if prop.identifier in _LOOKS or prop.identifier.startswith("bl_"):
            continue
        value = getattr(struct, prop.identifier)
        if prop.type == 'POINTER':
            if isinstance(value, bpy.types.ID):
                value = (value.name_full, getattr(value, "filepath", ""), getattr(value, "is_dirty", False))
            elif value is not None and depth < 2:
                value = _values(value, depth + 1)
            else:
                continue
        elif prop.type == 'COLLECTION':
            continue
        elif getattr(prop, "is_array", False):
            value = tuple(np.ravel(value).tolist())
        values.append((prop.identifier, value))
    return tuple(values)


def fingerprint(tree) -> tuple:
    """What the tree's light depends on: every node's settings and unlinked
    inputs, and every link."""
    nodes = tuple((node.name, node.bl_idname, node.mute, _values(node),
                   tuple(np.ravel(s.default_value).tolist() if hasattr(s, "default_value") else None
                         for s in node.inputs))
                  for node in tree.nodes)
    links = tuple((link.from_node.name, link.from_socket.identifier, link.to_node.name, link.to_socket.identifier,
                   link.is_muted) for link in tree.links)
    return nodes, links
