"""Points of a rectangle drawn uniformly over the solid angle it spans from
a point (Urena, Fajardo and King 2013, "An Area-Preserving
Parametrization for Spherical Rectangles", as Cycles' area lights sample
a rectangle): a large light near a surface, drawn uniformly by area,
sends most of its samples where it looks small; drawn by solid angle,
every sample carries the same share of its light."""

from __future__ import annotations

import math

from ..util.jit import inline
from ..util.vectors import dot1, normalize1, sum1

# Below this solid angle (sr) the parametrization loses its digits: such a
# rectangle is far enough to be drawn by area.
SMALLEST = 1e-4


@inline
def _cross1(a, b):
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


@inline
def spherical_rectangle1(origin, corner, edge_x, edge_y):
    """The spherical rectangle that the rectangle `corner + s edge_x + t
    edge_y` (s, t in [0, 1], orthogonal edges, 3-tuples) spans from the
    3-tuple `origin`: (solid angle, then what spherical_rectangle_point1
    needs). Its solid angle is g0 + g1 + g2 + g3 - 2 pi, the interior
    angles g_i at its corners (Urena et al. 2013, section 3); 0 from the
    rectangle's own plane."""
    len_x, len_y = math.sqrt(dot1(edge_x, edge_x)), math.sqrt(dot1(edge_y, edge_y))
    x = (edge_x[0] / len_x, edge_x[1] / len_x, edge_x[2] / len_x)
    y = (edge_y[0] / len_y, edge_y[1] / len_y, edge_y[2] / len_y)
    z = _cross1(x, y)
    d = sum1(1.0, corner, -1.0, origin)
    z0 = dot1(d, z)
    if z0 > 0.0:
        z, z0 = (-z[0], -z[1], -z[2]), -z0
    x0, y0 = dot1(d, x), dot1(d, y)
    x1, y1 = x0 + len_x, y0 + len_y
    if z0 > -1e-9 * (len_x + len_y):
        # in the rectangle's plane: it spans no solid angle
        return 0.0, x, y, z, x0, y0, z0, x1, y1, 0.0, 0.0, 0.0
    n0 = normalize1(_cross1((x0, y0, z0), (x1, y0, z0)))
    n1 = normalize1(_cross1((x1, y0, z0), (x1, y1, z0)))
    n2 = normalize1(_cross1((x1, y1, z0), (x0, y1, z0)))
    n3 = normalize1(_cross1((x0, y1, z0), (x0, y0, z0)))
    g0 = math.acos(min(max(-dot1(n0, n1), -1.0), 1.0))
    g1 = math.acos(min(max(-dot1(n1, n2), -1.0), 1.0))
    g2 = math.acos(min(max(-dot1(n2, n3), -1.0), 1.0))
    g3 = math.acos(min(max(-dot1(n3, n0), -1.0), 1.0))
    k = 2.0 * math.pi - g2 - g3
    return g0 + g1 - k, x, y, z, x0, y0, z0, x1, y1, n0[2], n2[2], k


@inline
def spherical_rectangle_point1(origin, rect, u, v):
    """The 3-tuple point of the rectangle at (u, v) of the unit square,
    uniform over the solid angle `rect` (spherical_rectangle1) spans from
    the 3-tuple `origin` (Urena et al. 2013, section 4)."""
    solid_angle, x, y, z, x0, y0, z0, x1, y1, b0, b1, k = rect
    au = u * solid_angle + k
    fu = (math.cos(au) * b0 - b1) / math.sin(au)
    cu = math.copysign(1.0, fu) / math.sqrt(fu * fu + b0 * b0)
    cu = min(max(cu, -1.0), 1.0)
    xu = -(cu * z0) / max(math.sqrt(1.0 - cu * cu), 1e-300)
    xu = min(max(xu, x0), x1)
    dist = math.sqrt(xu * xu + z0 * z0)
    h0 = y0 / math.sqrt(dist * dist + y0 * y0)
    h1 = y1 / math.sqrt(dist * dist + y1 * y1)
    hv = h0 + v * (h1 - h0)
    yv = hv * dist / math.sqrt(1.0 - hv * hv) if hv * hv < 1.0 - 1e-6 else y1
    return (origin[0] + xu * x[0] + yv * y[0] + z0 * z[0], origin[1] + xu * x[1] + yv * y[1] + z0 * z[1],
            origin[2] + xu * x[2] + yv * y[2] + z0 * z[2])
