"""Blender's light units, turned into radiometric quantities, as Cycles 4.x
and 5.x evaluate them (read in `intern/cycles/scene/light.cpp`,
`kernel/light/{point,spot,sun,area}.h` and `blender/light.cpp` of Blender
4.2, 4.5 and 5.3, and checked against Cycles renders of a diffuse plane,
each within 0.1%):

- Every lamp's colour is color x temperature colour x 2^exposure (the last
  two Blender 4.5+); the add-on folds them into `color` and `power`.
- Point lamp of Power P W: radiant intensity I = colour P / (4 pi) W/sr in
  every direction. With a radius r and Soft Falloff (the default) it is a
  disc of radius r that faces each point it lights, of radiance
  L = colour P / (4 pi^2 r^2): on its axis E = P / (4 pi (d^2 + r^2)).
  Without Soft Falloff it is a sphere of the same radiance, whose
  irradiance is the point lamp's wherever all of it is above the horizon.
- Spot lamp: the point lamp's intensity (the cone does not concentrate
  the power), times, for each point of the lamp,
      smoothstep((cos(theta) - cos(size/2)) / ((1 - cos(size/2)) blend)).
- Sun of Strength S: irradiance colour S W/m^2 on a surface facing it. With
  an Angle, its radiance is uniform over the cone of half-angle
  h = angle / 2: L = colour S / (pi sin^2 h).
- Area lamp of Power P and area A: one-sided Lambertian, radiance
  L = colour P / (pi A) along its normal's side (total flux P; there is no
  factor 1/4 since Cycles 4.0). Spread s narrows it: L is multiplied by
      max((tan(s/2) - tan a) / (tan(s/2) - s/2), 0)
  at angle a from the normal (Cycles' soft-box model; 3 / (s/2)^3 replaces
  1 / (tan(s/2) - s/2) below s/2 = 0.05), which keeps the flux P.
- World: a Background of Color and Strength is radiance Color x Strength.
- A Lambertian surface of albedo rho under irradiance E has radiance
  rho E / pi, what a Cycles Diffuse BSDF returns.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene import AreaLight, Light, SpotLight, SunLight


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


def spread_factor(spread: float, cos_a: np.ndarray) -> np.ndarray:
    """(n,) Cycles' spread weight of an area lamp's radiance at cos_a (n,)
    of the angle from its normal: 1 for a full spread of pi."""
    half = 0.5 * spread
    if half >= 0.5 * math.pi - 1e-9:
        return np.ones_like(cos_a)
    if half <= 0.0:
        # a parallel beam along the normal: no finite radiance off it
        return np.zeros_like(cos_a)
    tan_half = math.tan(half)
    normalise = 1.0 / (tan_half - half) if half > 0.05 else 3.0 / half ** 3
    with np.errstate(divide="ignore", invalid="ignore"):
        tan_a = np.sqrt(np.maximum(0.0, 1.0 - cos_a * cos_a)) / cos_a
    return np.where(cos_a > 0.0, np.maximum((tan_half - tan_a) * normalise, 0.0), 0.0)


def intensity(light: Light, energy: float, dirs: np.ndarray) -> np.ndarray:
    """Radiant intensity (n,3) W/sr toward unit `dirs (n,3)` of a point, spot
    or area lamp, seen from afar (an area lamp: L A cos(a) times its spread
    weight)."""
    if isinstance(light, AreaLight):
        cos_a = dirs @ light.direction
        lobe = np.maximum(cos_a, 0.0) * spread_factor(light.spread, cos_a) / math.pi
        return (light.color * (light.power * energy))[None, :] * lobe[:, None]
    i = point_intensity(light.power * energy, light.color)[None, :]
    if isinstance(light, SpotLight):
        return i * spot_attenuation(light, dirs)[:, None]
    return np.broadcast_to(i, (len(dirs), 3))


def sun_irradiance(light: SunLight, energy: float) -> np.ndarray:
    """Irradiance (3,) W/m^2 of a sun on a surface facing it."""
    return light.color * (light.strength * energy)


def sun_radiance(light: SunLight, energy: float) -> np.ndarray:
    """Radiance (3,) over the disc of a sun with an angle: S / (pi sin^2 h)."""
    return sun_irradiance(light, energy) / (math.pi * math.sin(0.5 * light.angle) ** 2)


def lamp_radiance(light: Light, energy: float) -> np.ndarray:
    """Radiance (3,) of a sized point or spot lamp's disc or sphere,
    P / (4 pi^2 r^2), or of an area lamp along its normal, P / (pi A)."""
    if isinstance(light, AreaLight):
        return light.color * (light.power * energy / (math.pi * light.area))
    return light.color * (light.power * energy / (4.0 * math.pi ** 2 * light.radius ** 2))


def is_delta(light: Light) -> bool:
    """The lamp is a point or a single direction: one shadow ray sees all of it."""
    if isinstance(light, SunLight):
        return light.angle <= 0.0
    if isinstance(light, AreaLight):
        return light.spread <= 0.0
    return light.radius <= 0.0
