"""Blender's light units, turned into radiometric quantities.

Source: Cycles, `intern/cycles/scene/light.cpp` (the light's strength is
colour * power, times 1/(4 pi) for point and spot lamps) and
`intern/cycles/kernel/light/spot.h` (the spot cone's smooth edge). With a lamp
radius of 0 Cycles evaluates intensity / t^2, so a lamp of Power P watts is an
isotropic point source of radiant intensity

    I = colour * P / (4 pi)   [W/sr]

A spot lamp has the same intensity inside its cone (the cone does not
concentrate the power), times

    smoothstep((cos(theta) - cos(size/2)) / ((1 - cos(size/2)) * blend))

A sun of Strength S gives irradiance colour * S [W/m^2] on a surface facing it.
A Lambertian surface of albedo rho under irradiance E has radiance rho E / pi,
which is what a Cycles Diffuse BSDF returns. Blender 4.5+ also multiplies
every lamp by 2^exposure; the add-on folds that into `power`.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene import Light, SpotLight, SunLight


def point_intensity(power: float, color: np.ndarray) -> np.ndarray:
    """Radiant intensity (3,) W/sr of a Blender point or spot lamp of `power` W."""
    return np.asarray(color, dtype=np.float64) * (power / (4.0 * math.pi))


def smoothstep(x: np.ndarray) -> np.ndarray:
    """Cycles' smoothstepf: 0 below 0, 1 above 1, 3x^2 - 2x^3 between."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def spot_attenuation(light: SpotLight, dirs: np.ndarray) -> np.ndarray:
    """Cone mask (n,) of a spot lamp for unit directions `dirs (n,3)` leaving it."""
    cos_theta = dirs @ light.direction
    cos_half = math.cos(0.5 * light.spot_size)
    if light.blend <= 0.0:
        return (cos_theta > cos_half).astype(np.float64)
    return smoothstep((cos_theta - cos_half) / ((1.0 - cos_half) * light.blend))


def intensity(light: Light, energy: float, dirs: np.ndarray) -> np.ndarray:
    """Radiant intensity (n,3) W/sr of a point or spot lamp toward `dirs (n,3)`."""
    i = point_intensity(light.power * energy, light.color)[None, :]
    if isinstance(light, SpotLight):
        return i * spot_attenuation(light, dirs)[:, None]
    return np.broadcast_to(i, (len(dirs), 3))


def sun_irradiance(light: SunLight, energy: float) -> np.ndarray:
    """Irradiance (3,) W/m^2 of a sun on a surface facing it."""
    return light.color * (light.strength * energy)
