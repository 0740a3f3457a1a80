"""Samples of a lamp as seen from surface points, for shadow rays (the
SampleLi of pbrt-v4's lights): a point on the lamp, or a direction of a
sun's disc, with the estimate of the irradiance it brings. The mean over a
lamp's samples, each times the receiver's cosine, is the lamp's irradiance
on the surface, shadows aside; a lamp of size 0 (radiometry.is_delta)
needs one sample and gives it exactly."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling.warps import concentric_disc, cone_directions, frames
from ..scene import AreaLight, Light, PointLight, SpotLight, SunLight
from ..util.vectors import DIVISION_FLOOR, dot, length
from . import radiometry


@dataclass
class LampSample:
    """One sample of a lamp for n surface points.

    dirs        (n,3) unit, from each point toward the sample
    dist        (n,) the distance a shadow ray must clear
    irradiance  (n,3) W/m^2 estimate, to be times the receiver's cosine
                with `dirs` (0 where the sample sends nothing)
    """

    dirs: np.ndarray
    dist: np.ndarray
    irradiance: np.ndarray


def sample_lamp(light: Light, energy: float, points: np.ndarray, uv: np.ndarray, far: float) -> LampSample:
    """A sample of `light` for each of `points (n,3)` at `uv (n,2)` in the
    unit square (ignored by lamps of size 0)."""
    if isinstance(light, SunLight):
        return _sun(light, energy, points, uv, far)
    if isinstance(light, AreaLight):
        return _area(light, energy, points, uv, far)
    if light.radius <= 0.0:
        offset = light.position - points
        dist = length(offset)
        dirs = offset / np.maximum(dist, DIVISION_FLOOR)[:, None]
        irradiance = radiometry.intensity(light, energy, -dirs) / np.maximum(dist * dist, DIVISION_FLOOR)[:, None]
        return LampSample(dirs, dist, irradiance)
    if light.soft_falloff:
        return _facing_disc(light, energy, points, uv)
    return _sphere(light, energy, points, uv)


def apparent_size(light: Light, points: np.ndarray) -> np.ndarray:
    """(n,) radians: the angle the lamp spans as seen from `points (n,3)`,
    2 atan(half-extent / distance) (the diagonal for an area lamp), a sun's
    angle, 0 for a lamp of size 0."""
    if isinstance(light, SunLight):
        return np.full(len(points), light.angle)
    if isinstance(light, AreaLight):
        half = math.hypot(float(np.linalg.norm(light.axis_x)), float(np.linalg.norm(light.axis_y)))
        center = light.center
    else:
        half, center = light.radius, light.position
    return 2.0 * np.arctan(half / np.maximum(length(points - center), DIVISION_FLOOR))


def _spot_mask(light: Light, leaving: np.ndarray) -> np.ndarray:
    """(n,) the spot's cone mask for rays `leaving (n,3)` its sample points
    (Cycles evaluates it per point of the lamp); 1 for a point lamp."""
    return radiometry.spot_attenuation(light, leaving) if isinstance(light, SpotLight) else np.ones(len(leaving))


def _facing_disc(light: PointLight | SpotLight, energy: float, points: np.ndarray, uv: np.ndarray) -> LampSample:
    """Soft Falloff: a disc of the lamp's radius through its centre, facing
    the point, sampled uniformly by area: E = L cos_disc (pi r^2) / t^2."""
    offset = points - light.position
    axis = offset / np.maximum(length(offset), DIVISION_FLOOR)[:, None]
    t, b = frames(axis)
    disc = light.radius * concentric_disc(uv)
    on_lamp = light.position + disc[:, :1] * t + disc[:, 1:] * b
    to_lamp = on_lamp - points
    dist = length(to_lamp)
    dirs = to_lamp / np.maximum(dist, DIVISION_FLOOR)[:, None]
    cos_disc = np.maximum(-dot(dirs, axis), 0.0)
    scale = cos_disc * (math.pi * light.radius ** 2) / np.maximum(dist * dist, DIVISION_FLOOR) * _spot_mask(light, -dirs)
    return LampSample(dirs, dist, radiometry.lamp_radiance(light, energy)[None, :] * scale[:, None])


def _sphere(light: PointLight | SpotLight, energy: float, points: np.ndarray, uv: np.ndarray) -> LampSample:
    """Soft Falloff off: a sphere of uniform radiance, sampled uniformly over
    the cap a point sees, E = L x the cap's solid angle; a point inside it
    sees it everywhere (E = L 4 pi over the uniform sphere of directions)."""
    to_center = light.position - points
    d = length(to_center)
    axis = to_center / np.maximum(d, DIVISION_FLOOR)[:, None]
    inside = d <= light.radius
    cos_max = np.where(inside, -1.0, np.sqrt(np.maximum(0.0, 1.0 - (light.radius / np.maximum(d, DIVISION_FLOOR)) ** 2)))
    dirs = cone_directions(axis, cos_max, uv)
    # the sphere along each direction: the near root outside it, the far one inside
    along = dot(dirs, to_center)
    root = np.sqrt(np.maximum(0.0, along * along - d * d + light.radius ** 2))
    dist = np.where(inside, along + root, along - root)
    solid_angle = 2.0 * math.pi * (1.0 - cos_max)
    # Cycles applies no cone mask to a point inside a spot's sphere
    mask = np.where(inside, 1.0, _spot_mask(light, -dirs))
    return LampSample(dirs, dist, radiometry.lamp_radiance(light, energy)[None, :] * (solid_angle * mask)[:, None])


def _sun(light: SunLight, energy: float, points: np.ndarray, uv: np.ndarray, far: float) -> LampSample:
    """Directions uniform in solid angle over the sun's disc,
    E = L x its solid angle 2 pi (1 - cos h); one direction for angle 0."""
    n = len(points)
    if light.angle <= 0.0:
        return LampSample(np.broadcast_to(-light.direction, points.shape), np.full(n, far),
                          np.broadcast_to(radiometry.sun_irradiance(light, energy), points.shape))
    cos_half = math.cos(0.5 * light.angle)
    dirs = cone_directions(np.broadcast_to(-light.direction, points.shape), np.full(n, cos_half), uv)
    solid_angle = 2.0 * math.pi * (1.0 - cos_half)
    return LampSample(dirs, np.full(n, far), np.broadcast_to(radiometry.sun_radiance(light, energy) * solid_angle,
                                                             points.shape))


def _area(light: AreaLight, energy: float, points: np.ndarray, uv: np.ndarray, far: float) -> LampSample:
    """Points uniform over the lamp's rectangle or ellipse,
    E = L(a) cos_lamp A / t^2, L(a) its radiance at angle a from its normal.
    A spread of 0 is a parallel beam along the normal: E = P / A where the
    point's shadow falls on the lamp."""
    if light.spread <= 0.0:
        return _parallel_area(light, energy, points, far)
    if light.shape == "ELLIPSE":
        xy = concentric_disc(uv)
    else:
        xy = 2.0 * uv - 1.0
    on_lamp = light.center + xy[:, :1] * light.axis_x + xy[:, 1:] * light.axis_y
    to_lamp = on_lamp - points
    dist = length(to_lamp)
    dirs = to_lamp / np.maximum(dist, DIVISION_FLOOR)[:, None]
    cos_lamp = -(dirs @ light.direction)
    weight = (np.maximum(cos_lamp, 0.0) * radiometry.spread_factor(light.spread, cos_lamp) * light.area
              / np.maximum(dist * dist, DIVISION_FLOOR))
    return LampSample(dirs, dist, radiometry.lamp_radiance(light, energy)[None, :] * weight[:, None])


def _parallel_area(light: AreaLight, energy: float, points: np.ndarray, far: float) -> LampSample:
    """Spread 0: light along the lamp's normal, irradiance P / A on a surface
    facing it, inside the lamp's footprint."""
    rel = points - light.center
    upstream = -(rel @ light.direction)
    on_plane = rel + upstream[:, None] * light.direction
    x = (on_plane @ light.axis_x) / max(float(light.axis_x @ light.axis_x), DIVISION_FLOOR)
    y = (on_plane @ light.axis_y) / max(float(light.axis_y @ light.axis_y), DIVISION_FLOOR)
    inside = (x * x + y * y <= 1.0) if light.shape == "ELLIPSE" else (np.abs(x) <= 1.0) & (np.abs(y) <= 1.0)
    lit = inside & (upstream > 0.0)
    irradiance = (light.color * (light.power * energy / light.area))[None, :] * lit[:, None]
    return LampSample(np.broadcast_to(-light.direction, points.shape), np.where(lit, upstream, far), irradiance)
