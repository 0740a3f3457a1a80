"""Object-space meshes kept between renders: each one's Embree scene (its
BVH) and its surface's open edges and winding, found again by a digest of
its vertices and triangles. An object that only moved since a recent
render (Live while the glass is dragged, a keyframed object in an
animation) is placed over its mesh's kept BVH by an instance transform,
and its surface is not analysed again.

The open edges and the winding hold under every placement: an invertible
affine map keeps which vertices coincide, and Mesh.instanced turns a
mirrored copy's triangles around, which keeps the sign of its volume."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..scene import Mesh
from . import embree
from .topology import open_edges, signed_volume

# The kept meshes' triangles in all: 106 bytes each in Embree's BVH and the
# mesh's float32 buffers (a 1M-triangle sphere's, measured), so at most
# about 110 MB.
CAPACITY_TRIANGLES = 1_000_000


@dataclass
class Prototype:
    """A mesh as Embree and the accelerator keep it.

    scene    the mesh's committed Embree scene, to be instanced
    holes    (k,2) the vertex pairs of its open edges (topology.open_edges)
    inward   its winding faces in: its signed volume is negative
    thin     whether a glass of it alone has a wall thinner than the
             tracing epsilon, by its placement's linear part (3,3) as
             bytes and the epsilon: a glass that only moves is as thin
             wherever it goes (Accelerator._warn_if_thin)
    """

    scene: embree.Scene
    holes: np.ndarray
    inward: bool
    thin: dict = field(default_factory=dict)


class Prototypes:
    """The prototypes of the meshes of the last renders, the least recently
    used dropped past CAPACITY_TRIANGLES. Safe to share between threads."""

    def __init__(self, capacity_triangles: int = CAPACITY_TRIANGLES):
        self.capacity = capacity_triangles
        self._kept: OrderedDict[tuple, Prototype] = OrderedDict()
        self._lock = threading.Lock()
        self.built = 0

    def of(self, mesh: Mesh, quality: str) -> Prototype:
        """The prototype of `mesh` built at BVH `quality`, kept or made now."""
        key = (_digest(mesh), quality)
        with self._lock:
            kept = self._kept.get(key)
            if kept is not None:
                self._kept.move_to_end(key)
                return kept
        holes = open_edges(mesh.triangles, mesh.vertices)
        inward = not len(holes) and signed_volume(np.take(mesh.vertices, mesh.triangles, axis=0)) < 0.0
        made = Prototype(embree.Scene([embree.Geometry(mesh.vertices, mesh.triangles)], quality), holes, inward)
        with self._lock:
            self.built += 1
            self._kept[key] = made
            while len(self._kept) > 1 and sum(len(p.scene.geometries[0].triangles)
                                               for p in self._kept.values()) > self.capacity:
                self._kept.popitem(last=False)
        return made

    def clear(self) -> None:
        with self._lock:
            self._kept.clear()


def _digest(mesh: Mesh) -> bytes:
    """A digest of the mesh's vertices and triangles, their shapes and types."""
    digest = hashlib.sha1()
    for array in (mesh.vertices, mesh.triangles):
        array = np.ascontiguousarray(array)
        digest.update(repr((array.dtype.str, array.shape)).encode())
        digest.update(array)
    return digest.digest()


PROTOTYPES = Prototypes()
