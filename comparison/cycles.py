"""The same view rendered by Cycles on the CPU with MNEE shadow caustics
(the reference the caustic render is compared with). Every setting changed
for it is put back, and the temporary EXR and its image are deleted."""

from __future__ import annotations

import os
import tempfile
import time

import bpy
import numpy as np

from ..export import SceneRead
from ..writeback.images import read_pixels
from .overrides import Overrides

RENDER_RESULT = "Render Result"


def _cycles_settings(overrides: Overrides, scene, samples: int, time_limit: float, path: str) -> None:
    render, cycles, output = scene.render, scene.cycles, scene.render.image_settings
    overrides.set(render, "engine", 'CYCLES')
    for name, value in (("device", 'CPU'), ("samples", samples), ("time_limit", time_limit),
                        ("use_denoising", False), ("pixel_filter_type", 'BOX'), ("filter_width", 1.0)):
        overrides.set(cycles, name, value)
    for name, value in (("film_transparent", False), ("use_compositing", False), ("use_sequencer", False),
                        ("use_border", False), ("use_multiview", False), ("use_motion_blur", False),
                        ("use_file_extension", False), ("filepath", path)):
        overrides.set(render, name, value)
    # The file format decides which colour depths and modes exist: record them first.
    overrides.keep(output, "color_depth", "color_mode")
    if hasattr(output, "media_type"):
        overrides.set(output, "media_type", 'IMAGE')
    for name, value in (("file_format", 'OPEN_EXR'), ("color_depth", '32'), ("color_mode", 'RGBA')):
        overrides.set(output, name, value)


def _shadow_caustics(overrides: Overrides, read: SceneRead) -> None:
    """Turn MNEE on for the transparent objects (casters), the receivers and the
    lamps. Reflectors are neither: MNEE cannot solve for mirrors."""
    for ob in read.scene.objects:
        source = bpy.data.objects[read.sources[ob.name]]
        if ob.is_transparent or ob.is_receiver:
            overrides.set(source.cycles, "is_caustics_caster" if ob.is_transparent else "is_caustics_receiver", True)
    for light in read.scene.lights:
        overrides.set(bpy.data.objects[read.sources[light.name]].data.cycles, "is_caustics_light", True)


def render_cycles(scene, read: SceneRead, samples: int, time_limit: float) -> tuple[np.ndarray, float]:
    """((h,w,4) float32 top row first, seconds) of a Cycles render of `scene`'s camera."""
    had_render_result = RENDER_RESULT in bpy.data.images
    with tempfile.TemporaryDirectory(prefix="caustic-cycles-") as folder, Overrides() as overrides:
        path = os.path.join(folder, "reference.exr")
        _cycles_settings(overrides, scene, samples, time_limit, path)
        _shadow_caustics(overrides, read)
        clock = time.perf_counter()
        bpy.ops.render.render(write_still=True, scene=scene.name)
        seconds = time.perf_counter() - clock
        image = bpy.data.images.load(path)
        try:
            pixels = read_pixels(image).copy()
        finally:
            bpy.data.images.remove(image)
    if not had_render_result and RENDER_RESULT in bpy.data.images:
        bpy.data.images.remove(bpy.data.images[RENDER_RESULT])
    return pixels, seconds
