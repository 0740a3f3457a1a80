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
from .instancers import Instancer, Reference, read_instancers
from .meshes import MeshSource, mesh_objects, object_visibility, place, read_reference, read_source
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
    (meshes.MeshSource.one_by_one). Geometry Nodes' instances are read in
    bulk where they can be (instancers.py), else the depsgraph's object
    instances are walked one by one; n counts them in the walk's order."""
    camera = read_camera(scene, depsgraph) if with_camera else dummy_camera()
    warnings = camera_warnings(scene) if with_camera else []
    reader = _Reader(SceneRead(Scene(objects=[], lights=[], camera=camera), warnings), depsgraph.view_layer,
                     renderable, meshes)
    instancers = read_instancers(depsgraph)
    if instancers is None:
        reader.walk(depsgraph)
    else:
        reader.bulk(depsgraph, instancers)
    reader.place_batches()
    return reader.read


class _Reader:
    """_read_objects' reading: `read` what it has read so far, `surfaces`
    each material's reading, `sources` each instanced mesh's (by instancer,
    object and mesh: the MeshSource or None, and its Visibility), `batches`
    the matrices (k,4,4) of the instances of each that are placed together."""

    def __init__(self, read: SceneRead, view_layer, renderable: Optional[set[str]], meshes: Optional[dict]):
        self.read, self.view_layer, self.renderable, self.meshes = read, view_layer, renderable, meshes
        self.surfaces: dict[Optional[str], Surface] = {}
        self.sources: dict[tuple, tuple[Optional[MeshSource], Visibility]] = {}
        self.batches: dict[tuple, list[np.ndarray]] = {}

    def walk(self, depsgraph) -> None:
        """Every object instance of `depsgraph`, one by one."""
        warnings = self.read.warnings
        for number, inst in enumerate(depsgraph.object_instances):
            ob = inst.object
            if not inst.is_instance:
                self.object(ob, lambda: numpy_matrix(inst.matrix_world))
                continue
            source, parent = ob.original, inst.parent
            holder = parent.original.name
            if self.renderable is not None and holder not in self.renderable:
                continue
            if ob.type == 'LIGHT':
                self.lamp(ob, parent, _name(source.name, holder, number), numpy_matrix(inst.matrix_world))
            elif ob.type in UNSUPPORTED_GEOMETRY:
                warnings.append(f"'{_name(source.name, holder, number)}': {ob.type.lower()} objects are not "
                                "supported; convert it to a mesh")
            elif ob.type == 'MESH' and source.caustic.role != 'IGNORE':
                name = f"{source.name} [{holder}]"
                self.instances((holder, source.name, ob.data.as_pointer()), np.array([number]),
                               numpy_matrix(inst.matrix_world)[None],
                               lambda: (read_source(ob, name, self.surfaces, warnings),
                                        object_visibility(ob, parent, self.view_layer)))

    def bulk(self, depsgraph, instancers: dict[str, Instancer]) -> None:
        """The objects of `depsgraph`, and the `instancers` of those whose
        Geometry Nodes make instances (instancers.read_instancers)."""
        number = 0
        for ob in depsgraph.objects:
            self.object(ob, lambda: numpy_matrix(ob.matrix_world))
            instancer = instancers.get(ob.name)
            if instancer is not None and (self.renderable is None or ob.original.name in self.renderable):
                for ref in instancer.references:
                    self._reference(ob, ref, number + 1 + ref.numbers)
            number += 1 + (instancer.count if instancer is not None else 0)

    def _reference(self, holder, ref: Reference, numbers: np.ndarray) -> None:
        """The instances `ref` of evaluated object `holder`, the walk's `numbers (k,)`."""
        source = ref.ob.original if ref.ob is not None else holder.original
        if source.caustic.role == 'IGNORE':
            return
        name = f"{source.name} [{holder.original.name}]"

        def read_mesh():
            mesh = (read_source(ref.ob, name, self.surfaces, self.read.warnings) if ref.ob is not None
                    else read_reference(holder, ref.mesh, name, self.surfaces, self.read.warnings))
            return mesh, object_visibility(ref.ob or holder, holder, self.view_layer)

        self.instances((holder.original.name, source.name, ref.mesh.as_pointer()), numbers, ref.matrices, read_mesh)

    def object(self, ob, matrix_of) -> None:
        """Evaluated object `ob`, which no instancer places, at `matrix_of()`."""
        source = ob.original
        if self.renderable is not None and source.name not in self.renderable:
            return
        if ob.type == 'LIGHT':
            self.lamp(ob, None, source.name, matrix_of())
        elif ob.type in UNSUPPORTED_GEOMETRY:
            self.read.warnings.append(f"'{source.name}': {ob.type.lower()} objects are not supported; convert it "
                                      "to a mesh")
        elif ob.type == 'MESH' and source.caustic.role != 'IGNORE':
            self._add(mesh_objects(ob, source.name, matrix_of(), object_visibility(ob, None, self.view_layer),
                                   self.surfaces, self.read.warnings, self.meshes),
                      source.name, False)

    def lamp(self, ob, parent, name: str, matrix: np.ndarray) -> None:
        """Evaluated lamp object `ob`, placed by `parent` (None: itself), named `name`, at `matrix (4,4)`."""
        lamp = engine_light(ob, matrix, name, self.read.warnings)
        seen = object_visibility(ob, parent, self.view_layer)
        lamp.visibility = Visibility(camera=seen.camera, glossy=seen.glossy, transmission=seen.transmission)
        self.read.scene.lights.append(lamp)
        self.read.sources[name] = ob.original.name

    def instances(self, key: tuple, numbers: np.ndarray, matrices: np.ndarray, read_mesh) -> None:
        """Instances of one mesh at `matrices (k,4,4)`, the walk's
        `numbers (k,)`: `key` (instancer, object, mesh) names the mesh, read
        by `read_mesh()` -> (MeshSource or None, Visibility) the first time
        it is met."""
        if key not in self.sources:
            self.sources[key] = read_mesh()
        mesh, visibility = self.sources[key]
        if mesh is None:
            return
        if not mesh.one_by_one:
            self.batches.setdefault(key, []).append(matrices)
            return
        parent, source_name, _ = key
        for number, matrix in zip(numbers.tolist(), matrices):
            self._add(place(mesh, _name(source_name, parent, number), matrix[None], visibility, self.surfaces,
                            self.read.warnings),
                      source_name, True)

    def place_batches(self) -> None:
        """Each mesh's batched instances as one object per material."""
        shared = collections.Counter(self.sources[key][0].name for key in self.batches)
        numbered: collections.Counter = collections.Counter()
        for key, matrices in self.batches.items():
            mesh, visibility = self.sources[key]
            numbered[mesh.name] += 1
            name = mesh.name if shared[mesh.name] == 1 else f"{mesh.name} #{numbered[mesh.name]}"
            self._add(place(mesh, name, np.concatenate(matrices), visibility, self.surfaces, self.read.warnings),
                      mesh.original.name, True)

    def _add(self, objects, source_name: str, instanced: bool) -> None:
        for obj, material in objects:
            self.read.scene.objects.append(obj)
            self.read.sources[obj.name], self.read.materials[obj.name] = source_name, material
            if instanced:
                self.read.instanced.add(obj.name)
