"""Samples of a lamp as seen from surface points, for shadow rays (the
SampleLi of pbrt-v4's lights): a point on the lamp, or a direction of a
sun's disc, with the estimate of the irradiance it brings. The mean over a
lamp's samples, each times the receiver's cosine, is the lamp's irradiance
on the surface, shadows aside; a lamp of size 0 (radiometry.is_delta)
needs one sample and gives it exactly. Each sample carries the solid-angle
density its direction was drawn with, which multiple importance sampling
weighs against a lobe's (passes/direct_light.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling.spherical_rectangle import SMALLEST, spherical_rectangle1, spherical_rectangle_point1
from ..sampling.warps import concentric_disc1, cone_direction1, cone_directions, orthonormal_basis1
from ..scene import AreaLight, Light, MeshLight, PointLight, SpotLight, SunLight
from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import DIVISION_FLOOR, dot1, row, set_row
from . import radiometry
from .radiometry import spot_attenuation1, spread_factor1


@dataclass
class LampSample:
    """One sample of a lamp for n surface points.

    dirs        (n,3) unit, from each point toward the sample
    dist        (n,) the distance a shadow ray must clear
    irradiance  (n,3) W/m^2 estimate, to be times the receiver's cosine
                with `dirs` (0 where the sample sends nothing)
    pdf         (n,) 1/sr, the density of drawing `dirs` (pbrt-v4's PDF_Li);
                inf for a lamp or sun of size 0, and for a mesh light,
                which no lobe's rays meet as a lamp
    """

    dirs: np.ndarray
    dist: np.ndarray
    irradiance: np.ndarray
    pdf: np.ndarray


def sample_lamp(light: Light, energy: float, points: np.ndarray, uv: np.ndarray, far: float) -> LampSample:
    """A sample of `light` for each of `points (n,3)` at `uv (n,2)` in the
    unit square (ignored by lamps of size 0)."""
    points, uv = contiguous(points, np.float64), contiguous(uv, np.float64)
    n = len(points)
    out = LampSample(np.empty((n, 3)), np.empty(n), np.empty((n, 3)), np.full(n, np.inf))
    if isinstance(light, SunLight):
        _sun(light, energy, uv, far, out)
    elif isinstance(light, MeshLight):
        _mesh_samples(out.dirs, out.dist, out.irradiance, points, uv, light.triangles, light.area_cdf,
                      float(light.areas.sum()), light.radiance * energy)
    elif isinstance(light, AreaLight):
        if light.spread <= 0.0:
            _parallel_area_samples(out.dirs, out.dist, out.irradiance, points, *_area_frame(light),
                                   light.shape == "ELLIPSE", light.color * (light.power * energy / light.area), far)
        else:
            _area_samples(out.dirs, out.dist, out.irradiance, out.pdf, points, uv, *_area_frame(light),
                          light.shape == "ELLIPSE", float(light.spread), float(light.area),
                          radiometry.lamp_radiance(light, energy))
    elif light.radius <= 0.0:
        _point_samples(out.dirs, out.dist, out.irradiance, points, _position(light),
                       radiometry.point_intensity(light.power * energy, light.color), *_cone(light))
    else:
        sampler = _facing_disc_samples if light.soft_falloff else _sphere_samples
        sampler(out.dirs, out.dist, out.irradiance, out.pdf, points, uv, _position(light), float(light.radius),
                radiometry.lamp_radiance(light, energy), *_cone(light))
    return out


def apparent_size(light: Light, points: np.ndarray) -> np.ndarray:
    """(n,) radians: the angle the lamp spans as seen from `points (n,3)`,
    2 atan(half-extent / distance) (the diagonal for an area lamp, the reach
    from its centroid for a mesh light), a sun's angle, 0 for a lamp of size 0."""
    if isinstance(light, SunLight):
        return np.full(len(points), light.angle)
    if isinstance(light, AreaLight):
        half = math.hypot(float(np.linalg.norm(light.axis_x)), float(np.linalg.norm(light.axis_y)))
        center = light.center
    elif isinstance(light, MeshLight):
        half, center = light.radius, light.position
    else:
        half, center = light.radius, light.position
    out = np.empty(len(points))
    _apparent_sizes(out, contiguous(points, np.float64), contiguous(center, np.float64), float(half))
    return out


def _position(light: PointLight | SpotLight) -> np.ndarray:
    return contiguous(light.position, np.float64)


def _cone(light: PointLight | SpotLight) -> tuple:
    """(masked, axis (3,), cos_half, blend): a spot's cone mask
    (radiometry.spot_attenuation1), evaluated per point of the lamp as
    Cycles does; masked False for a point lamp."""
    if isinstance(light, SpotLight):
        return True, contiguous(light.direction, np.float64), math.cos(0.5 * light.spot_size), float(light.blend)
    return False, np.zeros(3), 1.0, 0.0


def _area_frame(light: AreaLight) -> tuple:
    """(center, axis_x, axis_y, direction), each (3,) C-contiguous float64."""
    return tuple(contiguous(v, np.float64) for v in (light.center, light.axis_x, light.axis_y, light.direction))


def _sun(light: SunLight, energy: float, uv: np.ndarray, far: float, out: LampSample) -> None:
    """Directions uniform in solid angle over the sun's disc,
    E = L x its solid angle 2 pi (1 - cos h); one direction for angle 0."""
    if light.angle <= 0.0:
        out.dirs[:], out.irradiance[:] = -light.direction, radiometry.sun_irradiance(light, energy)
    else:
        cos_half = math.cos(0.5 * light.angle)
        out.dirs[:] = cone_directions(-light.direction, cos_half, uv)
        out.irradiance[:] = radiometry.sun_radiance(light, energy) * (2.0 * math.pi * (1.0 - cos_half))
        out.pdf[:] = cone_pdf1.py_func(cos_half)
    out.dist[:] = far


@inline
def cone_pdf1(cos_max):
    """1/sr: the density of directions drawn uniformly over a cone of
    half-angle acos(cos_max), 1 / (2 pi (1 - cos_max))."""
    return 1.0 / max(2.0 * math.pi * (1.0 - cos_max), DIVISION_FLOOR)


@inline
def area_pdf1(dist, cos_lamp, area):
    """1/sr: the solid-angle density of a point drawn uniformly over a
    lamp's `area`, seen at `dist` and at cosine `cos_lamp` to its normal,
    t^2 / (A cos) (pbrt-v4, 4.2.3); inf edge-on or from behind."""
    if cos_lamp <= 0.0:
        return math.inf
    return dist * dist / (area * cos_lamp)


@inline
def _rectangle1(ellipse, center, axis_x, axis_y):
    """(whether an area lamp of half-axes `axis_x, axis_y (3,)` about
    `center (3,)` is a rectangle with square corners, its corner, its two
    edges), the 3-tuples that spherical_rectangle1 takes."""
    ax, ay = (axis_x[0], axis_x[1], axis_x[2]), (axis_y[0], axis_y[1], axis_y[2])
    square = not ellipse and abs(dot1(ax, ay)) <= 1e-6 * math.sqrt(dot1(ax, ax) * dot1(ay, ay))
    corner = (center[0] - ax[0] - ay[0], center[1] - ax[1] - ay[1], center[2] - ax[2] - ay[2])
    return square, corner, (2.0 * ax[0], 2.0 * ax[1], 2.0 * ax[2]), (2.0 * ay[0], 2.0 * ay[1], 2.0 * ay[2])


@inline
def _area_point_drawn1(point, u, v, square, corner, edge_x, edge_y, ellipse, center, axis_x, axis_y):
    """(the 3-tuple point of an area lamp at (u, v) of the unit square, seen
    from the 3-tuple `point`, and the solid angle S it was drawn uniformly
    over, or 0 where it was drawn uniformly by area): _area_samples' choice."""
    if square:
        rect = spherical_rectangle1(point, corner, edge_x, edge_y)
        if rect[0] > SMALLEST:
            return spherical_rectangle_point1(point, rect, u, v), rect[0]
    return area_point1(u, v, ellipse, center, axis_x, axis_y), 0.0


@inline
def area_lamp_pdf1(origin, dist, cos_lamp, ellipse, center, axis_x, axis_y, area):
    """1/sr: the density _area_samples draws the direction toward a point
    of an area lamp with, seen from the 3-tuple `origin` at `dist` and
    cosine `cos_lamp`: 1 / S by solid angle, else area_pdf1."""
    square, corner, edge_x, edge_y = _rectangle1(ellipse, center, axis_x, axis_y)
    if square:
        solid_angle = spherical_rectangle1(origin, corner, edge_x, edge_y)[0]
        if solid_angle > SMALLEST:
            return 1.0 / solid_angle
    return area_pdf1(dist, cos_lamp, area)


@inline
def area_point1(u, v, ellipse, center, axis_x, axis_y):
    """The 3-tuple point (u, v) of the unit square on an area lamp:
    center + x axis_x + y axis_y, (x, y) = concentric_disc1(u, v) on its
    `ellipse`, else (2u - 1, 2v - 1) on its rectangle (uniform by area)."""
    if ellipse:
        x, y = concentric_disc1(u, v)
    else:
        x, y = 2.0 * u - 1.0, 2.0 * v - 1.0
    return (center[0] + x * axis_x[0] + y * axis_y[0], center[1] + x * axis_x[1] + y * axis_y[1],
            center[2] + x * axis_x[2] + y * axis_y[2])


@inline
def facing_disc_point1(u, v, at, radius, normal):
    """The 3-tuple point (u, v) of the unit square on the disc of `radius`
    about the 3-tuple `at` square to the unit `normal`: at + r (x t + y b),
    (x, y) = concentric_disc1(u, v), (t, b) orthonormal_basis1(normal)
    (uniform by area)."""
    t, b = orthonormal_basis1(normal)
    x, y = concentric_disc1(u, v)
    x, y = radius * x, radius * y
    return at[0] + x * t[0] + y * b[0], at[1] + x * t[1] + y * b[1], at[2] + x * t[2] + y * b[2]


@inline
def _toward1(points, i, target):
    """(unit 3-tuple direction, distance) from row i of `points (n,3)` to
    the 3-tuple `target`."""
    offset = (target[0] - points[i, 0], target[1] - points[i, 1], target[2] - points[i, 2])
    dist = math.sqrt(dot1(offset, offset))
    floor = max(dist, DIVISION_FLOOR)
    return (offset[0] / floor, offset[1] / floor, offset[2] / floor), dist


@inline
def _mask1(masked, leaving, axis, cos_half, blend):
    """The spot's cone mask for the unit 3-tuple `leaving` a point of it
    (radiometry.spot_attenuation1); 1 where not `masked`."""
    if not masked:
        return 1.0
    return spot_attenuation1(dot1(leaving, (axis[0], axis[1], axis[2])), cos_half, blend)


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], b1, f8[::1], f8, f8)")
def _point_samples(dirs, dist, irradiance, points, position, intensity, masked, axis, cos_half, blend):
    """A lamp of size 0 of radiant intensity `intensity (3,)` W/sr (a spot's
    times its mask): E = I / d^2 at distance d."""
    at = (position[0], position[1], position[2])
    for i in range(len(points)):
        l, d = _toward1(points, i, at)
        set_row(dirs, i, l)
        dist[i] = d
        mask = _mask1(masked, (-l[0], -l[1], -l[2]), axis, cos_half, blend)
        d2 = max(d * d, DIVISION_FLOOR)
        for c in range(3):
            irradiance[i, c] = intensity[c] * mask / d2


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8, f8[::1], b1, f8[::1], "
        "f8, f8)")
def _facing_disc_samples(dirs, dist, irradiance, pdf, points, uv, position, radius, radiance, masked, axis, cos_half,
                         blend):
    """Soft Falloff: a disc of `radius` through the lamp's centre, facing
    the point, of radiance `radiance (3,)`, sampled uniformly by area
    (facing_disc_point1): E = L cos_disc (pi r^2) / t^2 at distance t, cos_disc
    the disc's cosine toward the point; pdf = area_pdf1(t, cos_disc, pi r^2)."""
    at = (position[0], position[1], position[2])
    area = math.pi * (radius * radius)
    for i in range(len(points)):
        away, _ = _toward1(points, i, at)
        normal = (-away[0], -away[1], -away[2])
        l, d = _toward1(points, i, facing_disc_point1(uv[i, 0], uv[i, 1], at, radius, normal))
        set_row(dirs, i, l)
        dist[i] = d
        cos_disc = max(-dot1(l, normal), 0.0)
        pdf[i] = area_pdf1(d, cos_disc, area)
        scale = cos_disc * area / max(d * d, DIVISION_FLOOR) * _mask1(masked, (-l[0], -l[1], -l[2]), axis,
                                                                       cos_half, blend)
        for c in range(3):
            irradiance[i, c] = radiance[c] * scale


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8, f8[::1], b1, f8[::1], "
        "f8, f8)")
def _sphere_samples(dirs, dist, irradiance, pdf, points, uv, position, radius, radiance, masked, axis, cos_half, blend):
    """Soft Falloff off: a sphere of `radius` and uniform radiance `radiance
    (3,)`, sampled uniformly over the cap a point sees (cone_direction1),
    E = L x the cap's solid angle 2 pi (1 - cos_max), cos_max = sqrt(1 -
    (r/d)^2); a point inside it sees it everywhere (E = L 4 pi over the
    uniform sphere of directions); pdf = cone_pdf1(cos_max). The distance to clear is the sphere's
    near root along the direction, its far one from inside; Cycles applies
    no cone mask to a point inside a spot's sphere."""
    at = (position[0], position[1], position[2])
    for i in range(len(points)):
        toward, d = _toward1(points, i, at)
        inside = d <= radius
        q = radius / max(d, DIVISION_FLOOR)
        cos_max = -1.0 if inside else math.sqrt(max(0.0, 1.0 - q * q))
        pdf[i] = cone_pdf1(cos_max)
        t, b = orthonormal_basis1(toward)
        l = cone_direction1(toward, t, b, cos_max, uv[i, 0], uv[i, 1])
        set_row(dirs, i, l)
        along = dot1(l, (at[0] - points[i, 0], at[1] - points[i, 1], at[2] - points[i, 2]))
        root = math.sqrt(max(0.0, along * along - d * d + radius * radius))
        dist[i] = along + root if inside else along - root
        mask = 1.0 if inside else _mask1(masked, (-l[0], -l[1], -l[2]), axis, cos_half, blend)
        weight = 2.0 * math.pi * (1.0 - cos_max) * mask
        for c in range(3):
            irradiance[i, c] = radiance[c] * weight


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1], "
        "b1, f8, f8, f8[::1])")
def _area_samples(dirs, dist, irradiance, pdf, points, uv, center, axis_x, axis_y, normal, ellipse, spread, area,
                  radiance):
    """Points of an area lamp, L = `radiance (3,)` along the `normal (3,)`,
    s(a) its spread weight (radiometry.spread_factor1) at the angle a from
    it. A rectangle with square corners is drawn uniformly over the solid
    angle S it spans (sampling.spherical_rectangle, as Cycles does):
    E = L s(a) S, pdf = 1 / S; an ellipse, a sheared rectangle or one that
    looks smaller than spherical_rectangle.SMALLEST uniformly by area
    (area_point1): E = L s(a) cos_lamp A / t^2 at distance t, A = `area`,
    pdf = area_pdf1(t, cos_lamp, A)."""
    n = (normal[0], normal[1], normal[2])
    square, corner, edge_x, edge_y = _rectangle1(ellipse, center, axis_x, axis_y)
    for i in range(len(points)):
        target, solid_angle = _area_point_drawn1(row(points, i), uv[i, 0], uv[i, 1], square, corner, edge_x, edge_y,
                                                 ellipse, center, axis_x, axis_y)
        l, d = _toward1(points, i, target)
        set_row(dirs, i, l)
        dist[i] = d
        cos_lamp = -dot1(l, n)
        if solid_angle > 0.0:
            pdf[i] = 1.0 / solid_angle
            weight = solid_angle if cos_lamp > 0.0 else 0.0
        else:
            pdf[i] = area_pdf1(d, cos_lamp, area)
            weight = max(cos_lamp, 0.0) * area / max(d * d, DIVISION_FLOOR)
        weight *= spread_factor1(spread, cos_lamp)
        for c in range(3):
            irradiance[i, c] = radiance[c] * weight


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1], b1, f8[::1], f8)")
def _parallel_area_samples(dirs, dist, irradiance, points, center, axis_x, axis_y, normal, ellipse, flux_density,
                           far):
    """Spread 0: light along the lamp's `normal (3,)`, irradiance P / A =
    `flux_density (3,)` on a surface facing it, at the points whose shadow
    along the normal falls on the lamp, upstream of them (the distance to
    clear); 0 elsewhere."""
    n = (normal[0], normal[1], normal[2])
    ax, ay = (axis_x[0], axis_x[1], axis_x[2]), (axis_y[0], axis_y[1], axis_y[2])
    ax2, ay2 = max(dot1(ax, ax), DIVISION_FLOOR), max(dot1(ay, ay), DIVISION_FLOOR)
    for i in range(len(points)):
        rel = (points[i, 0] - center[0], points[i, 1] - center[1], points[i, 2] - center[2])
        upstream = -dot1(rel, n)
        on_plane = (rel[0] + upstream * n[0], rel[1] + upstream * n[1], rel[2] + upstream * n[2])
        x, y = dot1(on_plane, ax) / ax2, dot1(on_plane, ay) / ay2
        inside = x * x + y * y <= 1.0 if ellipse else abs(x) <= 1.0 and abs(y) <= 1.0
        lit = inside and upstream > 0.0
        set_row(dirs, i, (-n[0], -n[1], -n[2]))
        dist[i] = upstream if lit else far
        for c in range(3):
            irradiance[i, c] = flux_density[c] if lit else 0.0


@kernel("void(f8[::1], f8[:, ::1], f8[::1], f8)")
def _apparent_sizes(out, points, center, half):
    """out (n,) = 2 atan(half / d), d the distance of each of `points (n,3)` from `center (3,)`."""
    at = (center[0], center[1], center[2])
    for i in range(len(points)):
        out[i] = 2.0 * math.atan(half / max(_toward1(points, i, at)[1], DIVISION_FLOOR))


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, :, ::1], f8[::1], f8, f8[::1])")
def _mesh_samples(dirs, dist, irradiance, points, uv, triangles, cdf, area, radiance):
    """Points uniform by area over `triangles (k,3,3)` (`cdf (k,)` their
    areas' running share of `area`): triangle j where u falls in its share
    of the cdf, u rescaled within it, then the point of barycentrics
    (1 - sqrt(u), v sqrt(u)) (Shirley's warp). E = L |cos_light| A / d^2,
    |cos| as either side emits, the pdf being 1 / A."""
    last = len(cdf) - 1
    for i in range(len(points)):
        u = uv[i, 0]
        j = min(np.searchsorted(cdf, u, side="right"), last)
        low = cdf[j - 1] if j > 0 else 0.0
        width = cdf[j] - low
        u = min(max((u - low) / width, 0.0), 1.0) if width > 0.0 else 0.5
        root = math.sqrt(u)
        b0, b1 = 1.0 - root, uv[i, 1] * root
        b2 = 1.0 - b0 - b1
        a, b, c = triangles[j, 0], triangles[j, 1], triangles[j, 2]
        at = (b0 * a[0] + b1 * b[0] + b2 * c[0], b0 * a[1] + b1 * b[1] + b2 * c[1], b0 * a[2] + b1 * b[2] + b2 * c[2])
        e1 = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
        e2 = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
        normal = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        length = max(math.sqrt(dot1(normal, normal)), DIVISION_FLOOR)
        l, d = _toward1(points, i, at)
        set_row(dirs, i, l)
        dist[i] = d
        scale = abs(dot1(l, normal)) / length * area / max(d * d, DIVISION_FLOOR)
        for ch in range(3):
            irradiance[i, ch] = radiance[ch] * scale
