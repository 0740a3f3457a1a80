"""Geometry Nodes' instances read in bulk from each instancer's evaluated
geometry (`Object.evaluated_geometry`, Blender 4.5 on): its instances'
transforms and what each places, read with foreach_get, where the
depsgraph's object instances would cost a Python step per instance.

Only depsgraphs whose every instancer is read so take this way; the rest
(Blender 4.2, particles, Instancing Verts, Faces or Collection, instances
of lamps or other geometry, instances within instances other than an
Object Info or Collection Info node's) are walked one by one
(scene._read_objects)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import bpy
import numpy as np

from .matrices import numpy_matrix

BULK = hasattr(bpy.types.Object, "evaluated_geometry")


@dataclass
class Reference:
    """What some of an instancer's instances place: the mesh of `geometry`,
    which is no object of its own (an Ico Sphere node's, an Object Info
    node's), or evaluated mesh object `ob` (an Object Info node's "As
    Instance", an object of a Collection Info node's collection).
    `numbers (k,)` are their places among the object instances the
    depsgraph's walk yields for the instancer, `matrices (k,4,4)` their
    world transforms."""

    ob: Optional[bpy.types.Object]
    geometry: Optional[bpy.types.GeometrySet]
    numbers: np.ndarray
    matrices: np.ndarray

    @property
    def mesh(self) -> bpy.types.Mesh:
        """The object's mesh, or the geometry's (which lives as long as the geometry's Python object)."""
        return self.ob.data if self.ob is not None else self.geometry.mesh


@dataclass
class Instancer:
    """An instancer's instances: `count` object instances of the depsgraph's walk."""

    count: int
    references: list[Reference]


def read_instancers(depsgraph) -> Optional[dict[str, Instancer]]:
    """{evaluated object's name: its Instancer} for the objects of
    `depsgraph` whose Geometry Nodes make instances, or None where they
    cannot all be read in bulk (the module's docstring)."""
    if not BULK:
        return None
    found = {}
    for ob in depsgraph.objects:
        if ob.is_instancer:
            return None  # particles or Instancing: instances Geometry Nodes did not make
        if not any(modifier.type == 'NODES' for modifier in ob.modifiers):
            continue
        geometry = ob.evaluated_geometry()
        instances = geometry.instances_pointcloud()
        if (instances is not None and ob.type != 'MESH') or (ob.type == 'MESH' and _other_components(geometry)):
            return None  # the walk yields them as instances of their own
        if instances is None:
            continue
        instancer = _instancer(depsgraph, ob, geometry, instances)
        if instancer is None:
            return None
        found[ob.name] = instancer
    return found


def _other_components(geometry) -> bool:
    """Whether a mesh object's evaluated `geometry` holds what the walk yields as instances of their own:
    curves, points, volumes."""
    return any(getattr(geometry, kind, None) is not None for kind in ("curves", "pointcloud", "volume",
                                                                       "grease_pencil"))


def _transforms(instances) -> np.ndarray:
    """(k,4,4) the instances' transforms, from their point cloud's instance_transform (column-major float32)."""
    flat = np.empty(len(instances.points) * 16, dtype=np.float32)
    instances.attributes['instance_transform'].data.foreach_get('value', flat)
    return flat.reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)


def _reference_index(instances) -> np.ndarray:
    index = np.empty(len(instances.points), dtype=np.int32)
    instances.attributes['.reference_index'].data.foreach_get('value', index)
    return index


def _instancer(depsgraph, ob, geometry, instances) -> Optional[Instancer]:
    """The Instancer of evaluated object `ob`, whose evaluated `geometry`
    has `instances`; None where one of them places what only the walk reads.
    The walk yields each instance's objects in turn (a collection's all),
    which numbers them."""
    world = numpy_matrix(ob.matrix_world) @ _transforms(instances)
    index = _reference_index(instances)
    entries = np.zeros(len(index), dtype=np.int64)
    placed = []
    for number, reference in enumerate(geometry.instance_references()):
        rows = np.flatnonzero(index == number)
        if not len(rows):
            continue
        members = _members(depsgraph, reference)
        if members is None:
            return None
        entries[rows] = len(members)
        placed += [(member, rows, k) for k, member in enumerate(members) if member is not None]
    first = np.cumsum(entries) - entries
    references = [Reference(target, mesh_of, first[rows] + k, world[rows] @ inner)
                  for (target, mesh_of, inner), rows, k in placed]
    return Instancer(int(entries.sum()), references)


def _members(depsgraph, reference) -> Optional[list]:
    """What one instance of `reference` places, in the walk's order: for
    each of its objects (evaluated object or None, geometry whose mesh it is
    or None, (4,4) transform within the instance), or None for an empty,
    which the walk yields and the render skips. None where only the walk
    reads it."""
    if isinstance(reference, bpy.types.Collection):
        return _collection_members(depsgraph, reference, np.eye(4))
    if not isinstance(reference, bpy.types.GeometrySet) or _other_components(reference):
        return None
    inner = reference.instances_pointcloud()
    if inner is None:
        return [] if reference.mesh is None else [(None, reference, np.eye(4))]
    # an Object Info node's "As Instance", a Collection Info node's: one instance of an object or collection
    targets = reference.instance_references()
    if reference.mesh is not None or len(inner.points) != 1 or len(targets) != 1:
        return None
    within = _transforms(inner)[0]
    if isinstance(targets[0], bpy.types.Collection):
        return _collection_members(depsgraph, targets[0], within)
    target = _mesh_object(depsgraph, targets[0])
    return None if target is None else [(target, None, within)]


def _collection_members(depsgraph, collection, within: np.ndarray) -> Optional[list]:
    """_members of an instance of `collection` under `within (4,4)`: each
    object the depsgraph's mode shows, in the collection's order, its
    matrix less the collection's Instance Offset (Blender's collection
    instances, make_duplis_collection)."""
    shown = _shown(collection, 'hide_render' if depsgraph.mode == 'RENDER' else 'hide_viewport')
    offset = np.eye(4)
    offset[:3, 3] = -np.array(collection.instance_offset[:], dtype=np.float64)
    members = []
    for source in collection.all_objects:
        if source.name not in shown:
            continue
        if source.type == 'EMPTY' and source.instance_type == 'NONE':
            members.append(None)
            continue
        target = _mesh_object(depsgraph, source)
        if target is None:
            return None
        members.append((target, None, within @ offset @ numpy_matrix(target.matrix_world)))
    return members


def _shown(collection, hidden: str) -> set[str]:
    """The names of the objects of `collection` and its children that
    neither they nor a collection they are in hide by the flag `hidden`."""
    if getattr(collection, hidden):
        return set()
    names = {o.name for o in collection.objects if not getattr(o, hidden)}
    for child in collection.children:
        names |= _shown(child, hidden)
    return names


def _mesh_object(depsgraph, ob) -> Optional[bpy.types.Object]:
    """Object `ob` evaluated, if it is a mesh that instances nothing itself; else None."""
    if ob.type != 'MESH':
        return None
    ob = ob.evaluated_get(depsgraph)
    if ob.is_instancer or _makes_instances(ob):
        return None
    return ob


def _makes_instances(ob) -> bool:
    """Whether evaluated object `ob`'s own Geometry Nodes make instances."""
    return (any(modifier.type == 'NODES' for modifier in ob.modifiers)
            and ob.evaluated_geometry().instances_pointcloud() is not None)
