"""Live's write-back: the receivers' maps into the bake's images and node
groups (bake.py), wired in once and then only refilled. A receiver Live
wires gets exactly the nodes Bake would add; its group is tagged LIVE with
what Live did: ADDED where the material had no bake, REPLACED where Live
took an earlier bake's place. `remove_live` takes out what Live added and
leaves a replaced bake holding Live's last caustic, packed, as a bake."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from ..export import SceneRead
from .bake import IMAGE_PREFIX, bakeable, wire_bakes
from .bake_group import _group_image, baked_nodes, unwire
from .images import pack_image, write_image

LIVE = "caustic_live"
ADDED, REPLACED = "added", "replaced"


def _signature(read: SceneRead, name: str, material, imap) -> tuple:
    """What a receiver's node group is built from, but for its frame's
    placement and its image's pixels: equal signatures, the group can be
    refilled in place."""
    receiver = next(o.material for o in read.scene.objects if o.name == name)
    source = bpy.data.objects[read.sources[name]]
    uv_layer = source.data.uv_layers.active.name if source.data.uv_layers.active is not None else ""
    frame = imap.image_frame()
    return (material.name, source.name, uv_layer, np.asarray(receiver.albedo).tolist(), repr(receiver.specular),
            frame.coordinates, repr(frame.islands))


class LiveImages:
    """The groups Live wired in this session: receiver name -> (group
    name, signature); `echo` names the materials whose nodes or images
    (packed, resized) a `show` changed since it was last reset: Blender
    reports them, and every object's shading, as updated."""

    def __init__(self):
        self.wired: dict[str, tuple[str, tuple]] = {}
        self.echo: set[str] = set()

    def show(self, read: SceneRead, maps, images: dict, pack: bool) -> tuple[list[str], list[str]]:
        """Each bakeable receiver's map of `maps`, whose image `images`
        holds (jobs.map_rgba), shown by its material:
        refilled where its group is wired as it needs, else wired anew;
        packed (undo and saving keep it) if `pack`. Returns (receivers
        shown, warnings)."""
        plan, warnings = bakeable(read, maps)
        signatures = {name: _signature(read, name, material, maps[name]) for name, material in plan.items()}
        groups = {name: bpy.data.node_groups.get(self.wired[name][0]) for name in plan if name in self.wired}
        if set(plan) == set(self.wired) and all(
                groups[name] is not None and LIVE in groups[name] and self.wired[name][1] == signatures[name]
                and any(node.node_tree == groups[name] for node in baked_nodes(plan[name])) for name in plan):
            for name, group in groups.items():
                resized = tuple(_group_image(group).size) != maps[name].shape[::-1]
                write_image(IMAGE_PREFIX + name, images[name], pack=pack)
                if _place(group, maps[name].image_frame()) or resized or pack:
                    self.echo.add(plan[name].name)
            return list(plan), warnings
        replaced = {material.name for material in plan.values()
                    if any(LIVE not in node.node_tree for node in baked_nodes(material))}
        made = wire_bakes(read, plan, maps, lambda name: write_image(IMAGE_PREFIX + name, images[name], pack=pack))
        self.wired = {}
        self.echo |= {material.name for material in plan.values()}
        for name, group in made.items():
            group[LIVE] = REPLACED if plan[name].name in replaced else ADDED
            self.wired[name] = (group.name, signatures[name])
        return list(plan), warnings


def _place(group, frame) -> bool:
    """Set the group's Mapping node to `frame`'s placement; whether it changed."""
    inputs = next(node for node in group.nodes if node.bl_idname == 'ShaderNodeMapping').inputs
    wanted = {"Location": frame.location.tolist(), "Scale": frame.scale.tolist(),
              "Rotation": list(Matrix(frame.rotation.tolist()).to_euler('XYZ'))}
    changed = False
    for socket, value in wanted.items():
        if list(inputs[socket].default_value) != value:
            inputs[socket].default_value, changed = value, True
    return changed


def _live_nodes(material) -> list:
    return [node for node in baked_nodes(material) if LIVE in node.node_tree]


def _pack(image) -> None:
    """Pack `image` if it holds pixels that are only in memory (a preview
    written since the last pack)."""
    if image is not None and image.is_dirty:
        pack_image(image)


def pack_live() -> None:
    """Pack the images of Live's groups that hold a preview only in memory,
    so that saving keeps them."""
    for material in bpy.data.materials:
        for node in _live_nodes(material):
            _pack(_group_image(node.node_tree))


def remove_live() -> int:
    """Take out every group Live added, with its image; groups where Live
    replaced a bake stay, as a bake of Live's last caustic, packed. Returns
    how many receivers lost their caustic."""
    removed = 0
    for material in bpy.data.materials:
        nodes = _live_nodes(material)
        if any(node.node_tree[LIVE] == ADDED for node in nodes):
            removed += unwire(material)
            continue
        for node in nodes:
            _pack(_group_image(node.node_tree))
            del node.node_tree[LIVE]
    return removed
