"""Exact-area rasterisation of flat-shaded triangles (and convex polygons)
onto a grid.

Each cell receives value x (area of the triangle inside the cell), exactly,
with work proportional to the triangles' perimeters in cells rather than
their areas. It is the accumulation buffer of signed-area rasterisers
(Levien's font-rs, 2016; Sean Barrett's stb_truetype v2): every edge is cut
at the grid lines into pieces that each lie in one cell, and a piece from
(x0, y0) to (x1, y1) in cell (row r, column c) adds, with f the fraction of
the cell left of its midpoint,

    acc[r, c]     += dy (1 - f)
    acc[r, c + 1] += dy f

(dy = y1 - y0, signed). A running sum along each row then gives, in every
cell, the signed area between the polygon's edges and the row's far end,
which over a closed polygon is its coverage of the cell. A polygon of k
corners is k edges, whatever its shape; corners (m,k,2) may repeat a
polygon's last corner to pad it to k (an edge of no length adds nothing).
"""

from __future__ import annotations

from functools import partial
from typing import Callable

import numpy as np

from ..util.jit import inline, kernel


@inline
def signed_area1(a, b, c):
    """Area of the 2D triangle a, b, c ((2,) each), positive when
    counter-clockwise (y up): half the cross product (b - a) x (c - a)."""
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def signed_areas(corners: np.ndarray) -> np.ndarray:
    """(m,) `polygon_area1` of 2D triangles or convex polygons `corners (m,k,2)`."""
    return _signed_areas(np.ascontiguousarray(corners, dtype=np.float64))


@kernel("f8[::1](f8[:, :, ::1])")
def _signed_areas(corners):
    out = np.empty(len(corners))
    for t in range(len(corners)):
        out[t] = polygon_area1(corners, t)
    return out


@inline
def polygon_area1(corners, t):
    """Signed area of the convex polygon `corners[t] (k,2)` (k >= 3): the sum
    of its fan's `signed_area1`, a triangle's own for k = 3."""
    area = 0.0
    for k in range(1, corners.shape[1] - 1):
        area += signed_area1(corners[t, 0], corners[t, k], corners[t, k + 1])
    return area


def rasterise_triangles(shape: tuple[int, int], corners: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(c,h,w) planes holding, in each cell, the sum over triangles of
    `values (m,c)` times the triangle's area inside the cell.

    shape    (h, w) rows and columns; cell (r, c) spans x in [c, c+1], y in
             [r, r+1]
    corners  (m,3,2) triangle corners (x, y) in cell units, either winding,
             or (m,k,2) convex polygons'; parts outside the grid are dropped
    """
    buffer = Coverage(shape, values.shape[1])
    buffer.add(corners, values)
    return buffer.planes()


class Coverage:
    """The accumulation buffer of triangles added batch by batch: its memory
    is the grid's, whatever the number of triangles, and the coverage is
    the same however they were batched (the running sum is linear)."""

    def __init__(self, shape: tuple[int, int], channels: int):
        self.shape = shape
        h, w = shape
        # columns -1 (everything left of the grid) to w (the last piece's
        # right neighbour), flattened row-major
        self.acc = np.zeros((channels, h * (w + 2)))

    def add(self, corners: np.ndarray, values: np.ndarray, origin=(0.0, 0.0), cell: float = 1.0,
            share: np.ndarray | None = None) -> None:
        """Add triangles `corners (m,3,2)` (or convex polygons, (m,k,2)), cell units or, given the
        grid's first corner `origin (2,)` and its `cell` edge, in those
        units, of `values (m,c)` times `share (m,)` (None: 1; a triangle of
        share 0 is skipped); one channel of buffer takes the first."""
        for job in self.add_jobs(corners, values, origin, cell, share, bands=1):
            job()

    def add_jobs(self, corners: np.ndarray, values: np.ndarray, origin=(0.0, 0.0), cell: float = 1.0,
                 share: np.ndarray | None = None, bands: int = 1) -> list[Callable[[], None]]:
        """`add`, as jobs that each write one of `bands` bands of the
        grid's rows, to run on threads of their own, each over the
        triangles whose rows reach its band; the bands hold about equal
        numbers of triangle rows (`band_edges`), as a caustic crowds into a
        few rows. Each cell gets the same pieces in the same order whatever
        the bands, so the sums are `add`'s to the bit."""
        h, w = self.shape
        corners = np.ascontiguousarray(corners, dtype=np.float64)
        values = np.ascontiguousarray(values, dtype=np.float64)
        share = np.ones(len(corners)) if share is None else np.ascontiguousarray(share, dtype=np.float64)
        origin = np.asarray(origin, dtype=np.float64)
        low, high = np.empty(len(corners)), np.empty(len(corners))
        _row_spans(corners, float(origin[1]), float(cell), low, high)
        drawn = (share != 0.0) & (high >= 0) & (low < h)
        edges = band_edges(low[drawn], high[drawn], h, bands)
        return [partial(_accumulate, self.acc, h, w, corners, values, origin, float(cell), share,
                        np.flatnonzero(drawn & (high >= first) & (low < end)), int(first), int(end))
                for first, end in zip(edges[:-1], edges[1:])]

    def widen(self, channels: int) -> None:
        """Hold `channels` channels from now on, each a copy of the one held."""
        if len(self.acc) < channels:
            self.acc = np.repeat(self.acc, channels, axis=0)

    def planes(self) -> np.ndarray:
        """(c,h,w) the coverage-weighted sums of everything added."""
        h, w = self.shape
        return np.cumsum(self.acc.reshape(-1, h, w + 2), axis=2)[:, :, 1:w + 1]


@kernel("void(f8[:, :, ::1], f8, f8, f8[::1], f8[::1])")
def _row_spans(corners, origin_y, cell, low, high):
    """The first and last rows `low, high (m,)` that each of triangles (or
    polygons) `corners (m,k,2)` reaches, on a grid of `cell` from y =
    `origin_y`, as _accumulate places their corners."""
    for t in range(len(corners)):
        low[t], high[t] = np.inf, -np.inf
        for k in range(corners.shape[1]):
            row = np.floor((corners[t, k, 1] - origin_y) / cell)
            low[t], high[t] = min(low[t], row), max(high[t], row)


def band_edges(low: np.ndarray, high: np.ndarray, h: int, bands: int) -> np.ndarray:
    """(b+1,) ascending row edges from 0 to `h` of at most `bands` bands of
    rows, each holding about as many rows of triangles as the others, for
    triangles that reach rows `low` to `high (m,)` (each row a triangle
    crosses costs it about alike); every row counts one more, so that rows
    no triangle reaches are shared out too."""
    first = np.clip(low, 0, h - 1).astype(np.int64)
    last = np.clip(high, 0, h - 1).astype(np.int64)
    crossing = np.cumsum(np.bincount(first, minlength=h + 1) - np.bincount(last + 1, minlength=h + 1))[:h]
    work = np.concatenate([[0], np.cumsum(crossing + 1)])
    cuts = np.searchsorted(work, np.linspace(0, work[-1], max(1, min(bands, h)) + 1)[1:-1])
    return np.unique(np.concatenate([[0], np.clip(cuts, 1, h - 1), [h]]))


@kernel("void(f8[:, ::1], i8, i8, f8[:, :, ::1], f8[:, ::1], f8[::1], f8, f8[::1], i8[::1], i8, i8)")
def _accumulate(acc, h, w, corners, values, origin, cell, share, chosen, first_row, end_row):
    """Add every edge piece of the triangles `chosen (j,)` (ascending) of
    `corners (m,3,2)`, or convex polygons (m,k,2), (in units of `cell` from
    `origin (2,)`) of `values (m,c)` times `share (m,)` to the
    accumulation buffer `acc (c, h (w+2))`: each sloped edge is cut at the
    lines y = k into rows first_row..end_row-1 of 0..h-1, and each row
    piece at the lines x = k into columns -1..w-1 (everything left of the
    grid joins column -1; pieces right of it are dropped)."""
    channels, count = acc.shape[0], corners.shape[1]
    local = np.empty((1, count, 2))
    for i in range(len(chosen)):
        t = chosen[i]
        for k in range(count):
            local[0, k, 0] = (corners[t, k, 0] - origin[0]) / cell
            local[0, k, 1] = (corners[t, k, 1] - origin[1]) / cell
        # a counter-clockwise (y up) polygon accumulates minus its coverage
        area = polygon_area1(local, 0)
        sign = -1.0 if area > 0.0 else (1.0 if area < 0.0 else 0.0)
        for e in range(count):
            xs, ys = local[0, e, 0], local[0, e, 1]
            xe, ye = local[0, (e + 1) % count, 0], local[0, (e + 1) % count, 1]
            if ys == ye:
                continue
            lo, hi = min(ys, ye), max(ys, ye)
            slope = (xe - xs) / (ye - ys)
            up = 1.0 if ye > ys else -1.0
            for row in range(max(int(np.floor(lo)), first_row), min(int(np.floor(hi)), end_row - 1) + 1):
                y0, y1 = max(lo, row), min(hi, row + 1.0)
                xa, xb = xs + (y0 - ys) * slope, xs + (y1 - ys) * slope
                dy = (y1 - y0) * up
                left, right = min(xa, xb), max(xa, xb)
                width = right - left
                for col in range(max(int(np.floor(left)), -1), min(int(np.floor(max(right, -1.0))), w - 1) + 1):
                    c0 = left if col == -1 else max(left, col)
                    c1 = min(right, col + 1.0)
                    part = (c1 - c0) / width if width > 0.0 else 1.0
                    f = min(max(0.5 * (c0 + c1), col), col + 1.0) - col
                    at = row * (w + 2) + col + 1
                    for k in range(channels):
                        piece = sign * (values[t, k] * share[t]) * dy * part
                        acc[k, at] += piece * (1.0 - f)
                        acc[k, at + 1] += piece * f
