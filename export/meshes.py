"""Blender's evaluated meshes as the engine's objects in world space:
triangles, corner normals and UVs read with foreach_get, the objects the view
layer renders, and the one material each object is rendered with."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Optional

import numpy as np

from ..caustic_addon import Dielectric, Mesh, Object, Reflector
from .materials import engine_material, read_surface


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


def flattened(matrix: np.ndarray, vertices: np.ndarray) -> bool:
    """True if the object matrix `matrix (4,4)` scales the mesh of object
    space `vertices (n,3)` to 0 along an axis it has depth along (a plane
    scaled to 0 across itself is not flattened)."""
    _, scales, axes = np.linalg.svd(matrix[:3, :3])
    extent = float(np.ptp(vertices, axis=0).max(initial=0.0)) if len(vertices) else 0.0
    null = axes[scales <= 1e-12 * max(float(scales.max()), 1e-300)]
    return bool(len(null)) and float(np.ptp(vertices @ null.T, axis=0).max()) > 1e-9 * extent


def mesh_object(ob, name: str, matrix: np.ndarray, surfaces: dict, warnings: list[str]):
    """(engine Object in world space or None if it renders nothing, name of
    its material or None). `surfaces` holds each material's reading, so that
    a material shared by several objects is read, and warned about, once.
    A glass or mirror with no faces, glass scaled to 0 along an axis, and
    an object scaled to nothing are left out with a warning that names them."""
    with evaluated_mesh(ob) as mesh:
        local, material_index = _local_mesh(mesh)
        material = (_main_material(ob, material_index, name, warnings) if local is not None
                    else next((slot.material for slot in ob.material_slots), None))
    key = material.original.name if material is not None else None
    if key not in surfaces:
        surfaces[key] = read_surface(material)
        warnings += surfaces[key].warnings
    engine = engine_material(surfaces[key], ob.original.caustic)
    caster = isinstance(engine, (Dielectric, Reflector))
    if local is None:
        if caster or ob.original.caustic.role == 'RECEIVER':
            warnings.append(f"'{name}' has no faces, so it {'casts' if caster else 'receives'} no caustics: "
                            "it was left out")
        return None, None
    world = local.transformed(matrix)
    if len(world.triangles) == 0:
        warnings.append(f"'{name}' is scaled to 0, so none of its faces has any area: it was left out")
        return None, None
    if flattened(matrix, local.vertices):
        if isinstance(engine, Dielectric):
            warnings.append(f"'{name}' is scaled to 0 along an axis: glass with no thickness bends no light, "
                            "so it was left out")
            return None, None
        warnings.append(f"'{name}' is scaled to 0 along an axis: it is rendered flat")
    if np.any(surfaces[key].emission > 0.0):
        warnings.append(f"'{name}': its material '{key}' emits light; the caustic render shows it but lights "
                        "nothing with it and casts no caustics from it yet (a lamp in its place would)")
    return Object(name, world, engine), key
