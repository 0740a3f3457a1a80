"""Every batch of rays a render hands Embree, recorded, and replayed three
ways on 2 threads as the engine splits them: through embreex (what the
engine cast through before it called Embree itself: float32 copies in,
arrays of u, v, Ng, tfar, primID and geomID out); through Embree directly
as the engine calls it, with nothing around the cast (`rtcIntersect1` for
closest hits, `rtcOccluded8` for shadow rays: pure Embree time, 'direct1');
and with closest hits in packets of 8 too (`rtcIntersect8`, 'direct8').
The benchmarks' helper (passes.py, speed.py, bvh_build.py); never imported
by the engine.
"""

from __future__ import annotations

import ctypes
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass

import numba
import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh
from llvmlite import binding as llvm
from numba import types

from caustic_addon.tracing import embree
from caustic_addon.tracing.accelerator import Accelerator
from caustic_addon.tracing.embree import (PACKET, intersect1, occluded8, packet_blocked, packet_record, ray_record,
                                          set_packet_ray)

llvm.add_symbol("benchmark_rtcIntersect8", ctypes.cast(embree._lib.rtcIntersect8, ctypes.c_void_p).value)
_intersect8 = types.ExternalFunction("benchmark_rtcIntersect8",
                                     types.void(types.uintp, types.uintp, types.uintp, types.uintp))
# RTCRayHit8 in 4-byte words (rtcore_ray.h): 12 ray fields, then the hit's
# Ng (3), u, v, primID, geomID, instID, instPrimID, each 8 wide; then the
# valid mask.
_GEOM8, _VALID8, _WORDS8 = 96 + 48, 168, 176


@dataclass
class Batch:
    """One call into Embree: closest hits (`dists` None or bounded) or
    occlusion (`occluded`), among the objects `members`."""
    members: tuple
    origins: np.ndarray
    dirs: np.ndarray
    dists: np.ndarray | None
    occluded: bool

    def __len__(self) -> int:
        return len(self.origins)


@contextmanager
def recording(batches: list[Batch]):
    """Every batch the Accelerator casts inside the block, appended to `batches`."""
    closest_in, occluded = Accelerator.closest_in, Accelerator.occluded

    def recorded_closest(self, view, origins, dirs, dists=None):
        if len(origins) and view.scene is not None:
            batches.append(Batch(tuple(view.objects), np.array(origins, dtype=np.float64),
                                 np.array(dirs, dtype=np.float64), None if dists is None else np.array(dists), False))
        return closest_in(self, view, origins, dirs, dists)

    def recorded_occluded(self, origins, dirs, dists):
        view = self._views[3]
        if len(origins) and view.scene is not None:
            batches.append(Batch(tuple(view.objects), np.array(origins, dtype=np.float64),
                                 np.array(dirs, dtype=np.float64), np.array(dists), True))
        return occluded(self, origins, dirs, dists)

    Accelerator.closest_in, Accelerator.occluded = recorded_closest, recorded_occluded
    try:
        yield
    finally:
        Accelerator.closest_in, Accelerator.occluded = closest_in, occluded


@numba.njit(nogil=True)
def _occluded_in_packets(scene, origins, dirs, dists, geom_out):
    floats, words, valid, address, valid_address = packet_record()
    n = len(origins)
    for start in range(0, n, PACKET):
        count = min(PACKET, n - start)
        for k in range(count):
            i = start + k
            set_packet_ray(floats, words, valid, k, (origins[i, 0], origins[i, 1], origins[i, 2]),
                           (dirs[i, 0], dirs[i, 1], dirs[i, 2]), dists[i])
        occluded8(scene, floats, valid, address, valid_address, count)
        for k in range(count):
            geom_out[start + k] = 0 if packet_blocked(floats, k) else -1


@numba.njit(nogil=True)
def _direct1(scene, origins, dirs, dists, geom_out):
    floats, words, address = ray_record()
    bounded = len(dists) > 0
    for i in range(len(origins)):
        far = dists[i] if bounded else np.inf
        o, d = (origins[i, 0], origins[i, 1], origins[i, 2]), (dirs[i, 0], dirs[i, 1], dirs[i, 2])
        geom_out[i] = intersect1(scene, floats, words, address, o, d, far)[0]


@numba.njit(nogil=True)
def _direct8(scene, origins, dirs, dists, geom_out):
    block = np.zeros(_WORDS8 + 16, dtype=np.float32)
    skip = ((-block.ctypes.data) % 64) // 4
    f = block[skip:skip + _WORDS8]
    w = f.view(np.uint32)
    valid = f[_VALID8:_VALID8 + 8].view(np.int32)
    address = block.ctypes.data + 4 * skip
    bounded, n = len(dists) > 0, len(origins)
    for start in range(0, n, 8):
        for k in range(8):
            i = min(start + k, n - 1)
            valid[k] = -1 if start + k < n else 0
            f[k], f[8 + k], f[16 + k] = origins[i, 0], origins[i, 1], origins[i, 2]
            f[32 + k], f[40 + k], f[48 + k] = dirs[i, 0], dirs[i, 1], dirs[i, 2]
            f[24 + k], f[56 + k], f[64 + k] = 0.0, 0.0, dists[i] if bounded else np.inf
            w[72 + k], w[80 + k], w[88 + k] = 0xFFFFFFFF, 0, 0
            w[_GEOM8 + k], w[_GEOM8 - 8 + k], w[_GEOM8 + 8 + k] = 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF
        _intersect8(address + 4 * _VALID8, scene, address, 0)
        for k in range(min(8, n - start)):
            g = w[_GEOM8 + k]
            geom_out[start + k] = -1 if g == 0xFFFFFFFF else np.int64(g)


class Replay:
    """The recorded batches' scenes, built once, for each way of casting."""

    def __init__(self, objects, batches: list[Batch], threads: int = 2, quality: str = "medium"):
        self.batches, self.threads = batches, threads
        meshes = {members: [objects[i].mesh for i in members] for members in {b.members for b in batches}}
        self._direct = {m: embree.Scene([embree.Geometry(x.vertices, x.triangles) for x in ms], quality)
                        for m, ms in meshes.items()}
        self._embreex = {}
        for members, ms in meshes.items():
            scene = rtcore_scene.EmbreeScene()
            for mesh in ms:
                TriangleMesh(scene, mesh.vertices.astype(np.float32), mesh.triangles.astype(np.int32))
            self._embreex[members] = scene
        self._pool = ThreadPoolExecutor(threads)
        for way in ("direct1", "direct8"):  # compiled before any is timed
            self.seconds(way, self.batches[:1], repeats=1)

    def rays(self) -> int:
        return sum(len(b) for b in self.batches)

    def _cast(self, way: str, batch: Batch, a: int, b: int):
        dists = batch.dists
        if way == "embreex":
            o32 = np.ascontiguousarray(batch.origins[a:b], dtype=np.float32)
            d32 = np.ascontiguousarray(batch.dirs[a:b], dtype=np.float32)
            kwargs = dict(query="OCCLUDED") if batch.occluded else dict(output=1)
            return self._embreex[batch.members].run(
                o32, d32, dists=None if dists is None else np.ascontiguousarray(dists[a:b], dtype=np.float32),
                **kwargs)
        kernel = _occluded_in_packets if batch.occluded else _direct1 if way == "direct1" else _direct8
        out = np.empty(b - a, dtype=np.int64)
        kernel(self._direct[batch.members].handle, batch.origins[a:b], batch.dirs[a:b],
               np.zeros(0) if dists is None else dists[a:b], out)
        return out

    def seconds(self, way: str, batches: list[Batch] | None = None, repeats: int = 3) -> float:
        """The fastest of `repeats` replays of `batches` (all) by `way`:
        'embreex', 'direct1' (as the engine casts) or 'direct8' (closest
        hits in packets of 8 too)."""
        best = np.inf
        for _ in range(repeats):
            start = time.perf_counter()
            for batch in self.batches if batches is None else batches:
                n = len(batch)
                if n < 8192:
                    self._cast(way, batch, 0, n)
                    continue
                bounds = np.linspace(0, n, self.threads + 1).astype(int)
                list(self._pool.map(lambda i: self._cast(way, batch, bounds[i], bounds[i + 1]),
                                    range(self.threads)))
            best = min(best, time.perf_counter() - start)
        return best

    def close(self) -> None:
        self._pool.shutdown()
