"""A bake's write-back: each receiver's illumination map as a packed (or
on-disk, for an animation) float image, shown by its material through one
node group (bake_group.py); which receivers can take one. A material that
several receivers share shows each one's caustic on that receiver alone:
the bake numbers their objects in the custom property SELECTOR, which each
group compares."""

from collections import Counter

import bpy
import numpy as np

from ..export import SceneRead
from ..export.materials import albedo_socket
from ..jobs import map_rgba
from .bake_group import make_group, material_output, unwire, wire
from .images import write_image

IMAGE_PREFIX = "Caustic Map "
GROUP_PREFIX = "Caustic Bake "
SELECTOR = "caustic_receiver"


def bakeable(read: SceneRead, names) -> tuple[dict, list[str]]:
    """{receiver name: material} for the receivers whose material can show a
    bake, and a warning for each one that cannot."""
    plan, warnings = {}, []
    for name in names:
        material = bpy.data.materials.get(read.materials.get(name) or "")
        if name in read.instanced:
            warnings.append(f"'{name}' is an instance; its caustic cannot be baked into a material")
        elif material is None:
            warnings.append(f"'{name}' has no material to show its baked caustic")
        elif material.node_tree is None or material_output(material) is None or not (
                bpy.app.version >= (5, 0, 0) or material.use_nodes):
            warnings.append(f"material '{material.name}' of '{name}' has no node output to add the caustic to")
        else:
            plan[name] = material
    return plan, warnings


def bake_maps(read: SceneRead, maps) -> tuple[list[str], list[str]]:
    """Each bakeable receiver's map of `maps` into a packed image its
    material shows, replacing an earlier bake: (receivers baked, warnings)."""
    plan, warnings = bakeable(read, maps)
    wire_bakes(read, plan, maps, lambda name: write_image(IMAGE_PREFIX + name, map_rgba(maps[name])))
    return list(plan), warnings


def wire_bakes(read: SceneRead, plan: dict, maps, image_of) -> dict:
    """Replace the bake of each material of `plan` ({receiver name:
    material}) with the image `image_of(name)` of each receiver's map in
    `maps`; where receivers share a material, number their objects in
    SELECTOR so that each shows its own. Returns {receiver name: group}."""
    for material in {material.name: material for material in plan.values()}.values():
        unwire(material)
    sharing = Counter(material.name for material in plan.values())
    for name in plan:
        bpy.data.objects[read.sources[name]].pop(SELECTOR, None)
    numbers, groups = {}, {}
    for name, material in plan.items():
        number = None
        if sharing[material.name] > 1:
            source = bpy.data.objects[read.sources[name]]
            number = numbers.setdefault(source.name, len(numbers) + 1)
            source[SELECTOR] = number
        groups[name] = _wire_bake(read, name, material, image_of(name), maps[name], number)
    return groups


def forget_selectors() -> None:
    """Take the bake's SELECTOR off every object that has it."""
    for obj in bpy.data.objects:
        if SELECTOR in obj:
            del obj[SELECTOR]


def _wire_bake(read: SceneRead, name: str, material, image, imap, number: int | None):
    """`image` of receiver `name`'s map `imap` shown by its `material`
    through a new node group, on objects whose SELECTOR is `number` only if
    one is given; returns the group."""
    source = bpy.data.objects[read.sources[name]].data
    uv_layer = source.uv_layers.active.name if source.uv_layers.active is not None else ""
    receiver = next(o.material for o in read.scene.objects if o.name == name)
    share = receiver.specular.diffuse_share if receiver.specular is not None else None
    selector = None if number is None else (SELECTOR, number)
    group = make_group(GROUP_PREFIX + name, image, imap, receiver.albedo, uv_layer, share, selector)
    wire(material, group, albedo_socket(material))
    return group
