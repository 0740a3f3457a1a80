"""Embree 4, called directly: the `libembree4` that embreex's wheel ships,
scenes built from numpy buffers, and rays cast from the kernels.

The library is loaded once per process through ctypes and its two query
functions are registered with LLVM under names of our own
(`caustic_rtcIntersect1`, `caustic_rtcOccluded8`), so a kernel calls them
as external functions: the compiled code names the symbol, not an
address, and stays in numba's disk cache. Blender links a libembree4 of
its own for Cycles; the names keep ours apart from it.

What the kernels rely on (Embree 4.4's rtcore_ray.h, rtcore_scene.h):
- `RTCRayHit` is the 48-byte ray (origin, tnear, direction, time, tfar,
  mask, id, flags) then the hit (Ng, u, v, primID, geomID, instID and, in
  builds with instance arrays, instPrimID), 16-byte aligned. `ray_record`
  lays one out in a kernel's own block of memory, aligned to 64 bytes
  (what the 16-wide packets would want), once per kernel call; rays are
  written into it from the path state and hits read out of it, in place.
- tnear is 0: callers offset secondary origins themselves (accelerator.offset1).
- Embree works in float32: origins, directions and distances are rounded
  to nearest, as numpy's astype rounds them.
- Scenes are built with RTC_SCENE_FLAG_ROBUST, as embreex built them.
  Robust mode avoids most of the cracks between triangles that share an
  edge, not all of them: Embree's triangle test is not watertight, and a
  ray aimed exactly at a vertex or an edge can pass between the faces
  around it (tests/engine/test_stress.py measures it; the accelerator
  passes such phantom hits by the ray's medium).
- Shared buffers: Embree reads the vertex and index arrays where numpy
  keeps them (`rtcSetSharedGeometryBuffer`), so a `Geometry` holds them for
  as long as its scene lives. A vertex buffer is (n,4) float32: Embree
  reads each vertex with a 16-byte load.
- Build quality per use (`BUILD_QUALITY`): low where a scene lives for
  one Live update, medium for frames. High builds as fast but casts no
  faster on our scenes (benchmarks/bvh_build.py).
"""

from __future__ import annotations

import ctypes
import weakref
from pathlib import Path

import numpy as np
from llvmlite import binding as llvm
from numba import types

from ..util.jit import inline

# Enum values of Embree 4's rtcore_common.h, rtcore_buffer.h, rtcore_geometry.h, rtcore_scene.h.
_GEOMETRY_TYPE_TRIANGLE, _GEOMETRY_TYPE_INSTANCE_ARRAY = 0, 122
_BUFFER_TYPE_INDEX, _BUFFER_TYPE_VERTEX, _BUFFER_TYPE_TRANSFORM = 0, 1, 23
_FORMAT_UINT3, _FORMAT_FLOAT3, _FORMAT_FLOAT4X4_COLUMN_MAJOR = 0x5003, 0x9003, 0x9244
_SCENE_FLAG_ROBUST = 1 << 2
BUILD_QUALITY = {"low": 0, "medium": 1, "high": 2}  # RTC_BUILD_QUALITY_*
_ERRORS = {1: "unknown error", 2: "invalid argument", 3: "invalid operation", 4: "out of memory",
           5: "unsupported CPU", 6: "cancelled", 7: "level zero raytracing support missing"}

# RTCRayHit in 4-byte words: the ray's fields, then the hit's from word 12.
_ORG, _TNEAR, _DIR, _TIME, _TFAR, _MASK, _ID, _FLAGS = 0, 3, 4, 7, 8, 9, 10, 11
_U, _V, _PRIM, _GEOM, _INST, _INST_PRIM = 15, 16, 17, 18, 19, 20
_WORDS = 24  # RTCRayHit with instPrimID, padded to 16 bytes
_ALIGN_WORDS = 16  # 64 bytes
# RTCRay8: each of the ray's 12 fields 8 wide, in the same order; then the
# packet's valid mask (int32, -1 for a ray, 0 for none) in the same block.
PACKET = 8
_PACKET_VALID, _PACKET_WORDS = 12 * PACKET, 13 * PACKET
INVALID_ID = 0xFFFFFFFF


# Where embreex's wheels put libembree4, from site-packages: auditwheel's
# folder on Linux, delvewheel's on Windows (embreex's import puts it on the
# DLL search path, for tbb12.dll beside it), delocate's on macOS.
LIBRARY_PLACES = (("embreex.libs", "libembree4*.so*"), ("embreex.libs", "embree4*.dll"),
                  ("embreex/.dylibs", "libembree4*.dylib"))


def library_path() -> Path:
    """The libembree4 of the embreex this process imports."""
    import embreex

    site = Path(embreex.__file__).resolve().parents[1]
    for folder, pattern in LIBRARY_PLACES:
        found = sorted((site / folder).glob(pattern))
        if found:
            return found[0]
    raise ImportError(f"Embree's library is not where embreex's wheel puts it (in {site}: "
                      f"{', '.join(f'{folder}/{pattern}' for folder, pattern in LIBRARY_PLACES)}); "
                      "reinstall the extension")


def _load() -> ctypes.CDLL:
    """The library, its functions typed, its query functions registered with LLVM."""
    lib = ctypes.CDLL(str(library_path()))
    pointer, uint, size = ctypes.c_void_p, ctypes.c_uint, ctypes.c_size_t
    prototypes = {
        "rtcNewDevice": (pointer, [ctypes.c_char_p]),
        "rtcGetDeviceError": (ctypes.c_int, [pointer]),
        "rtcNewScene": (pointer, [pointer]),
        "rtcSetSceneFlags": (None, [pointer, ctypes.c_int]),
        "rtcSetSceneBuildQuality": (None, [pointer, ctypes.c_int]),
        "rtcCommitScene": (None, [pointer]),
        "rtcReleaseScene": (None, [pointer]),
        "rtcNewGeometry": (pointer, [pointer, ctypes.c_int]),
        "rtcSetSharedGeometryBuffer": (None, [pointer, ctypes.c_int, uint, ctypes.c_int, pointer, size, size, size]),
        "rtcCommitGeometry": (None, [pointer]),
        "rtcSetGeometryInstancedScene": (None, [pointer, pointer]),
        "rtcAttachGeometry": (uint, [pointer, pointer]),
        "rtcReleaseGeometry": (None, [pointer]),
    }
    for name, (restype, argtypes) in prototypes.items():
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes
    for name in ("rtcIntersect1", "rtcOccluded8"):
        llvm.add_symbol(f"caustic_{name}", ctypes.cast(getattr(lib, name), ctypes.c_void_p).value)
    return lib


_lib = _load()
_device = None

# The queries as the kernels call them, pointers as integers: (scene,
# RTCRayHit*, arguments* = NULL) and (valid*, scene, RTCRay8*, arguments* = NULL).
_intersect1 = types.ExternalFunction("caustic_rtcIntersect1", types.void(types.uintp, types.uintp, types.uintp))
_occluded8 = types.ExternalFunction("caustic_rtcOccluded8",
                                    types.void(types.uintp, types.uintp, types.uintp, types.uintp))


def device():
    """The process's Embree device, made on first use."""
    global _device
    if _device is None:
        _device = _lib.rtcNewDevice(None)
        if not _device:
            raise RuntimeError("Embree could not start on this CPU (rtcNewDevice failed)")
    return _device


def _check(what: str) -> None:
    code = _lib.rtcGetDeviceError(device())
    if code:
        raise MemoryError(f"Embree could not {what}: out of memory") if code == 4 else \
            RuntimeError(f"Embree could not {what}: {_ERRORS.get(code, f'error {code}')}")


class Geometry:
    """One triangle mesh as Embree reads it in place: `vertices (n,4)`
    float32 (w unused), `triangles (m,3)` uint32."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        self.vertices = np.zeros((len(vertices), 4), dtype=np.float32)
        self.vertices[:, :3] = vertices
        self.triangles = np.ascontiguousarray(triangles, dtype=np.uint32).reshape(-1, 3)


class Instances:
    """One mesh under many transforms, as Embree reads them in place: the
    mesh's own committed scene `prototype` (a Scene of one Geometry), and
    `transforms (k,4,4)` object to world, kept as column-major float32.
    Embree builds the mesh's BVH once and a BVH over the k boxes (an
    instance array, Embree 4.3); a hit reports the copy it met (intersect1)."""

    def __init__(self, prototype: "Scene", transforms: np.ndarray):
        self.prototype = prototype
        self.transforms = np.ascontiguousarray(np.asarray(transforms).transpose(0, 2, 1), dtype=np.float32)

    @property
    def triangle_count(self) -> int:
        return len(self.prototype.geometries[0].triangles) * len(self.transforms)


class Scene:
    """An Embree scene of `geometries` (a Geometry or Instances each),
    committed: a ray's geomID is its geometry's place in the list.
    `quality` is a key of BUILD_QUALITY. `handle` is what the kernels take;
    it is freed with the Scene."""

    def __init__(self, geometries: list[Geometry | Instances], quality: str = "medium"):
        self.geometries = geometries  # Embree reads their buffers while the scene lives
        self.handle = _lib.rtcNewScene(device())
        weakref.finalize(self, _lib.rtcReleaseScene, self.handle)
        _lib.rtcSetSceneFlags(self.handle, _SCENE_FLAG_ROBUST)
        _lib.rtcSetSceneBuildQuality(self.handle, BUILD_QUALITY[quality])
        for geometry in geometries:
            if isinstance(geometry, Instances):
                made = _lib.rtcNewGeometry(device(), _GEOMETRY_TYPE_INSTANCE_ARRAY)
                _lib.rtcSetGeometryInstancedScene(made, geometry.prototype.handle)
                _lib.rtcSetSharedGeometryBuffer(made, _BUFFER_TYPE_TRANSFORM, 0, _FORMAT_FLOAT4X4_COLUMN_MAJOR,
                                                geometry.transforms.ctypes.data, 0, 64, len(geometry.transforms))
            else:
                made = _lib.rtcNewGeometry(device(), _GEOMETRY_TYPE_TRIANGLE)
                _lib.rtcSetSharedGeometryBuffer(made, _BUFFER_TYPE_VERTEX, 0, _FORMAT_FLOAT3,
                                                geometry.vertices.ctypes.data, 0, 16, len(geometry.vertices))
                _lib.rtcSetSharedGeometryBuffer(made, _BUFFER_TYPE_INDEX, 0, _FORMAT_UINT3,
                                                geometry.triangles.ctypes.data, 0, 12, len(geometry.triangles))
            _lib.rtcCommitGeometry(made)
            _lib.rtcAttachGeometry(self.handle, made)
            _lib.rtcReleaseGeometry(made)
        _lib.rtcCommitScene(self.handle)
        count = sum(g.triangle_count if isinstance(g, Instances) else len(g.triangles) for g in geometries)
        _check(f"build the BVH of {count:,} triangles")


@inline
def ray_record():
    """A kernel's RTCRayHit: (floats (24,) float32 and words (24,) uint32,
    two views of it, and its address), 64-byte aligned in a block of its own."""
    block = np.zeros(_WORDS + _ALIGN_WORDS, dtype=np.float32)
    skip = ((-block.ctypes.data) % (4 * _ALIGN_WORDS)) // 4
    floats = block[skip:skip + _WORDS]
    return floats, floats.view(np.uint32), block.ctypes.data + 4 * skip


@inline
def _set_ray(floats, words, origin, d, tfar):
    """The ray of the record: from `origin` along `d`, 0 to `tfar`, every mask bit."""
    floats[_ORG], floats[_ORG + 1], floats[_ORG + 2] = origin[0], origin[1], origin[2]
    floats[_DIR], floats[_DIR + 1], floats[_DIR + 2] = d[0], d[1], d[2]
    floats[_TNEAR], floats[_TIME], floats[_TFAR] = 0.0, 0.0, tfar
    words[_MASK], words[_ID], words[_FLAGS] = INVALID_ID, 0, 0


@inline
def intersect1(scene, floats, words, address, origin, d, tfar):
    """Embree's closest hit of the ray from `origin` along `d` within `tfar`
    in scene `scene` (a Scene's handle), through the record `ray_record`
    gave: (geomID, primID, copy, t, u, v), geomID -1 on a miss. On an
    Instances, geomID is its place in the scene, primID the mesh's own
    triangle and `copy` the transform's row; elsewhere `copy` is 0."""
    _set_ray(floats, words, origin, d, tfar)
    words[_GEOM], words[_PRIM], words[_INST], words[_INST_PRIM] = INVALID_ID, INVALID_ID, INVALID_ID, 0
    _intersect1(scene, address, 0)
    if words[_GEOM] == INVALID_ID:
        geom, copy = -1, 0
    elif words[_INST] == INVALID_ID:
        geom, copy = np.int64(words[_GEOM]), 0
    else:
        geom, copy = np.int64(words[_INST]), np.int64(words[_INST_PRIM])
    return (geom, np.int64(words[_PRIM]), copy, np.float64(floats[_TFAR]), np.float64(floats[_U]),
            np.float64(floats[_V]))


@inline
def packet_record():
    """A kernel's RTCRay8 and its valid mask: (floats (104,) float32, words
    (104,) uint32, valid (8,) int32, views of one block, 64-byte aligned;
    the address of the rays and of the mask)."""
    block = np.zeros(_PACKET_WORDS + _ALIGN_WORDS, dtype=np.float32)
    skip = ((-block.ctypes.data) % (4 * _ALIGN_WORDS)) // 4
    floats = block[skip:skip + _PACKET_WORDS]
    address = block.ctypes.data + 4 * skip
    return (floats, floats.view(np.uint32), floats[_PACKET_VALID:].view(np.int32), address,
            address + 4 * _PACKET_VALID)


@inline
def set_packet_ray(floats, words, valid, k, origin, d, tfar):
    """Ray `k` of the packet: from `origin` along `d`, 0 to `tfar`, every mask bit."""
    for axis in range(3):
        floats[(_ORG + axis) * PACKET + k] = origin[axis]
        floats[(_DIR + axis) * PACKET + k] = d[axis]
    floats[_TNEAR * PACKET + k], floats[_TIME * PACKET + k], floats[_TFAR * PACKET + k] = 0.0, 0.0, tfar
    words[_MASK * PACKET + k], words[_ID * PACKET + k], words[_FLAGS * PACKET + k] = INVALID_ID, 0, 0
    valid[k] = -1


@inline
def occluded8(scene, floats, valid, address, valid_address, count):
    """Embree's occlusion test of the packet's first `count` rays, set by
    set_packet_ray (the rest are masked off); afterwards ray k is blocked
    where packet_blocked(floats, k): Embree sets its tfar to -inf when it
    finds something in the way."""
    for k in range(count, PACKET):
        valid[k] = 0
    _occluded8(valid_address, scene, address, 0)


@inline
def packet_blocked(floats, k):
    return floats[_TFAR * PACKET + k] < 0.0
