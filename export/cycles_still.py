"""One still rendered by a scene's own engine to a temporary float EXR and
read back; every output setting changed for it is put back, and the file,
its image and a Render Result that was not there before are deleted
(except where a render view shows it, after a render started as F12).

`StillRender.start()` asks for the render as F12 does. In the interface
that starts Blender's render job (its progress in the status bar, its
render view, Esc stops it: any Esc press sets Blender's global break flag,
which the render thread polls) and returns at once; in the background
Blender renders before the call returns. Blender ends its render job on its
main thread, so the main thread can only poll `ended`, never wait for it."""

from __future__ import annotations

import os
import tempfile
import time

import bpy
import numpy as np

from .overrides import Overrides
from .pixels import image_pixels

RENDER_RESULT = "Render Result"


def cycles_enabled() -> bool:
    """Whether the Cycles add-on is on (Preferences > Add-ons can turn it
    off): it registers Scene.cycles."""
    return hasattr(bpy.types.Scene, "cycles")


def _exr_output(overrides: Overrides, scene, path: str) -> None:
    render, output = scene.render, scene.render.image_settings
    for name, value in (("use_compositing", False), ("use_sequencer", False), ("use_border", False),
                        ("use_multiview", False), ("use_file_extension", False), ("filepath", path)):
        overrides.set(render, name, value)
    # The file format decides which colour depths and modes exist: record them first.
    overrides.keep(output, "color_depth", "color_mode")
    if hasattr(output, "media_type"):
        overrides.set(output, "media_type", 'IMAGE')
    for name, value in (("file_format", 'OPEN_EXR'), ("color_depth", '32'), ("color_mode", 'RGBA')):
        overrides.set(output, name, value)


class StillRender:
    """A still of `scene` as it is set up, its output settings changed on
    `overrides` (which the caller restores, after `close()`)."""

    def __init__(self, scene, overrides: Overrides):
        self.scene, self._overrides = scene, overrides
        self._folder = tempfile.TemporaryDirectory(prefix="caustic-still-")
        self._path = os.path.join(self._folder.name, "still.exr")
        self._keep_render_result = RENDER_RESULT in bpy.data.images
        self._clock = 0.0
        self.seconds = 0.0

    def start(self, wait: bool = False) -> bool:
        """Begin the render (or, with `wait`, render before returning);
        False if Blender refused to start it. RuntimeError names a failure
        Blender reports."""
        _exr_output(self._overrides, self.scene, self._path)
        self._clock = time.perf_counter()
        if wait:
            started = bpy.ops.render.render(write_still=True, scene=self.scene.name)
            self.seconds = time.perf_counter() - self._clock
        else:
            started = bpy.ops.render.render('INVOKE_DEFAULT', write_still=True, scene=self.scene.name)
            # the render view opened for it shows the Render Result, as after F12
            self._keep_render_result |= not bpy.app.background
        return 'CANCELLED' not in started

    @property
    def ended(self) -> bool:
        """Whether Blender's render job is over (then `seconds` is its time)."""
        if bpy.app.is_job_running('RENDER'):
            return False
        if not self.seconds:
            self.seconds = time.perf_counter() - self._clock
        return True

    def pixels(self) -> np.ndarray | None:
        """(h, w, 4) float32 linear RGBA, top row first; None if the render
        wrote no file (it was stopped, or it failed)."""
        if not os.path.exists(self._path):
            return None
        image = bpy.data.images.load(self._path)
        try:
            return image_pixels(image).copy()
        finally:
            bpy.data.images.remove(image)

    def close(self) -> None:
        self._folder.cleanup()
        if not self._keep_render_result and RENDER_RESULT in bpy.data.images:
            bpy.data.images.remove(bpy.data.images[RENDER_RESULT])


def render_still(scene, overrides: Overrides) -> tuple[np.ndarray, float]:
    """((h, w, 4) float32 linear RGBA, top row first; seconds) of `scene`
    rendered as it is set up, here and now, its output settings changed on
    `overrides`."""
    still = StillRender(scene, overrides)
    try:
        still.start(wait=True)
        pixels = still.pixels()
    finally:
        still.close()
    if pixels is None:
        raise RuntimeError("the render wrote no image")
    return pixels, still.seconds
