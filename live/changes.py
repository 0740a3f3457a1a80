"""Which changes can move a caustic: a depsgraph's updates to the objects
that take part (meshes not set to Ignore, lights, instancers, and whatever
the last update read), to materials, lights, worlds and node trees other
than the bake's own, and the scene's caustic settings. The camera, the
view, selection and objects that take no part cost nothing. The scene's
own settings are compared by `settings_key`."""

import bpy

from ..export.materials import BAKE_TAG


def _takes_part(ob) -> bool:
    if ob.type == 'LIGHT':
        return True
    if ob.type == 'MESH':
        return ob.caustic.role != 'IGNORE'
    return ob.instance_type != 'NONE'


def moves_caustic(depsgraph, read_from: set[str], echo: set[str]) -> bool:
    """Whether an update of `depsgraph` can move a caustic; `read_from`
    names the Blender objects the last update read. `echo` names the
    materials whose nodes or images Live itself changed since the last
    depsgraph update: Blender then reports them, their node trees and
    every object's shading and geometry as updated, so while it is not
    empty only transforms count for objects."""
    for update in depsgraph.updates:
        data = update.id.original
        if isinstance(data, bpy.types.Object):
            changed = update.is_updated_transform or (
                not echo and (update.is_updated_geometry or update.is_updated_shading))
            if changed and (data.name in read_from or _takes_part(data)):
                return True
        elif isinstance(data, (bpy.types.World, bpy.types.Light)):
            return True
        elif isinstance(data, bpy.types.Material):
            if data.name not in echo:
                return True
        elif isinstance(data, bpy.types.NodeTree) and BAKE_TAG not in data and not _tree_of(data, echo):
            return True
    return False


def _tree_of(tree, materials: set[str]) -> bool:
    """Whether `tree` is the node tree of one of `materials`."""
    return any(material.node_tree == tree for material in bpy.data.materials if material.name in materials)


def forget_meshes(depsgraph, meshes: dict) -> None:
    """Drop from `meshes` (export.read_scene's, by object name) the
    objects whose geometry `depsgraph` updated."""
    for update in depsgraph.updates:
        if isinstance(update.id, bpy.types.Object) and update.is_updated_geometry:
            meshes.pop(update.id.original.name, None)


def settings_key(scene) -> tuple:
    """The scene's caustic settings and world, as a key that changes when
    one of them does: Live's timer compares it at each call, since a
    setting changed from Python sends no depsgraph update, and a Scene
    update comes with selection too."""
    props = scene.caustic
    values = tuple(getattr(props, p.identifier) for p in props.bl_rna.properties if p.identifier != "rna_type")
    return tuple(v[:] if hasattr(v, "__len__") and not isinstance(v, str) else v for v in values) + (
        scene.world.name if scene.world is not None else None,)
