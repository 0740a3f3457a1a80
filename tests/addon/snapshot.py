"""Every RNA property of a struct, recursively, as plain Python values, so
tests can tell whether anything in the file changed."""

import warnings

import bpy

# Runtime state, not data: it changes without anyone editing the file.
VOLATILE = {"rna_type", "session_uid", "is_evaluated", "original", "bindcode", "storage_type", "depsgraph",
            "tool_settings", "is_visible"}
MAX_DEPTH = 6


def plain(value):
    """A copy of a property value that holds no reference into Blender's memory."""
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    if isinstance(value, set):
        return tuple(sorted(value))
    return tuple(plain(item) for item in value)


def rna(struct, depth=0):
    """Nested dicts and tuples of `struct`'s properties; IDs it points to appear by name."""
    if struct is None:
        return None
    if isinstance(struct, bpy.types.ID) and depth > 0:
        return ("ID", type(struct).__name__, struct.name)
    if depth > MAX_DEPTH:
        return "..."
    out = {}
    for prop in struct.bl_rna.properties:
        name = prop.identifier
        if name in VOLATILE:
            continue
        try:
            value = getattr(struct, name)
        except (AttributeError, RuntimeError):
            continue
        if prop.type == 'POINTER':
            out[name] = rna(value, depth + 1)
        elif prop.type == 'COLLECTION':
            out[name] = tuple(rna(item, depth + 1) for item in value)
        else:
            out[name] = plain(value)
    return out


def snapshot_file():
    """All ID datablocks of the kinds a render could touch, by collection and name."""
    kinds = ("objects", "meshes", "materials", "node_groups", "images", "lights", "cameras", "worlds", "scenes",
             "collections", "textures")
    with warnings.catch_warnings():
        # Blender 5 warns on reading properties it will remove, such as use_nodes.
        warnings.simplefilter("ignore", DeprecationWarning)
        state = {kind: {block.name: rna(block) for block in getattr(bpy.data, kind)} for kind in kinds}
        state["material node trees"] = {m.name: material_state(m) for m in bpy.data.materials if m.node_tree}
    return state


def material_state(material):
    """The material's nodes (with every socket value) and its links, order-free."""
    tree = material.node_tree
    nodes = {node.name: rna(node) for node in tree.nodes}
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                   for l in tree.links)
    return nodes, links
