"""Ray differentials through specular bounces (Igehy 1999, "Tracing ray
differentials"; pbrt's SurfaceInteraction::ComputeDifferentials): how an eye
ray's origin and direction change per pixel step, carried through each
reflection and refraction, so that a receiver seen through glass or in a
mirror is averaged over the pixel's footprint there (PlaneChart.footprint),
as one seen directly is, and not read at a point; and how a beam vertex
from a point of a lamp with a size lands as the point moves across its
cell of the lamp (`landing_differentials`: passes/beam.py spreads its beams
over that image of the cell).

A ray is o + s d; its differentials do, dd are (2,3) per ray, one row per
pixel step right and down (a beam vertex's: per unit along its lamp cell's
two axes). At a hit the point moves by the transfer dp, the
surface's shading normal by dn (its corner normals' interpolant), and the
new direction by the derivative of the reflection or refraction formula."""

from __future__ import annotations

import math

import numpy as np

from ..tracing.accelerator import GEOMETRY_TYPES, REFLECTED, REFRACTED
from ..tracing.triangles import TRIANGLES_TYPE, corner_at1, corner_normal_at1, face_normal_at1, locate1
from ..tracing.hits import HIT_TYPES
from ..util.jit import inline, kernel, named_kernel
from ..util.rows import contiguous
from ..util.vectors import dot1, row, scale1, set_subrow, subrow, sum1, transferred1
from .interface import INTERFACE_TYPES
from .paths import PATH_TYPES


@inline
def normal_change1(triangles, obj, prim, u, v, shading, dp0, dp1):
    """(dn0, dn1): the change of the unit shading normal `shading` of
    global triangle `prim` of object `obj` (tracing/triangles.py) at
    barycentrics u, v when the point moves by `dp0`, `dp1` in its plane.
    The point's barycentric change solves dp = e1 du + e2 dv (least
    squares, e_k = p_k - p_0); the interpolant m = (1-u-v) n_0 + u n_1 +
    v n_2 changes by dm = (n_1 - n_0) du + (n_2 - n_0) dv, and its
    normalised form by (dm - n (n.dm)) / |m|, with the sign that orients it
    as `shading`."""
    none = (0.0, 0.0, 0.0)
    r, copy, placed = locate1(triangles, obj, prim)
    p0 = corner_at1(triangles, r, copy, placed, 0)
    e1 = sum1(1.0, corner_at1(triangles, r, copy, placed, 1), -1.0, p0)
    e2 = sum1(1.0, corner_at1(triangles, r, copy, placed, 2), -1.0, p0)
    g11, g12, g22 = dot1(e1, e1), dot1(e1, e2), dot1(e2, e2)
    det = g11 * g22 - g12 * g12
    n0, n1, n2 = (corner_normal_at1(triangles, r, copy, placed, 0), corner_normal_at1(triangles, r, copy, placed, 1),
                  corner_normal_at1(triangles, r, copy, placed, 2))
    m = sum1(1.0, sum1(1.0 - u - v, n0, u, n1), v, n2)
    size = math.sqrt(dot1(m, m))
    if not (det > 0.0 and size > 1e-12):
        return none, none
    n = scale1(1.0 / size, m)
    scale = (1.0 if dot1(n, shading) >= 0.0 else -1.0) / size
    dm_du, dm_dv = sum1(1.0, n1, -1.0, n0), sum1(1.0, n2, -1.0, n0)
    b = (dot1(dp0, e1), dot1(dp0, e2), dot1(dp1, e1), dot1(dp1, e2))
    dm0 = sum1((g22 * b[0] - g12 * b[1]) / det, dm_du, (g11 * b[1] - g12 * b[0]) / det, dm_dv)
    dm1 = sum1((g22 * b[2] - g12 * b[3]) / det, dm_du, (g11 * b[3] - g12 * b[2]) / det, dm_dv)
    return (scale1(scale, sum1(1.0, dm0, -dot1(n, dm0), n)), scale1(scale, sum1(1.0, dm1, -dot1(n, dm1), n)))


@inline
def reflected_change1(d, dd, n, dn):
    """dr of the mirror direction r = d - 2 (d.n) n (Igehy 1999):

        dr = dd - 2 ((d.n) dn + (dd.n + d.dn) n)"""
    c = dot1(d, n)
    return sum1(1.0, dd, -2.0, sum1(c, dn, dot1(dd, n) + dot1(d, dn), n))


@inline
def refracted_change1(d, dd, n, dn, t, eta):
    """dt of the refracted direction t = eta d - mu n, mu = eta (d.n) +
    cos_t and cos_t = -t.n, `n` on the side `d` comes from (Igehy 1999):

        dt = eta dd - mu dn - dmu n,  dmu = (eta - eta^2 (d.n) / (t.n)) d(d.n)

    with d(d.n) = dd.n + d.dn."""
    c, cos_t = dot1(d, n), -dot1(t, n)
    mu = eta * c + cos_t
    d_mu = (eta + eta * eta * c / cos_t) * (dot1(dd, n) + dot1(d, dn)) if cos_t > 0.0 else 0.0
    return sum1(1.0, sum1(eta, dd, -mu, dn), -d_mu, n)


@named_kernel("void", PATH_TYPES, HIT_TYPES, INTERFACE_TYPES, GEOMETRY_TYPES,
              {"reflected": "i8[::1]", "refracted": "i8[::1]"})
def _branch_differentials(reflected, refracted, out_dirs, dirs, t, facing, scattering, eta, obj, prim, u, v,
                          triangles, d_origins, d_dirs, out_d_origins, out_d_dirs):
    """The differentials of the branches of each path i: its reflected
    branch is row `reflected[i]` of the out_ arrays, its refracted one row
    `refracted[i]` (-1: none). The transfer and the normal's change are the
    path's, shared by its branches."""
    for i in range(len(reflected)):
        if reflected[i] < 0 and refracted[i] < 0:
            continue
        d, normal = row(dirs, i), row(scattering, i)
        dd0, dd1 = subrow(d_dirs, i, 0), subrow(d_dirs, i, 1)
        dp0 = transferred1(subrow(d_origins, i, 0), dd0, d, t[i], row(facing, i))
        dp1 = transferred1(subrow(d_origins, i, 1), dd1, d, t[i], row(facing, i))
        dn0, dn1 = normal_change1(triangles, obj[i], prim[i], u[i], v[i], normal, dp0, dp1)
        k = reflected[i]
        if k >= 0:
            set_subrow(out_d_origins, k, 0, dp0)
            set_subrow(out_d_origins, k, 1, dp1)
            set_subrow(out_d_dirs, k, 0, reflected_change1(d, dd0, normal, dn0))
            set_subrow(out_d_dirs, k, 1, reflected_change1(d, dd1, normal, dn1))
        k = refracted[i]
        if k >= 0:
            out = row(out_dirs, k)
            set_subrow(out_d_origins, k, 0, dp0)
            set_subrow(out_d_origins, k, 1, dp1)
            set_subrow(out_d_dirs, k, 0, refracted_change1(d, dd0, normal, dn0, out, eta[i]))
            set_subrow(out_d_dirs, k, 1, refracted_change1(d, dd1, normal, dn1, out, eta[i]))


def branch_differentials(accel, paths, hits, surface, source: np.ndarray, kind: np.ndarray,
                         out_dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(d_origins, d_dirs), each (k,2,3) float32, of the branches that `source (k,)`
    paths of `paths` sent from their `hits` at `surface`
    (bounce.Interface), along `out_dirs (k,3)`, each of `kind (k,)`."""
    k = len(source)
    branch = {kind_: np.full(len(paths), -1, dtype=np.int64) for kind_ in (REFLECTED, REFRACTED)}
    for kind_, rows in branch.items():
        chosen = np.flatnonzero(kind == kind_)
        rows[source[chosen]] = chosen
    out_d_origins, out_d_dirs = np.empty((k, 2, 3), dtype=np.float32), np.empty((k, 2, 3), dtype=np.float32)
    f8 = np.float64
    _branch_differentials(reflected=branch[REFLECTED], refracted=branch[REFRACTED],
                          out_dirs=contiguous(out_dirs, f8), dirs=contiguous(paths.dirs, f8),
                          t=contiguous(hits.t, f8), facing=contiguous(surface.facing, f8),
                          scattering=contiguous(surface.scattering, f8), eta=contiguous(surface.eta, f8),
                          obj=contiguous(hits.obj, np.int64), prim=contiguous(hits.prim, np.int64),
                          u=contiguous(hits.u, f8), v=contiguous(hits.v, f8), triangles=accel.triangles,
                          d_origins=contiguous(paths.d_origins, np.float32),
                          d_dirs=contiguous(paths.d_dirs, np.float32), out_d_origins=out_d_origins,
                          out_d_dirs=out_d_dirs)
    return out_d_origins, out_d_dirs


@kernel(f"void(f8[:, ::1], f8[::1], i8[::1], i8[::1], {TRIANGLES_TYPE}, f4[:, :, ::1], f4[:, :, ::1], "
        "f8[:, :, ::1], f8[:, :, ::1])")
def _landing_differentials(dirs, t, obj, prim, triangles, d_origins, d_dirs, dp, duv):
    """`landing_differentials` of paths along `dirs (n,3)` that met
    triangles `prim (n,)` (global) of objects `obj (n,)` at distance `t (n,)`."""
    for i in range(len(t)):
        r, copy, placed = locate1(triangles, obj[i], prim[i])
        d, normal = row(dirs, i), face_normal_at1(triangles, r, copy, placed)
        p0 = corner_at1(triangles, r, copy, placed, 0)
        e1 = sum1(1.0, corner_at1(triangles, r, copy, placed, 1), -1.0, p0)
        e2 = sum1(1.0, corner_at1(triangles, r, copy, placed, 2), -1.0, p0)
        g11, g12, g22 = dot1(e1, e1), dot1(e1, e2), dot1(e2, e2)
        det = g11 * g22 - g12 * g12
        for k in range(2):
            moved = transferred1(subrow(d_origins, i, k), subrow(d_dirs, i, k), d, t[i], normal)
            set_subrow(dp, i, k, moved)
            b1, b2 = dot1(moved, e1), dot1(moved, e2)
            duv[i, k, 0] = (g22 * b1 - g12 * b2) / det if det > 0.0 else 0.0
            duv[i, k, 1] = (g11 * b2 - g12 * b1) / det if det > 0.0 else 0.0


def landing_differentials(accel, paths, hits) -> tuple[np.ndarray, np.ndarray]:
    """(dp (n,2,3) world, duv (n,2,2) barycentric (u, v) of the triangle
    hit): how the points where `paths`, which carry differentials, met
    `hits` move with each differential, on the plane of the triangle each
    met (the transfer, Igehy 1999; the barycentrics' change solves dp = e1
    du + e2 dv, e_k = p_k - p_0)."""
    n = len(paths)
    dp, duv = np.empty((n, 2, 3)), np.empty((n, 2, 2))
    f8 = np.float64
    _landing_differentials(contiguous(paths.dirs, f8), contiguous(hits.t, f8), contiguous(hits.obj, np.int64),
                           contiguous(hits.prim, np.int64), accel.triangles, contiguous(paths.d_origins, np.float32),
                           contiguous(paths.d_dirs, np.float32), dp, duv)
    return dp, duv
