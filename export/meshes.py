"""Blender's evaluated meshes as the engine's objects in world space:
triangles, corner normals and UVs read with foreach_get, the objects the view
layer renders, and the one material each object is rendered with."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Optional

import numpy as np

from ..caustic_addon import Mesh, Object
from .materials import engine_material, read_surface
from .textures import ObjectFrame, bind


def renderable_objects(view_layer) -> set[str]:
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


def _local_mesh(mesh) -> tuple[Optional[Mesh], np.ndarray, dict[str, np.ndarray]]:
    """(Mesh in object space or None if it has no faces, material_index (nt,),
    UV map name -> (nt,3,2) corner coordinates, "" the active map)."""
    tris = mesh.loop_triangles
    nt = len(tris)
    if nt == 0:
        return None, np.zeros(0, dtype=np.int32), {}
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
    uv_maps = {}
    for layer in mesh.uv_layers:
        uvs = np.empty(len(mesh.loops) * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uvs)
        uv_maps[layer.name] = uvs.reshape(-1, 2)[tri_loops].astype(np.float64)
    if mesh.uv_layers.active is not None:
        uv_maps[""] = uv_maps[mesh.uv_layers.active.name]
    return (Mesh(co.reshape(-1, 3), tri_vertices.reshape(nt, 3), corner_normals.reshape(-1, 3)[tri_loops],
                 uv_maps.get("")), material_index, uv_maps)


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


def mesh_object(ob, name: str, matrix: np.ndarray, surfaces: dict, warnings: list[str]):
    """(engine Object in world space or None if the mesh has no faces, name of its material or None).
    `surfaces` holds each material's reading, so that a material shared by
    several objects is read, and warned about, once."""
    with evaluated_mesh(ob) as mesh:
        local, material_index, uv_maps = _local_mesh(mesh)
        material = _main_material(ob, material_index, name, warnings) if local is not None else None
    if local is None:
        return None, None
    key = material.original.name if material is not None else None
    if key not in surfaces:
        surfaces[key] = read_surface(material)
        warnings += surfaces[key].warnings
    texture = None
    if surfaces[key].texture is not None:
        data = ob.original.data
        if np.linalg.det(matrix[:3, :3]) < 0:
            # a mirroring matrix turns the engine's triangles around (Mesh.transformed)
            uv_maps = {layer: corners[:, ::-1] for layer, corners in uv_maps.items()}
        frame = ObjectFrame(uv_maps, np.linalg.inv(matrix), np.array(data.texspace_location[:], dtype=np.float64),
                            np.array(data.texspace_size[:], dtype=np.float64))
        texture = bind(surfaces[key].texture, frame, f"'{name}'", warnings)
    if np.any(surfaces[key].emission > 0.0):
        warnings.append(f"'{name}': its material '{key}' emits light; the caustic render shows it but lights "
                        "nothing with it and casts no caustics from it yet (a lamp in its place would)")
    return Object(name, local.transformed(matrix), engine_material(surfaces[key], ob.original.caustic, texture)), key
