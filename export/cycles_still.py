"""One still rendered by a scene's own engine to a temporary float EXR and
read back; every output setting changed for it is put back, and the file,
its image and a Render Result that was not there before are deleted."""

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


def render_still(scene, overrides: Overrides) -> tuple[np.ndarray, float]:
    """((h, w, 4) float32 linear RGBA, top row first; seconds) of `scene`
    rendered as it is set up, its output settings changed on `overrides`."""
    had_render_result = RENDER_RESULT in bpy.data.images
    with tempfile.TemporaryDirectory(prefix="caustic-still-") as folder:
        path = os.path.join(folder, "still.exr")
        _exr_output(overrides, scene, path)
        clock = time.perf_counter()
        bpy.ops.render.render(write_still=True, scene=scene.name)
        seconds = time.perf_counter() - clock
        image = bpy.data.images.load(path)
        try:
            pixels = image_pixels(image).copy()
        finally:
            bpy.data.images.remove(image)
    if not had_render_result and RENDER_RESULT in bpy.data.images:
        bpy.data.images.remove(bpy.data.images[RENDER_RESULT])
    return pixels, seconds
