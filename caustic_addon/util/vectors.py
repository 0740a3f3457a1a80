"""Row-wise vector helpers over (n,3) arrays, and their scalar forms over
3-tuples for kernels (`util.jit`). Reductions over three values are spelt
out: numpy's reductions along a short last axis (norm, max or sum with
axis=1) run 3 to 8 times slower than einsum or two elementwise calls (numpy
2.x, measured on (20000,3) arrays)."""

from __future__ import annotations

import math

import numpy as np

from .jit import inline
from .rows import contiguous

# A floor under a length, an area or a probability that divides: it keeps a
# zero-sized thing finite (0 / 0 becomes 0) and lies far below any real value.
DIVISION_FLOOR = 1e-300


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (n,3) arrays -> (n,)."""
    return np.einsum("ij,ij->i", a, b)


def length(v: np.ndarray) -> np.ndarray:
    """(n,) Euclidean lengths of the rows of `v (n,3)`."""
    return np.sqrt(dot(v, v))


def normalize(v: np.ndarray) -> np.ndarray:
    """Rows of `v (n,3)` scaled to unit length; zero rows stay zero."""
    size = length(v)[:, None]
    return v / np.where(size > 0, size, 1.0)


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,3) row-wise cross products of `a (n,3)` and `b (n,3)`."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def max_channel(c: np.ndarray) -> np.ndarray:
    """(n,) the largest of the three channels of `c (n,3)`."""
    return np.maximum(np.maximum(c[:, 0], c[:, 1]), c[:, 2])


def float_rows(*arrays) -> list[np.ndarray]:
    """`arrays` broadcast against each other, as writeable C-contiguous
    float64 (copies where they are not), the form the kernels' signatures take."""
    arrays = [np.asarray(a, dtype=np.float64) for a in arrays]
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    return [contiguous(a if a.shape == shape else np.broadcast_to(a, shape), np.float64) for a in arrays]


@inline
def row(a, i):
    """Row i of `a (n,3)` as a 3-tuple."""
    return (a[i, 0], a[i, 1], a[i, 2])


@inline
def set_row(a, i, v):
    """Row i of `a (n,3)` = the 3-tuple `v`."""
    a[i, 0], a[i, 1], a[i, 2] = v[0], v[1], v[2]


@inline
def subrow(a, i, k):
    """Row k of item i of `a (n,m,3)` (a triangle's corner, one of a ray's
    differentials) as a 3-tuple."""
    return (a[i, k, 0], a[i, k, 1], a[i, k, 2])


@inline
def set_subrow(a, i, k, v):
    """Row k of item i of `a (n,m,3)` = the 3-tuple `v`."""
    a[i, k, 0], a[i, k, 1], a[i, k, 2] = v[0], v[1], v[2]


@inline
def dot1(a, b):
    """a . b of 3-tuples."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@inline
def sum1(s, a, t, b):
    """s a + t b of 3-tuples `a`, `b` and scalars `s`, `t`."""
    return (s * a[0] + t * b[0], s * a[1] + t * b[1], s * a[2] + t * b[2])


@inline
def normalize1(v):
    """The 3-tuple `v` at unit length; zero stays zero."""
    size = math.sqrt(dot1(v, v))
    return v if size == 0.0 else (v[0] / size, v[1] / size, v[2] / size)


@inline
def max_channel1(c):
    """The largest of the three channels of the 3-tuple `c`."""
    return max(max(c[0], c[1]), c[2])


@inline
def scale1(s, a):
    """s a of the 3-tuple `a` and scalar `s`."""
    return (s * a[0], s * a[1], s * a[2])


@inline
def transferred1(do, dd, d, s, normal):
    """dp, the change of the point where the ray o + s d meets the plane of
    `normal`, when the ray changes by `do`, `dd` (Igehy 1999, "Tracing ray
    differentials", the transfer):

        dp = (do + s dd) + ds d,   ds = -((do + s dd).n) / (d.n)"""
    moved = sum1(1.0, do, s, dd)
    return sum1(1.0, moved, -dot1(moved, normal) / dot1(d, normal), d)
