"""Blender's evaluated scene (modifiers applied, instances expanded) copied
into the engine's numpy Scene, in world space. It runs on the main thread;
what it returns holds no bpy data, so the engine can run on a worker thread."""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import Camera, Mesh, Object, PointLight, Scene, SpotLight, SunLight
from .errors import InputError
from .materials import Surface, engine_material, read_surface

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


def render_size(render) -> tuple[int, int]:
    """(pixx, pixy): the render resolution scaled by its percentage, as Blender computes it."""
    return (render.resolution_x * render.resolution_percentage // 100,
            render.resolution_y * render.resolution_percentage // 100)


def _matrix(matrix) -> np.ndarray:
    """(4,4) float64 of a mathutils Matrix."""
    return np.array(matrix, dtype=np.float64).reshape(4, 4)


def read_camera(scene, depsgraph) -> Camera:
    """The active camera at the render resolution."""
    if scene.camera is None:
        raise InputError("The scene has no active camera")
    camera = scene.camera.evaluated_get(depsgraph)
    data = camera.data
    if data.type not in ('PERSP', 'ORTHO'):
        raise InputError(f"'{scene.camera.name}' is a panoramic camera; only perspective and orthographic "
                         "cameras are supported")
    matrix = _matrix(camera.matrix_world)
    matrix[:3, :3] /= np.linalg.norm(matrix[:3, :3], axis=0)
    pixx, pixy = render_size(scene.render)
    return Camera(matrix=matrix, pixx=pixx, pixy=pixy, kind=data.type, fov=data.angle, ortho_scale=data.ortho_scale,
                  sensor_fit=data.sensor_fit, shift_x=data.shift_x, shift_y=data.shift_y,
                  clip_start=data.clip_start, clip_end=data.clip_end)


def _camera_warnings(scene) -> list[str]:
    warnings = []
    if scene.render.pixel_aspect_x != scene.render.pixel_aspect_y:
        warnings.append("non-square pixels (Pixel Aspect) are rendered square")
    if scene.camera is not None and scene.camera.type == 'CAMERA' and scene.camera.data.dof.use_dof:
        warnings.append(f"'{scene.camera.name}': depth of field is not rendered")
    return warnings


def _renderable_objects(view_layer) -> set[str]:
    """Names of the objects the view layer renders: in included collections
    not disabled for renders, and not disabled for renders themselves."""
    names, stack = set(), [view_layer.layer_collection]
    while stack:
        layer = stack.pop()
        if layer.exclude or layer.collection.hide_render:
            continue
        names.update(ob.name for ob in layer.collection.objects if not ob.hide_render)
        stack.extend(layer.children)
    return names


@contextmanager
def evaluated_mesh(ob_eval):
    """The evaluated object's mesh, freed on exit."""
    mesh = ob_eval.to_mesh()
    try:
        yield mesh
    finally:
        ob_eval.to_mesh_clear()


def _local_mesh(mesh) -> tuple[Optional[Mesh], np.ndarray]:
    """(Mesh in object space or None if it has no faces, material_index (nt,))."""
    tris = mesh.loop_triangles
    nt = len(tris)
    if nt == 0:
        return None, np.zeros(0, dtype=np.int32)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    tri_vertices = np.empty(nt * 3, dtype=np.int32)
    tris.foreach_get("vertices", tri_vertices)
    tri_loops = np.empty(nt * 3, dtype=np.int32)
    tris.foreach_get("loops", tri_loops)
    tri_loops = tri_loops.reshape(nt, 3)
    corner_normals = np.empty(len(mesh.loops) * 3, dtype=np.float32)
    mesh.corner_normals.foreach_get("vector", corner_normals)
    material_index = np.empty(nt, dtype=np.int32)
    tris.foreach_get("material_index", material_index)
    corner_uvs = None
    if mesh.uv_layers.active is not None:
        uvs = np.empty(len(mesh.loops) * 2, dtype=np.float32)
        mesh.uv_layers.active.data.foreach_get("uv", uvs)
        corner_uvs = uvs.reshape(-1, 2)[tri_loops]
    return Mesh(co.reshape(-1, 3), tri_vertices.reshape(nt, 3), corner_normals.reshape(-1, 3)[tri_loops],
                corner_uvs), material_index


def _main_material(ob_eval, material_index: np.ndarray, name: str, warnings: list[str]):
    """The material on most of the object's triangles; a warning if it has several."""
    slots = [slot.material for slot in ob_eval.material_slots]
    if not slots:
        return None
    counts = np.bincount(np.clip(material_index, 0, len(slots) - 1), minlength=len(slots))
    main = slots[int(counts.argmax())]
    if len({slots[i].name if slots[i] else None for i in np.flatnonzero(counts)}) > 1:
        warnings.append(f"'{name}' has several materials; all of it is rendered with "
                        f"'{main.name if main else 'no material'}'")
    return main


def _light(ob_eval, matrix: np.ndarray, name: str, warnings: list[str]):
    """The engine lamp for a Blender light object, or None (with a warning) if it has none."""
    light = ob_eval.data
    color = np.array(light.color[:], dtype=np.float64)
    if getattr(light, "use_temperature", False):
        color *= np.array(light.temperature_color[:], dtype=np.float64)
    power = light.energy * 2.0 ** getattr(light, "exposure", 0.0)
    position, down = matrix[:3, 3], -matrix[:3, 2]
    if light.type == 'POINT':
        return PointLight(position, power, color, name=name)
    if light.type == 'SPOT':
        return SpotLight(position, down, power, light.spot_size, light.spot_blend, color, name=name)
    if light.type == 'SUN':
        return SunLight(down, power, color, name=name)
    warnings.append(f"lamp '{name}': {light.type.lower()} lamps are not supported; it was left out")
    return None


def _background(world, warnings: list[str]) -> np.ndarray:
    """(3,) radiance the camera sees where it sees nothing: the world's plain colour."""
    if world is None:
        return np.zeros(3)
    if world.node_tree is None or not (bpy.app.version >= (5, 0, 0) or world.use_nodes):
        return np.array(world.color[:], dtype=np.float64)
    output = world.node_tree.get_output_node('CYCLES')
    link = output.inputs['Surface'].links[0] if output is not None and output.inputs['Surface'].is_linked else None
    node = link.from_node if link is not None else None
    if node is None or node.bl_idname != 'ShaderNodeBackground' or any(s.is_linked for s in node.inputs):
        warnings.append(f"world '{world.name}': only a plain Background colour is understood; "
                        "the background is black")
        return np.zeros(3)
    return np.array(node.inputs['Color'].default_value[:3], dtype=np.float64) * node.inputs['Strength'].default_value


def _dummy_camera() -> Camera:
    """A one-pixel camera, for runs that only need the photon pass."""
    return Camera(matrix=np.eye(4), pixx=1, pixy=1)


def _mesh_object(ob, name: str, matrix: np.ndarray, surfaces: dict, warnings: list[str]):
    """(engine Object in world space or None if the mesh has no faces, name of its material or None)."""
    with evaluated_mesh(ob) as mesh:
        local, material_index = _local_mesh(mesh)
        material = _main_material(ob, material_index, name, warnings) if local is not None else None
    if local is None:
        return None, None
    key = material.original.name if material is not None else None
    if key not in surfaces:
        surfaces[key] = read_surface(material)
        warnings += surfaces[key].warnings
    return Object(name, local.transformed(matrix), engine_material(surfaces[key], ob.original.caustic)), key


def read_scene(context, with_camera: bool = True) -> SceneRead:
    """The engine scene of the context's view layer. Raises InputError if it
    has no camera (when `with_camera`), no lamp or no receiver."""
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    camera = read_camera(scene, depsgraph) if with_camera else _dummy_camera()
    warnings = _camera_warnings(scene) if with_camera else []
    renderable = _renderable_objects(context.view_layer)
    read = SceneRead(Scene(objects=[], lights=[], camera=camera), warnings)
    surfaces: dict[Optional[str], Surface] = {}
    seen, skipped_lamps = set(), False
    for number, inst in enumerate(depsgraph.object_instances):
        ob = inst.object
        source = ob.original
        if (inst.parent.original if inst.is_instance else source).name not in renderable:
            continue
        seen.add(source.name)
        name = f"{source.name} [{inst.parent.original.name} #{number}]" if inst.is_instance else source.name
        matrix = _matrix(inst.matrix_world)
        if ob.type == 'LIGHT':
            light = _light(ob, matrix, name, warnings)
            skipped_lamps |= light is None
            if light is not None:
                read.scene.lights.append(light)
                read.sources[name] = source.name
        elif ob.type in UNSUPPORTED_GEOMETRY:
            warnings.append(f"'{name}': {ob.type.lower()} objects are not supported; convert it to a mesh")
        elif ob.type == 'MESH' and source.caustic.role != 'IGNORE':
            obj, material = _mesh_object(ob, name, matrix, surfaces, warnings)
            if obj is not None:
                read.scene.objects.append(obj)
                read.sources[name], read.materials[name] = source.name, material
                if inst.is_instance:
                    read.instanced.add(name)
    hidden = sorted(n for n in renderable - seen if bpy.data.objects[n].type in {'MESH', 'LIGHT'})
    warnings += [f"'{n}' is hidden in the viewport, so it was left out; unhide it to render it" for n in hidden]
    read.scene.background = _background(scene.world, warnings)
    read.scene.ambient = np.array(scene.caustic.ambient[:], dtype=np.float64)
    if not read.scene.lights:
        raise InputError("The scene has no point, spot or sun lamp" +
                         (" (area lamps are not supported)" if skipped_lamps else ""))
    if not read.scene.receivers:
        raise InputError("No object receives caustics: give a mesh a diffuse material or set its "
                         "Caustics role to Receiver")
    return read
