"""One engine render, run here or on a worker thread, and the illumination
maps kept between renders. Nothing in this module touches bpy: the scene
comes in as numpy, the result goes out as numpy."""

from __future__ import annotations

import threading
import time
import traceback
from dataclasses import replace

import numpy as np

from ..caustic_addon import (Cancelled, MapCache, RenderResult, RenderSettings, Scene, SceneError, memory_refusal,
                             render)

# Illumination maps of the last scene rendered: a camera move re-runs only the eye pass.
MAP_CACHE = MapCache()
# What a pixel of the render takes in Blender besides the engine's own: the render image and its three
# passes, each a float RGBA buffer (16 B) and its packed EXR (up to 16 B), the UI's undo step holding a copy
# of those (16 B), and the flipped copy each write makes (16 B). Measured: 129 B a pixel over the engine's
# peak at 3000 x 3000, in the background, where no undo step is kept.
IMAGE_BYTES_PER_PIXEL = 4 * (16 + 16 + 16) + 16


LOWER_RESOLUTION = "lower the resolution or its % (Output Properties)"


def refusal(scene: Scene, settings: RenderSettings, besides: dict[str, tuple[float, str]] | None = None) -> str | None:
    """Why a render of `scene` into Blender's images cannot fit in memory,
    the whole process's need told up front, with what the caller holds
    `besides` (part: (bytes, what to lower)); None if it fits."""
    pixels = scene.camera.pixx * scene.camera.pixy
    return memory_refusal(scene, settings, besides={
        "Blender's images of the render": (IMAGE_BYTES_PER_PIXEL * pixels, LOWER_RESOLUTION), **(besides or {})})


def map_rgba(imap, threads: int = 1) -> np.ndarray:
    """(h,w,4) float32 of a map's irradiance, top row first (map row 0 is the
    chart's lowest y), read on up to `threads` threads: a bake's image."""
    rgba = np.ones(imap.shape + (4,), dtype=np.float32)
    rgba[..., :3] = imap.irradiance(threads)
    return rgba[::-1]


class RenderJob:
    """fraction and stage follow the engine's progress; after the run, either
    `result` is set or `error` holds the message for the user (None when
    cancelled). `cache` keeps the maps a later job can reuse; `key` is their
    key in it, where the job knows it before the render (None: the render's)."""

    def __init__(self, scene: Scene, settings: RenderSettings, cache: MapCache = MAP_CACHE):
        self.scene, self.settings, self.cache = scene, settings, cache
        self.key: str | None = None
        self.fraction, self.stage = 0.0, ""
        self.result: RenderResult | None = None
        self.error: str | None = None
        self.cancelled = False
        self.seconds = 0.0
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None

    def _progress(self, fraction: float, stage: str) -> None:
        self.fraction, self.stage = fraction, stage

    def run(self) -> None:
        clock = time.perf_counter()
        try:
            self.result = render(self.scene, self.settings, progress=self._progress, cancel=self._cancel.is_set,
                                 cache=self.cache, key=self.key)
        except Cancelled:
            self.cancelled = True
        except SceneError as exc:
            self.error = str(exc)
        except Exception as exc:
            traceback.print_exc()
            self.error = f"The caustic engine failed: {type(exc).__name__}: {exc}"
        self.seconds = time.perf_counter() - clock

    def drop_maps(self) -> None:
        """Once the result is written: its maps go, so that a run keeps no
        frame's maps through the next one (the cache keeps those a later
        frame can reuse)."""
        if self.result is not None:
            self.result = replace(self.result, maps={})

    def start(self) -> None:
        self._thread = threading.Thread(target=self.run, name="caustic render", daemon=True)
        self._thread.start()

    def cancel(self) -> None:
        self._cancel.set()

    def wait(self) -> None:
        if self._thread is not None:
            self._thread.join()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()
