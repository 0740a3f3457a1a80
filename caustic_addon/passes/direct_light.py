"""Direct light from the lamps at opaque surface points, with shadow rays.

Radiance leaving a point toward the eye, per lamp of irradiance E at normal
incidence and unit vector l toward it:

    L = E cos(theta_l) * (albedo / pi + specular * (e + 8) / (8 pi) * (n.h)^e)

the Lambert term (what a Cycles Diffuse BSDF returns) plus an
energy-normalised Blinn-Phong lobe (Akenine-Moller et al., Real-Time
Rendering, 4th ed., eq. 9.65 family). A lamp behind the surface gets no
shadow ray. Dielectrics and reflectors block shadow rays: the light they
redirect arrives through the illumination maps.
"""

from __future__ import annotations

import math

import numpy as np

from ..emission import radiometry
from ..scene import Light, SunLight
from ..tracing.accelerator import Accelerator
from ..util.vectors import DIVISION_FLOOR, dot, length, max_channel, normalize


def toward_light(light: Light, energy: float, points: np.ndarray, far: float):
    """For surface `points (n,3)`: unit vectors toward the lamp (n,3), the
    distance a shadow ray must clear (n,), and the irradiance (n,3) W/m^2 on a
    surface facing the lamp."""
    if isinstance(light, SunLight):
        to_light = np.broadcast_to(-light.direction, points.shape)
        return to_light, np.full(len(points), far), np.broadcast_to(
            radiometry.sun_irradiance(light, energy), points.shape)
    offset = light.position - points
    dist = length(offset)
    to_light = offset / np.maximum(dist, DIVISION_FLOOR)[:, None]
    intensity = radiometry.intensity(light, energy, -to_light)
    return to_light, dist, intensity / np.maximum(dist * dist, DIVISION_FLOOR)[:, None]


def direct_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                    shading: np.ndarray, facing: np.ndarray, view: np.ndarray, albedo: np.ndarray,
                    specular: np.ndarray, exponent: np.ndarray, far: float) -> np.ndarray:
    """Radiance (n,3) toward the eye from all lamps' direct light.

    shading, facing   (n,3) shading and geometric normals, both on the eye's side
    view              (n,3) unit vectors from the points toward the eye
    albedo, specular  (n,3); exponent (n,)
    """
    out = np.zeros((len(points), 3))
    for light in lights:
        to_light, dist, irradiance = toward_light(light, energy, points, far)
        cos = dot(shading, to_light)
        lit = (cos > 0.0) & (dot(facing, to_light) > 0.0) & (max_channel(irradiance) > 0.0)
        if not lit.any():
            continue
        idx = np.flatnonzero(lit)
        origins = accel.offset(points[idx], facing[idx], to_light[idx])
        blocked = accel.occluded(origins, to_light[idx], dist[idx] - 2.0 * accel.epsilon)
        idx = idx[~blocked]
        if len(idx) == 0:
            continue
        half = normalize(to_light[idx] + view[idx])
        n_dot_h = np.clip(dot(shading[idx], half), 0.0, 1.0)
        e = exponent[idx]
        lobe = specular[idx] * ((e + 8.0) / (8.0 * math.pi) * n_dot_h ** e)[:, None]
        out[idx] += irradiance[idx] * cos[idx, None] * (albedo[idx] / math.pi + lobe)
    return out
