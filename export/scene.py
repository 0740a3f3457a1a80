"""Blender's scene as a render evaluates it (modifiers at their render
settings, instances expanded; see render_view.py) copied into the engine's
numpy Scene, in world space. It runs on the main thread; what it returns
holds no bpy data, so the engine can run on a worker thread."""

from __future__ import annotations

import collections
from dataclasses import dataclass, field
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import Scene, Visibility
from .camera import camera_warnings, check_camera, check_render_size, dummy_camera, read_camera
from .errors import InputError
from .lamps import engine_light
from .materials import Surface
from .matrices import numpy_matrix
from .meshes import MeshSource, mesh_objects, object_visibility, place, read_source
from .render_view import adaptive_subdivision, read_as_render, renderable_objects, viewport_differences
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


def read_scene(context, with_camera: bool = True, depsgraph=None, meshes: Optional[dict] = None) -> SceneRead:
    """The engine scene of the context's view layer, as a render sees it,
    or of `depsgraph` when given (one a render is evaluating: its handlers
    read it). Raises InputError if it has no camera (when `with_camera`), no
    light (neither a lamp nor a world) or no receiver. A scene without a
    camera, or a view layer disabled for rendering, which Blender does not
    render, is read as the viewport shows it, and a warning names what a
    render would see otherwise. `meshes` keeps the meshes read from
    `depsgraph` between reads (meshes.mesh_objects)."""
    scene, view_layer = (context.scene, context.view_layer) if depsgraph is None else (depsgraph.scene, None)
    if with_camera:
        check_camera(scene)
    if depsgraph is not None:
        read = _read_objects(scene, depsgraph, with_camera, meshes=meshes)
    elif scene.camera is not None and view_layer.use:
        check_render_size(scene.render)
        read = read_as_render(scene, view_layer, lambda depsgraph: _read_objects(scene, depsgraph, with_camera))
        adaptive = sorted({read.sources[name] for name in read.materials
                           if adaptive_subdivision(scene, bpy.data.objects[read.sources[name]])})
        read.warnings += [f"'{name}': Cycles subdivides it adaptively when it renders; the caustic render uses "
                          "its Subdivision Surface's Render levels" for name in adaptive]
    else:
        renderable = renderable_objects(view_layer)
        read = _read_objects(scene, context.evaluated_depsgraph_get(), with_camera, renderable)
        differ = viewport_differences(view_layer, set(read.sources.values()))
        why = ("The scene has no camera" if scene.camera is None
               else f"The view layer '{view_layer.name}' is disabled for rendering (Use for Rendering)")
        if differ:
            read.warnings.append(f"{why}, so Blender cannot evaluate it as it renders: it was read as the viewport "
                                 "shows it, which differs for " + ", ".join(differ))
    read.scene.world = engine_world(scene.world, read.warnings)
    read.scene.ambient = np.array(scene.caustic.ambient[:], dtype=np.float64)
    if not read.scene.lights and not read.scene.emitting and read.scene.world.is_black:
        raise InputError("Nothing lights the scene: it has no light and no emitting surface, and its world is black")
    if not read.scene.receivers:
        raise InputError("No object receives caustics: give a mesh a diffuse material or set its "
                         "Caustics role to Receiver")
    return read


def read_for_bake(context, depsgraph=None, meshes=None) -> SceneRead:
    """The scene to bake (as `depsgraph` evaluates it, if given, with the
    meshes kept in `meshes`: export.read_scene); InputError if nothing in it
    casts caustics."""
    read = read_scene(context, with_camera=False, depsgraph=depsgraph, meshes=meshes)
    if not read.scene.casters:
        raise InputError("Nothing to bake: no object is transparent or a reflector")
    return read


def _name(source: str, parent: Optional[str], number: int) -> str:
    """The engine name of the depsgraph's object instance `number` of object
    `source`, placed by instancer `parent` (None: the object itself)."""
    return source if parent is None else f"{source} [{parent} #{number}]"


def _read_objects(scene, depsgraph, with_camera: bool, renderable: Optional[set[str]] = None,
                  meshes: Optional[dict] = None) -> SceneRead:
    """The camera, lamps and meshes of `depsgraph`; with `renderable`, only
    the objects it names (and instances of them). An instancer's instances
    of one mesh are read once and placed under all their matrices at once:
    one engine object per material, named "Object [Instancer]" (Object.copies;
    "... #n" where one instancer places several meshes), or one per
    instance, "Object [Instancer #n]", where it is textured or a receiver
    (meshes.MeshSource.one_by_one)."""
    camera = read_camera(scene, depsgraph) if with_camera else dummy_camera()
    warnings = camera_warnings(scene) if with_camera else []
    read = SceneRead(Scene(objects=[], lights=[], camera=camera), warnings)
    surfaces: dict[Optional[str], Surface] = {}
    sources: dict[tuple, tuple[Optional[MeshSource], Visibility]] = {}
    batches: dict[tuple, list[np.ndarray]] = {}

    def add(objects, source_name: str, instanced: bool) -> None:
        for obj, material in objects:
            read.scene.objects.append(obj)
            read.sources[obj.name], read.materials[obj.name] = source_name, material
            if instanced:
                read.instanced.add(obj.name)

    for number, inst in enumerate(depsgraph.object_instances):
        ob = inst.object
        source = ob.original
        parent = inst.parent.original.name if inst.is_instance else None
        if renderable is not None and (parent or source.name) not in renderable:
            continue
        if ob.type == 'LIGHT':
            name = _name(source.name, parent, number)
            lamp = engine_light(ob, numpy_matrix(inst.matrix_world), name, warnings)
            seen = object_visibility(inst, depsgraph.view_layer)
            lamp.visibility = Visibility(camera=seen.camera, glossy=seen.glossy, transmission=seen.transmission)
            read.scene.lights.append(lamp)
            read.sources[name] = source.name
        elif ob.type in UNSUPPORTED_GEOMETRY:
            warnings.append(f"'{_name(source.name, parent, number)}': {ob.type.lower()} objects are not supported; "
                            "convert it to a mesh")
        elif ob.type != 'MESH' or source.caustic.role == 'IGNORE':
            continue
        elif parent is None:
            visibility = object_visibility(inst, depsgraph.view_layer)
            add(mesh_objects(ob, source.name, numpy_matrix(inst.matrix_world), visibility, surfaces, warnings, meshes),
                source.name, False)
        else:
            key = (parent, source.name, ob.data.as_pointer())
            if key not in sources:
                sources[key] = (read_source(ob, f"{source.name} [{parent}]", surfaces, warnings),
                                object_visibility(inst, depsgraph.view_layer))
            mesh, visibility = sources[key]
            if mesh is not None and mesh.one_by_one:
                add(place(mesh, _name(source.name, parent, number), numpy_matrix(inst.matrix_world)[None], visibility,
                          surfaces, warnings),
                    source.name, True)
            elif mesh is not None:
                batches.setdefault(key, []).append(numpy_matrix(inst.matrix_world))
    shared = collections.Counter(sources[key][0].name for key in batches)
    numbered: collections.Counter = collections.Counter()
    for key, matrices in batches.items():
        mesh, visibility = sources[key]
        numbered[mesh.name] += 1
        name = mesh.name if shared[mesh.name] == 1 else f"{mesh.name} #{numbered[mesh.name]}"
        add(place(mesh, name, np.stack(matrices), visibility, surfaces, warnings), mesh.original.name, True)
    return read
