"""A bake's write-back: each receiver's illumination map as a packed (or
on-disk, for an animation) float image, shown by its material through one
node group (bake_group.py); which receivers can take one."""

import bpy
import numpy as np

from ..export import SceneRead
from ..export.materials import albedo_socket
from .bake_group import make_group, material_output, unwire, wire
from .images import write_image

IMAGE_PREFIX = "Caustic Map "
GROUP_PREFIX = "Caustic Bake "


def bakeable(read: SceneRead, names) -> tuple[dict, list[str]]:
    """{receiver name: material} for the receivers whose material can show a
    bake, and a warning for each one that cannot."""
    plan, warnings, owners = {}, [], {}
    for name in names:
        material = bpy.data.materials.get(read.materials.get(name) or "")
        if name in read.instanced:
            warnings.append(f"'{name}' is an instance; its caustic cannot be baked into a material")
        elif material is None:
            warnings.append(f"'{name}' has no material to show its baked caustic")
        elif material.node_tree is None or material_output(material) is None or not (
                bpy.app.version >= (5, 0, 0) or material.use_nodes):
            warnings.append(f"material '{material.name}' of '{name}' has no node output to add the caustic to")
        elif material.name in owners:
            warnings.append(f"material '{material.name}' is shared by '{owners[material.name]}' and '{name}'; "
                            f"only the caustic on '{owners[material.name]}' is baked")
        else:
            owners[material.name] = name
            plan[name] = material
    return plan, warnings


def map_rgba(imap) -> np.ndarray:
    """(h,w,4) float32 of a map's irradiance, top row first (map row 0 is the chart's lowest y)."""
    rgba = np.ones(imap.shape + (4,), dtype=np.float32)
    rgba[..., :3] = imap.irradiance()
    return rgba[::-1]


def bake_maps(read: SceneRead, maps) -> tuple[list[str], list[str]]:
    """Each bakeable receiver's map of `maps` into a packed image its
    material shows, replacing an earlier bake: (receivers baked, warnings)."""
    plan, warnings = bakeable(read, maps)
    for name, material in plan.items():
        unwire(material)
        wire_bake(read, name, material, write_image(IMAGE_PREFIX + name, map_rgba(maps[name])), maps[name])
    return list(plan), warnings


def wire_bake(read: SceneRead, name: str, material, image, imap):
    """`image` of receiver `name`'s map `imap` shown by its `material` through a new node group; returns the group."""
    source = bpy.data.objects[read.sources[name]].data
    uv_layer = source.uv_layers.active.name if source.uv_layers.active is not None else ""
    receiver = next(o.material for o in read.scene.objects if o.name == name)
    share = receiver.specular.diffuse_share if receiver.specular is not None else None
    group = make_group(GROUP_PREFIX + name, image, imap, receiver.albedo, uv_layer, share)
    wire(material, group, albedo_socket(material))
    return group
