"""Blender's evaluated meshes as the engine's objects in world space:
triangles, corner normals and UVs read with foreach_get, one engine object
for each material the triangles use, and how the object is seen (its ray
visibility and holdout, as Cycles reads them)."""

from __future__ import annotations

from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import Dielectric, Diffuse, Mesh, Object, Reflector, Visibility
from ..caustic_addon.scene.geometry import with_area
from .materials import abbe_conflict, engine_material, read_surface
from .textures import ObjectFrame, bind

# Faces of an empty slot: Cycles renders them with its default surface, a
# grey Diffuse BSDF (0.8) in Blender 4.2 and 4.5 and a grey Principled BSDF
# (0.8, Roughness 0.5) in 5.x (both rendered to check); read_surface(None)
# gives the same.
EMPTY_SLOT = ("its faces are rendered as Cycles renders them, with its default grey "
              + ("diffuse surface" if bpy.app.version < (5, 0, 0) else "Principled BSDF"))


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


def _material_parts(slots: list, material_index: np.ndarray, name: str, warnings: list[str]) -> list:
    """[(material or None, triangle rows (k,) in mesh order, slot numbers
    from 1)]: the triangles by the material of their slot in `slots` (a
    material or None each), a slot index past the last slot taking the last
    one, as Cycles does. Slots holding the same material are one part. A
    warning names each empty slot that faces use (EMPTY_SLOT: what the
    engine and Cycles render there)."""
    if not slots:
        return [(None, np.arange(len(material_index)), [])]
    slot_of = np.clip(material_index, 0, len(slots) - 1)
    parts: dict = {}
    for slot in np.flatnonzero(np.bincount(slot_of, minlength=len(slots))).tolist():
        material = slots[slot]
        if material is None:
            warnings.append(f"'{name}': material slot {slot + 1} is empty; {EMPTY_SLOT}")
        key = None if material is None else material.original.name
        _, numbers = parts.get(key, (None, []))
        parts[key] = (material, numbers + [slot])
    return [(material, np.arange(len(slot_of)) if len(parts) == 1 else np.flatnonzero(np.isin(slot_of, numbers)),
             [n + 1 for n in numbers]) for material, numbers in parts.values()]


def flattened(matrix: np.ndarray, vertices: np.ndarray) -> bool:
    """True if the object matrix `matrix (4,4)` scales the mesh of object
    space `vertices (n,3)` to 0 along an axis it has depth along (a plane
    scaled to 0 across itself is not flattened)."""
    _, scales, axes = np.linalg.svd(matrix[:3, :3])
    null = axes[scales <= 1e-12 * max(float(scales.max()), 1e-300)]
    if not len(null) or not len(vertices):
        return False
    extent = float(np.ptp(vertices, axis=0).max())
    return float(np.ptp(vertices @ null.T, axis=0).max()) > 1e-9 * extent


def _surface(material, surfaces: dict, warnings: list[str]):
    """The reading of `material` (or None), read and warned about once."""
    key = material.original.name if material is not None else None
    if key not in surfaces:
        surfaces[key] = read_surface(material)
        warnings += surfaces[key].warnings
    return surfaces[key]


def _warn_faceless(original, slots: list, name: str, surfaces: dict, warnings: list[str]) -> None:
    """A warning for a mesh with no faces that would be a glass, a mirror
    or a receiver it was made to be, by its first slot's material (`slots`),
    with the settings of object `original`."""
    material = next(iter(slots), None)
    engine = engine_material(_surface(material, surfaces, warnings), original.caustic)
    if isinstance(engine, (Dielectric, Reflector)):
        warnings.append(f"'{name}' has no faces, so it casts no caustics: it was left out")
    elif original.caustic.role == 'RECEIVER':
        warnings.append(f"'{name}' has no faces, so it receives no caustics: it was left out")


def object_visibility(ob, parent, view_layer) -> Visibility:
    """The rays that see evaluated object `ob`, placed by instancer
    `parent` (None: itself), as Cycles reads them
    (intern/cycles/blender/object.cpp): the object's ray visibility, and its
    instancer's too; holdout (the object's or its collection's) and Indirect
    Only (its collection's, which hides it from camera rays) from the
    instancer, if any, in `view_layer`."""
    owners = [ob] + ([parent] if parent is not None else [])
    holder = (parent if parent is not None else ob).original
    holdout = holder.holdout_get(view_layer=view_layer)
    indirect_only = not holdout and holder.indirect_only_get(view_layer=view_layer)

    def seen(flag: str) -> bool:
        return all(getattr(owner, flag) for owner in owners)

    return Visibility(camera=seen("visible_camera") and not indirect_only, glossy=seen("visible_glossy"),
                      transmission=seen("visible_transmission"), shadow=seen("visible_shadow"), holdout=holdout)


@dataclass
class MeshSource:
    """An evaluated mesh object as read once, to be placed once or many
    times (`place`): its mesh in object space, its triangles' materials and
    UV maps, and its parts, one per material (_material_parts: (material
    name or None, triangle rows, slot numbers)), whose readings are in the
    `surfaces` it was read with. `one_by_one`: its copies are objects of
    their own, as a texture reads object coordinates per object and a
    receiver's map is laid out per object."""

    name: str
    original: bpy.types.Object
    local: Mesh
    material_index: np.ndarray
    uv_maps: dict[str, np.ndarray]
    parts: list[tuple[Optional[str], np.ndarray, list[int]]]
    one_by_one: bool
    visible_diffuse: bool


def read_source(ob, name: str, surfaces: dict, warnings: list[str],
                meshes: Optional[dict] = None) -> Optional[MeshSource]:
    """The MeshSource of evaluated mesh object `ob`, named `name` in
    warnings; None, with a warning, if it has no faces. `surfaces` holds
    each material's reading, so that a material shared by several objects
    is read, and warned about, once. `meshes` keeps each object's mesh in
    object space by `name` between reads, for a caller that drops those that
    changed (Live): a mesh found there, of the same object, is not read again."""
    uid = ob.original.session_uid
    kept = meshes.get(name) if meshes is not None else None
    slots = [slot.material for slot in ob.material_slots]
    with evaluated_mesh(ob) if kept is None or kept[0] != uid else nullcontext() as mesh:
        local, material_index, uv_maps = _local_mesh(mesh) if mesh is not None else kept[1:]
        if meshes is not None:
            meshes[name] = (uid, local, material_index, uv_maps)
    return _source(name, ob.original, slots, ob.visible_diffuse, local, material_index, uv_maps, surfaces, warnings)


def read_reference(holder, mesh, name: str, surfaces: dict, warnings: list[str]) -> Optional[MeshSource]:
    """read_source of a mesh that Geometry Nodes on evaluated object
    `holder` instance, that is no object of its own (an Ico Sphere node's,
    an Object Info node's geometry), as Blender's depsgraph makes it an
    object: the holder's settings and ray visibility, the mesh's materials."""
    return _source(name, holder.original, list(mesh.materials), holder.visible_diffuse, *_local_mesh(mesh),
                   surfaces, warnings)


def _source(name: str, original, slots: list, visible_diffuse: bool, local: Optional[Mesh],
            material_index: np.ndarray, uv_maps: dict, surfaces: dict, warnings: list[str]) -> Optional[MeshSource]:
    """The MeshSource of mesh `local` (None: it has no faces, which a
    warning names) with object `original`'s settings and the materials in
    `slots`."""
    if local is None:
        _warn_faceless(original, slots, name, surfaces, warnings)
        return None
    parts = _material_parts(slots, material_index, name, warnings)
    named = []
    for material, rows, slots in parts:
        _surface(material, surfaces, warnings)
        named.append((material.original.name if material is not None else None, rows, slots))
    engines = [engine_material(surfaces[key], original.caustic) for key, _, _ in named]
    one_by_one = (any(surfaces[key].texture is not None for key, _, _ in named)
                  or any(isinstance(engine, Diffuse) and engine.receiver for engine in engines))
    return MeshSource(name, original, local, material_index, uv_maps, named, one_by_one, visible_diffuse)


def mesh_objects(ob, name: str, matrix: np.ndarray, visibility: Visibility, surfaces: dict,
                 warnings: list[str], meshes: Optional[dict] = None) -> list[tuple[Object, Optional[str]]]:
    """The engine objects of evaluated mesh object `ob` in world space,
    under `matrix (4,4)` (read_source, then place)."""
    source = read_source(ob, name, surfaces, warnings, meshes)
    return [] if source is None else place(source, name, matrix[None], visibility, surfaces, warnings)


def place(source: MeshSource, name: str, matrices: np.ndarray, visibility: Visibility, surfaces: dict,
          warnings: list[str]) -> list[tuple[Object, Optional[str]]]:
    """[(engine Object in world space, name of its material or None)] of
    `source` under `matrices (k,4,4)`: one for each material its triangles
    use, named `name` if there is one and "name [material]" if there are
    several, which are then parts of one body. Each part's mesh is placed
    once under each matrix, as one object (Mesh.instanced; Object.copies),
    but for a single object that is `one_by_one` or flattened, placed in
    world space: an instanced object that only moves keeps its mesh's BVH
    between renders (tracing/prototypes.py).

    A glass or mirror scaled to 0 along an axis, and an object scaled to
    nothing, are left out with a warning that names them; faces an
    object's scale flattens to no area are dropped, and so are instances
    scaled to 0 along an axis."""
    local, material_index, uv_maps, parts = source.local, source.material_index, source.uv_maps, source.parts
    if len(matrices) > 1:
        singular = np.linalg.det(matrices[:, :3, :3]) == 0.0
        if np.any(singular):
            warnings.append(f"'{name}': {int(singular.sum()):,} of its {len(matrices):,} instances are scaled to 0 "
                            "along an axis: they were left out")
            matrices = matrices[~singular]
        if len(matrices) == 0:
            return []
    matrix = matrices[0]
    if len(matrices) == 1 and np.linalg.det(matrix[:3, :3]) == 0.0:
        # Mesh.transformed drops them too; the triangles' materials and UVs must follow
        kept = np.flatnonzero(with_area(local.transformed(matrix).vertices, local.triangles))
        if len(kept) == 0:
            warnings.append(f"'{name}' is scaled to 0, so none of its faces has any area: it was left out")
            return []
        local, material_index = local.subset(kept), material_index[kept]
        uv_maps = {layer: corners[kept] for layer, corners in uv_maps.items()}
        parts = [(key, np.searchsorted(kept, np.intersect1d(rows, kept)), slots) for key, rows, slots in parts]
        parts = [part for part in parts if len(part[1])]
    instanced = len(matrices) > 1 or not (source.one_by_one or np.linalg.det(matrix[:3, :3]) == 0.0)
    world = None if instanced else local.transformed(matrix)
    engines = {key: engine_material(surfaces[key], source.original.caustic) for key, _, _ in parts}
    if flattened(matrix, local.vertices) and len(matrices) == 1:
        if any(isinstance(engine, Dielectric) for engine in engines.values()):
            warnings.append(f"'{name}' is scaled to 0 along an axis: glass with no thickness bends no light, "
                            "so it was left out")
            return []
        warnings.append(f"'{name}' is scaled to 0 along an axis: it is rendered flat")
    if np.linalg.det(matrix[:3, :3]) < 0:
        # a mirroring matrix turns the engine's triangles around (Mesh.transformed)
        uv_maps = {layer: corners[:, ::-1] for layer, corners in uv_maps.items()}
    several = len(parts) > 1
    objects = []
    for key, rows, slots in parts:
        if surfaces[key].black is not None:
            warnings.append(f"'{name}': material '{key}' (slot {', '.join(map(str, slots))}) {surfaces[key].black}; "
                            "Cycles renders its faces black, and so does the caustic render")
        part = f"{name} [{key if key is not None else 'no material'}]" if several else name
        engine = engines[key]
        if surfaces[key].texture is not None:
            data = source.original.data
            frame = ObjectFrame({layer: np.take(corners, rows, axis=0) for layer, corners in uv_maps.items()},
                                np.linalg.pinv(matrix), np.array(data.texspace_location[:], dtype=np.float64),
                                np.array(data.texspace_size[:], dtype=np.float64), source.original)
            engine = engine_material(surfaces[key], source.original.caustic,
                                     bind(surfaces[key].texture, frame, f"'{part}'", warnings))
        conflict = abbe_conflict(surfaces[key], source.original.caustic, name, key)
        if conflict is not None and isinstance(engine, Dielectric):
            warnings.append(conflict)
        body = name if several else None
        if world is not None:
            obj = Object(part, world.subset(rows) if several else world, engine, visibility, body)
        else:
            mesh = local.subset(rows) if several else local
            # no part receives (MeshSource.one_by_one): no map is laid out on a UV map
            obj = Object.instanced(part, Mesh(mesh.vertices, mesh.triangles, mesh.corner_normals), matrices, engine,
                                   visibility, body)
        objects.append((obj, key))
    if not source.visible_diffuse and any(obj.is_caster for obj, _ in objects):
        warnings.append(f"'{name}': its Diffuse ray visibility is off, which hides it from Cycles' diffuse "
                        "bounces and the caustics they find through it; the caustic render's light goes from the "
                        "lights, so it still casts its caustic")
    return objects
