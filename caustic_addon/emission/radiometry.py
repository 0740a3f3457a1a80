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

from ..scene import AreaLight, Light, MeshLight, SpotLight, SunLight
from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import dot1, row


def point_intensity(power: float, color: np.ndarray) -> np.ndarray:
    """Radiant intensity (3,) W/sr of a Blender point or spot lamp of `power` W."""
    return np.asarray(color, dtype=np.float64) * (power / (4.0 * math.pi))


@inline
def smoothstep1(x):
    """Cycles' smoothstepf: 0 below 0, 1 above 1, 3x^2 - 2x^3 between."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


@inline
def spot_attenuation1(cos_theta, cos_half, blend):
    """A spot lamp's cone mask for a direction leaving it at cos_theta from
    its axis, cos_half = cos(Spot Size / 2) (Cycles' `spot_attenuation`):
    smoothstep((cos_theta - cos_half) / ((1 - cos_half) blend)), a hard
    edge (cos_theta > cos_half) at Blend 0."""
    if blend <= 0.0:
        return 1.0 if cos_theta > cos_half else 0.0
    return smoothstep1((cos_theta - cos_half) / ((1.0 - cos_half) * blend))


@inline
def spread_factor1(spread, cos_a):
    """Cycles' spread weight of an area lamp's radiance at cos_a of the
    angle a from its normal, for a Spread of `spread` radians (its soft-box
    model): max((tan(s/2) - tan a) / (tan(s/2) - s/2), 0), with 3 / (s/2)^3
    for 1 / (tan(s/2) - s/2) below s/2 = 0.05; 1 at a full spread of pi, 0
    behind the lamp and, at a spread of 0 (a parallel beam along the
    normal), everywhere: there is no finite radiance off the normal."""
    half = 0.5 * spread
    if half >= 0.5 * math.pi - 1e-9:
        return 1.0
    if half <= 0.0 or not cos_a > 0.0:
        return 0.0
    tan_half = math.tan(half)
    normalise = 1.0 / (tan_half - half) if half > 0.05 else 3.0 / math.pow(half, 3.0)
    tan_a = math.sqrt(max(0.0, 1.0 - cos_a * cos_a)) / cos_a
    return max((tan_half - tan_a) * normalise, 0.0)


def spot_attenuation(light: SpotLight, dirs: np.ndarray) -> np.ndarray:
    """(n,) spot_attenuation1 of a spot lamp for unit directions `dirs (n,3)` leaving it."""
    out = np.empty(len(dirs))
    _spot_values(out, contiguous(dirs, np.float64), contiguous(light.direction, np.float64),
                 math.cos(0.5 * light.spot_size), float(light.blend))
    return out


def spread_factor(spread: float, cos_a: np.ndarray) -> np.ndarray:
    """(n,) spread_factor1 of an area lamp of `spread` at each of `cos_a (n,)`."""
    out = np.empty(len(cos_a))
    _spread_values(out, float(spread), contiguous(cos_a, np.float64))
    return out


@kernel("void(f8[::1], f8[:, ::1], f8[::1], f8, f8)")
def _spot_values(out, dirs, axis, cos_half, blend):
    for i in range(len(dirs)):
        out[i] = spot_attenuation1(dot1(row(dirs, i), (axis[0], axis[1], axis[2])), cos_half, blend)


@kernel("void(f8[::1], f8, f8[::1])")
def _spread_values(out, spread, cos_a):
    for i in range(len(cos_a)):
        out[i] = spread_factor1(spread, cos_a[i])


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
    return light.color * (light.strength * sun_energy(light, energy))


def sun_energy(light: SunLight, energy: float) -> float:
    """The render's Energy as it scales a sun: not at all for one of the
    world's (SunLight.of_world), as it scales no world."""
    return 1.0 if light.of_world else energy


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
    if isinstance(light, MeshLight):
        return False
    return light.radius <= 0.0
