"""Maps of the unit square onto discs, cones of directions and frames around
an axis: scalar cores over floats and 3-tuples (`..1`, for kernels,
util/jit.py) and their forms over arrays of rows."""

from __future__ import annotations

import math

import numpy as np

from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import row, set_row


@inline
def orthonormal_basis1(axis):
    """(t, b): two unit 3-tuples that make a right-handed frame (t, b, axis)
    with the unit 3-tuple `axis` (x, y, z) (Duff et al. 2017, "Building an
    orthonormal basis, revisited", listing 3): s = +1 for z >= 0, else -1,
    a = -1 / (s + z), c = x y a,
    t = (1 + s x^2 a, s c, -s x), b = (c, s + y^2 a, -y)."""
    x, y, z = axis[0], axis[1], axis[2]
    sign = 1.0 if z >= 0.0 else -1.0
    a = -1.0 / (sign + z)
    c = x * y * a
    return (1.0 + sign * (x * x) * a, sign * c, -sign * x), (c, sign + (y * y) * a, -y)


@inline
def in_frame1(local, t, b, axis):
    """The 3-tuple local[0] t + local[1] b + local[2] axis: a direction given
    in the frame (t, b, axis), in world space."""
    return (local[0] * t[0] + local[1] * b[0] + local[2] * axis[0],
            local[0] * t[1] + local[1] * b[1] + local[2] * axis[1],
            local[0] * t[2] + local[1] * b[2] + local[2] * axis[2])


@inline
def concentric_disc1(u, v):
    """(x, y) on the unit disc: Shirley and Chiu's equal-area map of (u, v)
    in the unit square (Shirley and Chiu 1997, "A low distortion map between
    disk and square"; pbrt-v4's SampleUniformDiskConcentric): with
    a = 2u - 1, b = 2v - 1, r = a, phi = (pi/4) b / a where |a| > |b|, else
    r = b, phi = pi/2 - (pi/4) a / b; the centre goes to 0."""
    a, b = 2.0 * u - 1.0, 2.0 * v - 1.0
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0
    if abs(a) > abs(b):
        r, phi = a, 0.25 * math.pi * b / a
    else:
        r, phi = b, 0.5 * math.pi - 0.25 * math.pi * a / b
    return r * math.cos(phi), r * math.sin(phi)


@inline
def uniform_disc1(radius, u, v):
    """(x, y) uniform over the disc of `radius` in polar form:
    r = radius sqrt(u), phi = 2 pi v (pbrt-v4's SampleUniformDiskPolar)."""
    r = radius * math.sqrt(u)
    phi = 2.0 * math.pi * v
    return r * math.cos(phi), r * math.sin(phi)


@inline
def cone_of_disc1(x, y, cos_max):
    """The local 3-tuple direction (about +z) of the unit disc's point
    (x, y) in the cone cos(theta) >= cos_max, uniform in solid angle for
    points uniform on the disc: at radius rho, cos(theta) = 1 - rho^2 (1 -
    cos_max), the azimuth kept (Archimedes' hat-box theorem: a cap's area is
    linear in its height)."""
    rho2 = x * x + y * y
    cos_t = 1.0 - rho2 * (1.0 - cos_max)
    sin_t = math.sqrt(max(0.0, 1.0 - cos_t * cos_t))
    rho = math.sqrt(rho2)
    c, s = (x / rho, y / rho) if rho > 0.0 else (1.0, 0.0)
    return (sin_t * c, sin_t * s, cos_t)


@inline
def cone_direction1(axis, t, b, cos_max, u, v):
    """The unit 3-tuple direction of (u, v) in the unit square, uniform in
    solid angle within acos(cos_max) of the unit `axis`, whose frame is
    (t, b, axis): cone_of_disc1 of concentric_disc1(u, v)."""
    x, y = concentric_disc1(u, v)
    return in_frame1(cone_of_disc1(x, y, cos_max), t, b, axis)


@inline
def cosine_hemisphere1(normal, t, b, u, v):
    """The unit 3-tuple direction of (u, v) about the unit `normal` (frame
    t, b, normal) with density cos(theta) / pi: Malley's method, the
    concentric disc's point lifted onto the hemisphere, z = sqrt(1 - x^2 -
    y^2) (pbrt-v4's SampleCosineHemisphere)."""
    x, y = concentric_disc1(u, v)
    z = math.sqrt(max(0.0, 1.0 - x * x - y * y))
    return in_frame1((x, y, z), t, b, normal)


def concentric_disc(uv: np.ndarray) -> np.ndarray:
    """(n,2) concentric_disc1 of each of `uv (n,2)`."""
    out = np.empty((len(uv), 2))
    _concentric_rows(out, contiguous(uv, np.float64))
    return out


def sample_disc(radius: float, uv: np.ndarray) -> np.ndarray:
    """(n,2) uniform_disc1 of each of `uv (n,2)`, on the disc of `radius`."""
    out = np.empty((len(uv), 2))
    _uniform_disc_rows(out, float(radius), contiguous(uv, np.float64))
    return out


def frames(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """orthonormal_basis1 of each of `axes (n,3)` (unit): (t (n,3), b (n,3))."""
    t, b = np.empty((len(axes), 3)), np.empty((len(axes), 3))
    _frame_rows(t, b, contiguous(axes, np.float64))
    return t, b


def orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """orthonormal_basis1 of the unit `axis (3,)`: (t (3,), b (3,))."""
    t, b = frames(np.reshape(axis, (1, 3)))
    return t[0], b[0]


def cone_directions(axis: np.ndarray, cos_max: float, uv: np.ndarray) -> np.ndarray:
    """(n,3) cone_direction1 of each of `uv (n,2)`: unit directions uniform
    in solid angle within acos(cos_max) of the unit `axis (3,)`."""
    out = np.empty((len(uv), 3))
    _cone_rows(out, contiguous(axis, np.float64), float(cos_max), contiguous(uv, np.float64), False)
    return out


def cone_of_disc(axis: np.ndarray, cos_max: float, disc: np.ndarray) -> np.ndarray:
    """(n,3) cone_of_disc1 of each of the unit disc's points `disc (n,2)`,
    about the unit `axis (3,)`."""
    out = np.empty((len(disc), 3))
    _cone_rows(out, contiguous(axis, np.float64), float(cos_max), contiguous(disc, np.float64), True)
    return out


def cosine_hemisphere(normals: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) cosine_hemisphere1 of each of `uv (n,2)` about `normals (n,3)`."""
    out = np.empty((len(uv), 3))
    _cosine_rows(out, contiguous(normals, np.float64), contiguous(uv, np.float64))
    return out


@kernel("void(f8[:, ::1], f8[:, ::1])")
def _concentric_rows(out, uv):
    for i in range(len(uv)):
        out[i, 0], out[i, 1] = concentric_disc1(uv[i, 0], uv[i, 1])


@kernel("void(f8[:, ::1], f8, f8[:, ::1])")
def _uniform_disc_rows(out, radius, uv):
    for i in range(len(uv)):
        out[i, 0], out[i, 1] = uniform_disc1(radius, uv[i, 0], uv[i, 1])


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1])")
def _frame_rows(t_out, b_out, axes):
    for i in range(len(axes)):
        t, b = orthonormal_basis1(row(axes, i))
        set_row(t_out, i, t)
        set_row(b_out, i, b)


@kernel("void(f8[:, ::1], f8[::1], f8, f8[:, ::1], b1)")
def _cone_rows(out, axis, cos_max, points, on_disc):
    """Directions about `axis` of `points (n,2)`, of the unit square, or
    `on_disc` of the unit disc."""
    a = (axis[0], axis[1], axis[2])
    t, b = orthonormal_basis1(a)
    for i in range(len(points)):
        if on_disc:
            set_row(out, i, in_frame1(cone_of_disc1(points[i, 0], points[i, 1], cos_max), t, b, a))
        else:
            set_row(out, i, cone_direction1(a, t, b, cos_max, points[i, 0], points[i, 1]))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1])")
def _cosine_rows(out, normals, uv):
    for i in range(len(uv)):
        n = row(normals, i)
        t, b = orthonormal_basis1(n)
        set_row(out, i, cosine_hemisphere1(n, t, b, uv[i, 0], uv[i, 1]))
