"""Illumination maps kept between renders: moving the camera, or changing
only the eye pass (samples, ambient), must not re-run the pass
from the lamps. Maps are found by a hash of everything that pass reads;
the renderer uses them if each can serve the camera (`sees`: a flat
receiver's beam map makes the new view's screen layer from the beams it
kept, and one that kept too few to do it sends the lamps out again).

By default only the last scene's maps are kept, and they are dropped
before a lamp pass for another scene starts: an animation whose caster
moves traces every frame, and a second set would be held beside the one
being traced for nothing (in the animated pool, 65 MB of maps, and 0.6 s
of this machine's page faults in the second frame as the heap grew for it)."""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from dataclasses import fields
from typing import Optional

import numpy as np

from ..scene import RenderSettings, Scene

# RenderSettings fields that change nothing in the maps.
_EYE_ONLY = {"spp", "edge_samples", "lamp_samples", "world_samples", "threads", "chunk_size"}
# Material fields only the eye pass reads: a receiver's map holds irradiance.
_SHADING_ONLY = {"albedo", "specular", "texture"}
# Lamp fields only the eye pass reads: which eye rays see the lamp itself.
_SEEN_ONLY = {"visibility"}


def scene_digest(scene: Scene) -> bytes:
    """SHA-1 of what the pass from the lamps reads of `scene`: the objects
    in order (name, body, geometry, material), the lamps and the world."""
    digest = hashlib.sha1()

    def add(value) -> None:
        if isinstance(value, np.ndarray):
            digest.update(str((value.dtype, value.shape)).encode())
            digest.update(np.ascontiguousarray(value))
        else:
            digest.update(repr(value).encode())

    for obj in scene.objects:
        add((obj.name, obj.body, type(obj.material).__name__))
        mesh = obj.mesh if obj.instances is None else obj.instances.mesh  # the copies follow from it
        for array in (mesh.vertices, mesh.triangles, mesh.corner_normals, mesh.corner_uvs):
            add(array)
        if obj.instances is not None:
            add(obj.instances.transforms)
        for name, value in vars(obj.material).items():
            if name in _SHADING_ONLY:
                continue
            add(name)
            add(value if isinstance(value, np.ndarray) else np.asarray(value))
    for light in [*scene.lights, scene.world]:
        add(type(light).__name__)
        for name, value in vars(light).items():
            if name in _SEEN_ONLY:
                continue
            add(name)
            add(value if isinstance(value, np.ndarray) else np.asarray(value))
    return digest.digest()


def lamp_pass_key(scene: Scene, settings: RenderSettings, digest: Optional[bytes] = None) -> str:
    """SHA-1 of `scene_digest` (`digest`, where the caller has it) and the
    lamp pass's settings: equal keys give equal maps. The band count counts
    only if a material disperses."""
    key = hashlib.sha1(scene_digest(scene) if digest is None else digest)
    disperses = any(math.isfinite(getattr(o.material, "abbe", math.inf)) for o in scene.objects)
    ignored = _EYE_ONLY if disperses else _EYE_ONLY | {"bands"}
    key.update(repr({f.name: getattr(settings, f.name) for f in fields(settings) if f.name not in ignored}).encode())
    return key.hexdigest()


class MapCache:
    """The lamp passes of the last `capacity` distinct scenes: key ->
    (maps, their figures, their warnings), the least recently used dropped
    first, also while they hold more than `max_bytes` (but the newest).
    Safe to share between threads."""

    def __init__(self, capacity: int = 1, max_bytes: Optional[int] = None):
        self.capacity, self.max_bytes = capacity, max_bytes
        self._entries: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    @staticmethod
    def _entry_bytes(entry) -> int:
        maps, _, _ = entry
        return sum(imap.nbytes for imap in maps.values())

    @property
    def nbytes(self) -> int:
        with self._lock:
            return sum(map(self._entry_bytes, self._entries.values()))

    def get(self, key: str):
        with self._lock:
            if key in self._entries:
                self._entries.move_to_end(key)
                return self._entries[key]
            return None

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()

    def make_room(self, key: str) -> None:
        """Before the lamp pass for `key` runs: drop its old entry and the
        least recently used beyond one fewer than capacity, so that the maps
        being traced are not held beside as many as `put` will keep."""
        with self._lock:
            self._entries.pop(key, None)
            while len(self._entries) >= self.capacity:
                self._entries.popitem(last=False)

    def put(self, key: str, value) -> None:
        with self._lock:
            self._entries[key] = value
            self._entries.move_to_end(key)
            while len(self._entries) > self.capacity:
                self._entries.popitem(last=False)
            if self.max_bytes is not None:
                sizes = [self._entry_bytes(entry) for entry in self._entries.values()]
                while len(self._entries) > 1 and sum(sizes) > self.max_bytes:
                    self._entries.popitem(last=False)
                    sizes.pop(0)
