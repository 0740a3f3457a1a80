"""Blender's evaluated scene (modifiers applied, instances expanded) copied
into the engine's numpy Scene, in world space. It runs on the main thread;
what it returns holds no bpy data, so the engine can run on a worker thread."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import Scene
from .camera import camera_warnings, dummy_camera, read_camera
from .errors import InputError
from .lamps import engine_light
from .materials import Surface
from .matrices import numpy_matrix
from .meshes import mesh_object, renderable_objects
from .world import engine_world

# Object types with geometry the engine cannot take.
UNSUPPORTED_GEOMETRY = {'CURVE', 'SURFACE', 'META', 'FONT', 'VOLUME', 'CURVES', 'POINTCLOUD', 'GPENCIL',
                        'GREASEPENCIL'}


@dataclass
class SceneRead:
    """The engine scene and where its parts came from.

    sources    engine object or lamp name -> name of the Blender object it was read from
    materials  engine object name -> name of the Blender material used, or None
    instanced  engine object names that come from instances (not bakeable)
    """

    scene: Scene
    warnings: list[str]
    sources: dict[str, str] = field(default_factory=dict)
    materials: dict[str, Optional[str]] = field(default_factory=dict)
    instanced: set[str] = field(default_factory=set)


def read_scene(context, with_camera: bool = True, depsgraph=None) -> SceneRead:
    """The engine scene of the context's view layer, or of `depsgraph` (as
    a render evaluates it) when given. Raises InputError if it has no
    camera (when `with_camera`), no light (neither a lamp nor a world) or
    no receiver."""
    if depsgraph is None:
        scene, view_layer, depsgraph = context.scene, context.view_layer, context.evaluated_depsgraph_get()
    else:
        scene, view_layer = depsgraph.scene, depsgraph.view_layer
    camera = read_camera(scene, depsgraph) if with_camera else dummy_camera()
    warnings = camera_warnings(scene) if with_camera else []
    renderable = renderable_objects(view_layer)
    read = SceneRead(Scene(objects=[], lights=[], camera=camera), warnings)
    surfaces: dict[Optional[str], Surface] = {}
    seen = set()
    for number, inst in enumerate(depsgraph.object_instances):
        ob = inst.object
        source = ob.original
        if (inst.parent.original if inst.is_instance else source).name not in renderable:
            continue
        seen.add(source.name)
        name = f"{source.name} [{inst.parent.original.name} #{number}]" if inst.is_instance else source.name
        matrix = numpy_matrix(inst.matrix_world)
        if ob.type == 'LIGHT':
            read.scene.lights.append(engine_light(ob, matrix, name, warnings))
            read.sources[name] = source.name
        elif ob.type in UNSUPPORTED_GEOMETRY:
            warnings.append(f"'{name}': {ob.type.lower()} objects are not supported; convert it to a mesh")
        elif ob.type == 'MESH' and source.caustic.role != 'IGNORE':
            obj, material = mesh_object(ob, name, matrix, surfaces, warnings)
            if obj is not None:
                read.scene.objects.append(obj)
                read.sources[name], read.materials[name] = source.name, material
                if inst.is_instance:
                    read.instanced.add(name)
    hidden = sorted(n for n in renderable - seen if bpy.data.objects[n].type in {'MESH', 'LIGHT'})
    warnings += [f"'{n}' is hidden in the viewport, so it was left out; unhide it to render it" for n in hidden]
    read.scene.world = engine_world(scene.world, warnings)
    read.scene.ambient = np.array(scene.caustic.ambient[:], dtype=np.float64)
    if not read.scene.lights and read.scene.world.is_black:
        raise InputError("Nothing lights the scene: it has no lamp, and its world is black")
    if not read.scene.receivers:
        raise InputError("No object receives caustics: give a mesh a diffuse material or set its "
                         "Caustics role to Receiver")
    return read
