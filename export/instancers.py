"""Geometry Nodes' instances read in bulk from each instancer's evaluated
geometry (`Object.evaluated_geometry`, Blender 4.5 on): its instances'
transforms and what each places, read with foreach_get, where the
depsgraph's object instances would cost a Python step per instance.

Only depsgraphs whose every instancer is read so take this way; the rest
(Blender 4.2, particles, Instancing Verts, Faces or Collection, instances
of collections, lamps or other geometry, instances within instances other
than an Object Info node's "As Instance") are walked one by one
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
    Instance"). `rows (k,)` are the instances' places among the instancer's
    (in the depsgraph's order), `matrices (k,4,4)` their world transforms."""

    ob: Optional[bpy.types.Object]
    geometry: Optional[bpy.types.GeometrySet]
    rows: np.ndarray
    matrices: np.ndarray

    @property
    def mesh(self) -> bpy.types.Mesh:
        """The object's mesh, or the geometry's (which lives as long as the geometry's Python object)."""
        return self.ob.data if self.ob is not None else self.geometry.mesh


@dataclass
class Instancer:
    """An instancer's instances: `count` of them, one depsgraph object instance each."""

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
    has `instances`; None where one of them places what only the walk reads."""
    world = numpy_matrix(ob.matrix_world) @ _transforms(instances)
    index = _reference_index(instances)
    references = []
    for number, reference in enumerate(geometry.instance_references()):
        rows = np.flatnonzero(index == number)
        if not len(rows):
            continue
        if not isinstance(reference, bpy.types.GeometrySet) or _other_components(reference):
            return None
        inner = reference.instances_pointcloud()
        if inner is None:
            if reference.mesh is not None:
                references.append(Reference(None, reference, rows, world[rows]))
            continue
        # an Object Info node's "As Instance": one instance of one object
        placed = reference.instance_references()
        if reference.mesh is not None or len(inner.points) != 1 or len(placed) != 1:
            return None
        target = placed[0]
        if not isinstance(target, bpy.types.Object) or target.type != 'MESH':
            return None
        target = target.evaluated_get(depsgraph)
        if target.is_instancer or _makes_instances(target):
            return None
        references.append(Reference(target, None, rows, world[rows] @ _transforms(inner)[0]))
    return Instancer(len(index), references)


def _makes_instances(ob) -> bool:
    """Whether evaluated object `ob`'s own Geometry Nodes make instances."""
    return (any(modifier.type == 'NODES' for modifier in ob.modifiers)
            and ob.evaluated_geometry().instances_pointcloud() is not None)
