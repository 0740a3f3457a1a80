"""The same view rendered by Cycles on the CPU with MNEE shadow caustics
(the reference the caustic render is compared with). Every setting changed
for it is put back."""

from __future__ import annotations

import bpy
import numpy as np

from ..export import SceneRead
from ..export.cycles_still import render_still
from ..export.overrides import Overrides


def _cycles_settings(overrides: Overrides, scene, samples: int, time_limit: float) -> None:
    overrides.set(scene.render, "engine", 'CYCLES')
    for name, value in (("device", 'CPU'), ("samples", samples), ("time_limit", time_limit),
                        ("use_denoising", False), ("pixel_filter_type", 'BOX'), ("filter_width", 1.0)):
        overrides.set(scene.cycles, name, value)
    for name, value in (("film_transparent", False), ("use_motion_blur", False)):
        overrides.set(scene.render, name, value)


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
    with Overrides() as overrides:
        _cycles_settings(overrides, scene, samples, time_limit)
        _shadow_caustics(overrides, read)
        return render_still(scene, overrides)
