"""The lamps that eye rays meet: a lamp with a size seen straight on, and
its glint in smooth glass, water and mirrors. Cycles lets rays meet the
lamps themselves (`kernel/light/{area,point,distant}.h`, *_intersect):

- an area lamp is its rectangle or ellipse, seen from its front only, of
  radiance colour P / (pi A) times its spread weight at the angle the ray
  makes with its normal (radiometry.spread_factor1);
- a point or spot lamp of radius r is, with Soft Falloff, the disc of
  radius r about its centre that faces the ray's origin, and without it
  the sphere of radius r, both of radiance colour P / (4 pi^2 r^2), a
  spot's times its cone mask for the ray's direction reversed;
- a sun of angle 2h is its disc of directions, seen by rays that leave the
  scene, of radiance colour S / (pi sin^2 h).

Lamps hide nothing: a ray sees every lamp in front of what it meets. Each
lamp is seen by the kinds of ray its Ray Visibility allows (Camera,
Glossy, Transmission; in Blender a lamp is not seen by the camera until
its Camera box is ticked). Lamps of size 0 are never met.

Rays drawn from a rough lobe meet a lamp as one of two strategies for its
light (passes/direct_light.py): given their density, each lamp's radiance
is weighed by the power heuristic against the density its own samples
draw that direction with (emission/lamp_samples.py), times how many of
them there are to each lobe ray."""

from __future__ import annotations

import math

import numpy as np

from ..emission import radiometry
from ..emission.lamp_samples import area_lamp_pdf1, area_pdf1, cone_pdf1
from ..emission.radiometry import spot_attenuation1, spread_factor1
from ..sampling.mis import power_heuristic1
from ..scene import AreaLight, Light, SpotLight, SunLight
from ..tracing.accelerator import CAMERA, REFLECTED, REFRACTED
from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import dot1, row


def seen_by(light: Light, kind: np.ndarray) -> np.ndarray:
    """(n,) bool: whether rays of `kind (n,)` (CAMERA, REFLECTED,
    REFRACTED) see `light`, by its ray visibility."""
    flags = np.zeros(max(CAMERA, REFLECTED, REFRACTED) + 1, dtype=bool)
    flags[[CAMERA, REFLECTED, REFRACTED]] = (light.visibility.camera, light.visibility.glossy,
                                             light.visibility.transmission)
    return flags[kind]


def lamps_met(lights: list[Light], energy: float, origins: np.ndarray, dirs: np.ndarray, reach: np.ndarray,
              kind: np.ndarray, drawn_pdf: np.ndarray | None = None, lamp_draws: int = 1) -> np.ndarray:
    """(n,3) radiance W/(m^2 sr) of the lamps with a size that rays from
    `origins (n,3)` along unit `dirs (n,3)` of `kind (n,)` meet before
    `reach (n,)` (inf where they leave the scene). Rays a lobe drew with
    density `drawn_pdf (n,)` (inf: a smooth surface's, or the camera's)
    take each lamp's radiance times p^2 / (p^2 + (lamp_draws p_lamp)^2),
    p_lamp the density of its samples, `lamp_draws` to each ray (Veach 1997,
    the power heuristic); what an area lamp of spread 0 sends along its one
    direction is left to its samples."""
    out = np.zeros((len(dirs), 3))
    origins, dirs, reach = contiguous(origins, np.float64), contiguous(dirs, np.float64), contiguous(reach, np.float64)
    drawn = np.zeros(0) if drawn_pdf is None else contiguous(drawn_pdf, np.float64)
    for light in lights:
        if radiometry.is_delta(light):
            continue
        rows = np.flatnonzero(seen_by(light, kind))
        if not len(rows):
            continue
        if isinstance(light, SunLight):
            _sun_met(out, dirs, reach, rows, contiguous(-light.direction, np.float64), math.cos(0.5 * light.angle),
                     radiometry.sun_radiance(light, energy), drawn, lamp_draws)
        elif isinstance(light, AreaLight):
            _area_met(out, origins, dirs, reach, rows, *(contiguous(v, np.float64) for v in (
                light.center, light.axis_x, light.axis_y, light.direction)), light.shape == "ELLIPSE",
                float(light.spread), float(light.area), radiometry.lamp_radiance(light, energy), drawn, lamp_draws)
        else:
            spot = isinstance(light, SpotLight)
            _point_met(out, origins, dirs, reach, rows, contiguous(light.position, np.float64), float(light.radius),
                       bool(light.soft_falloff), radiometry.lamp_radiance(light, energy), spot,
                       contiguous(light.direction if spot else np.zeros(3), np.float64),
                       math.cos(0.5 * light.spot_size) if spot else 1.0, float(light.blend) if spot else 0.0, drawn,
                       lamp_draws)
    return out


@inline
def _lobe_drawn1(drawn, i):
    """Whether row i's ray was drawn from a rough lobe: `drawn` is not (0,)
    and drawn[i] is finite (the lamp's own density then weighs it)."""
    return len(drawn) > 0 and drawn[i] < math.inf


@inline
def _drawn_share1(p, lamp_pdf, lamp_draws):
    """The power heuristic's weight of a ray drawn with density `p` against
    `lamp_draws` samples of a lamp of density `lamp_pdf`; 0 where
    `lamp_pdf` is inf."""
    if lamp_pdf == math.inf or not p > 0.0:
        return 0.0
    return power_heuristic1(1.0, p, lamp_draws, lamp_pdf)


@kernel("void(f8[:, ::1], f8[:, ::1], f8[::1], i8[::1], f8[::1], f8, f8[::1], f8[::1], i8)")
def _sun_met(out, dirs, reach, rows, toward, cos_half, radiance, drawn, lamp_draws):
    """The sun's disc, `toward (3,)` unit, half-angle acos(cos_half), in the
    directions of the rows that leave the scene."""
    for i in rows:
        if reach[i] == math.inf and dot1(row(dirs, i), (toward[0], toward[1], toward[2])) >= cos_half:
            weight = _drawn_share1(drawn[i], cone_pdf1(cos_half), lamp_draws) if _lobe_drawn1(drawn, i) else 1.0
            for c in range(3):
                out[i, c] += radiance[c] * weight


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], i8[::1], f8[::1], f8[::1], f8[::1], f8[::1], b1, f8,"
        " f8, f8[::1], f8[::1], i8)")
def _area_met(out, origins, dirs, reach, rows, center, axis_x, axis_y, normal, ellipse, spread, area, radiance,
              drawn, lamp_draws):
    """The area lamp: the plane of its axes, met in front of its emitting
    side; the point's coordinates (x, y) along the half-axes, by their
    Gram matrix, inside the unit square or, for an `ellipse`, disc."""
    plane = (axis_x[1] * axis_y[2] - axis_x[2] * axis_y[1], axis_x[2] * axis_y[0] - axis_x[0] * axis_y[2],
             axis_x[0] * axis_y[1] - axis_x[1] * axis_y[0])
    ax, ay = (axis_x[0], axis_x[1], axis_x[2]), (axis_y[0], axis_y[1], axis_y[2])
    xx, xy, yy = dot1(ax, ax), dot1(ax, ay), dot1(ay, ay)
    det = xx * yy - xy * xy
    if det <= 0.0:
        return
    n = (normal[0], normal[1], normal[2])
    for i in rows:
        d = row(dirs, i)
        cos_a = -dot1(d, n)
        across = dot1(d, plane)
        if cos_a <= 0.0 or across == 0.0:
            continue
        to_center = (center[0] - origins[i, 0], center[1] - origins[i, 1], center[2] - origins[i, 2])
        t = dot1(to_center, plane) / across
        if not 0.0 < t < reach[i]:
            continue
        q = (t * d[0] - to_center[0], t * d[1] - to_center[1], t * d[2] - to_center[2])
        qx, qy = dot1(q, ax), dot1(q, ay)
        x, y = (yy * qx - xy * qy) / det, (xx * qy - xy * qx) / det
        inside = x * x + y * y <= 1.0 if ellipse else abs(x) <= 1.0 and abs(y) <= 1.0
        if inside:
            weight = spread_factor1(spread, cos_a)
            if _lobe_drawn1(drawn, i):
                origin = (origins[i, 0], origins[i, 1], origins[i, 2])
                lamp_pdf = (area_lamp_pdf1(origin, t, cos_a, ellipse, center, axis_x, axis_y, area) if spread > 0.0
                            else math.inf)
                weight *= _drawn_share1(drawn[i], lamp_pdf, lamp_draws)
            for c in range(3):
                out[i, c] += radiance[c] * weight


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], i8[::1], f8[::1], f8, b1, f8[::1], b1, f8[::1], f8, f8,"
        " f8[::1], i8)")
def _point_met(out, origins, dirs, reach, rows, position, radius, facing_disc, radiance, masked, axis, cos_half,
               blend, drawn, lamp_draws):
    """A point or spot lamp of `radius`: the disc about `position` that
    faces the ray's origin (`facing_disc`: Soft Falloff) or the sphere, met
    in front of the origin; a spot's cone mask along the ray, reversed."""
    for i in rows:
        d = row(dirs, i)
        to_center = (position[0] - origins[i, 0], position[1] - origins[i, 1], position[2] - origins[i, 2])
        dist2 = dot1(to_center, to_center)
        along = dot1(to_center, d)
        if facing_disc:
            # the plane through the centre square to the centre's direction
            if along <= 0.0:
                continue
            t = dist2 / along
            miss2 = t * t - dist2
            lamp_pdf = area_pdf1(t, along / math.sqrt(dist2), math.pi * radius * radius)
        else:
            miss2 = dist2 - along * along
            if miss2 > radius * radius:
                continue
            # the near root, or the far one from inside the sphere
            root = math.sqrt(radius * radius - miss2)
            t = along + root if dist2 <= radius * radius else along - root
            miss2 = 0.0
            lamp_pdf = cone_pdf1(-1.0 if dist2 <= radius * radius else math.sqrt(1.0 - radius * radius / dist2))
        if miss2 > radius * radius or not 0.0 < t < reach[i]:
            continue
        weight = _drawn_share1(drawn[i], lamp_pdf, lamp_draws) if _lobe_drawn1(drawn, i) else 1.0
        if masked:
            weight *= spot_attenuation1(-dot1(d, (axis[0], axis[1], axis[2])), cos_half, blend)
        for c in range(3):
            out[i, c] += radiance[c] * weight
