"""Light inside a medium: Beer-Lambert absorption, and the coefficient from the colours artists give."""

from __future__ import annotations

import math

import numpy as np

from ..util.jit import inline


@inline
def beer_lambert1(absorption, distance):
    """Transmittance exp(-sigma_a s) of a path of length `distance` through
    a medium of absorption coefficient `absorption` (sigma_a, one channel)
    per metre."""
    return math.exp(-absorption * distance)


def absorption_from_color(color, distance: float) -> np.ndarray:
    """Absorption coefficient sigma_a (3,) per metre of a medium whose
    transmittance after `distance` metres is `color` (3,) in (0, 1]:
    exp(-sigma_a d) = color, so sigma_a = -ln(color) / d (Beer-Lambert; the
    "transmission colour at depth" of other renderers)."""
    return -np.log(np.asarray(color, dtype=np.float64)) / distance


def volume_absorption(color, density: float) -> np.ndarray:
    """Absorption coefficient (3,) per metre of Blender's Volume Absorption
    node: sigma_a = density * (1 - color), colour and density clamped at 0
    (Cycles `svm_node_closure_volume` in kernel/svm/closure.h; EEVEE's
    gpu_shader_material_volume_absorption.glsl)."""
    return max(float(density), 0.0) * (1.0 - np.maximum(np.asarray(color, dtype=np.float64), 0.0))
