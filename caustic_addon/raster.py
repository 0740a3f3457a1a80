"""Exact-area rasterisation of flat-shaded triangles onto a grid.

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
which over a closed polygon is its coverage of the cell.
"""

from __future__ import annotations

import numpy as np


# Triangles per batch: bounds the pieces' temporaries (~200 B a piece).
_BATCH = 1 << 15


def rasterise_triangles(shape: tuple[int, int], corners: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(h,w,c) grid holding, in each cell, the sum over triangles of
    `values (m,c)` times the triangle's area inside the cell.

    shape    (h, w) rows and columns; cell (r, c) spans x in [c, c+1], y in
             [r, r+1]
    corners  (m,3,2) triangle corners (x, y) in cell units, either winding;
             parts outside the grid are dropped
    """
    h, w = shape
    # columns -1 (everything left of the grid) to w (the last piece's right
    # neighbour), flattened row-major
    acc = np.zeros((values.shape[1], h * (w + 2)))
    for first in range(0, len(corners), _BATCH):
        _accumulate(acc, h, w, corners[first:first + _BATCH], values[first:first + _BATCH])
    return np.cumsum(acc.reshape(-1, h, w + 2), axis=2)[:, :, 1:w + 1].transpose(1, 2, 0)


def _accumulate(acc: np.ndarray, h: int, w: int, corners: np.ndarray, values: np.ndarray) -> None:
    """Add the triangles' edge pieces to the accumulation buffer `acc (c, h (w+2))`."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    winding = np.sign(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    # a counter-clockwise (y up) triangle accumulates minus its coverage
    weight = -winding[:, None] * values

    start = corners.reshape(-1, 2)
    end = corners[:, [1, 2, 0]].reshape(-1, 2)
    edge_weight = np.repeat(weight, 3, axis=0)
    sloped = start[:, 1] != end[:, 1]
    start, end, edge_weight = start[sloped], end[sloped], edge_weight[sloped]

    rows, (x0, y0, x1, y1), edge = _split(start, end, axis=1, first=0, last=h - 1, merge_before=False)
    # pieces left of the grid cover whole rows of it: they gather in column -1
    cols, (x0, y0, x1, y1), segment = _split(np.stack([x0, y0], 1), np.stack([x1, y1], 1), axis=0,
                                           first=-1, last=w - 1, merge_before=True)
    rows, edge = rows[segment], edge[segment]
    f = np.clip(0.5 * (x0 + x1) - cols, 0.0, 1.0)
    dy = y1 - y0
    index = np.concatenate([rows * (w + 2) + cols + 1, rows * (w + 2) + cols + 2])
    for k in range(len(acc)):
        wk = edge_weight[edge, k] * dy
        acc[k] += np.bincount(index, weights=np.concatenate([wk * (1.0 - f), wk * f]), minlength=acc.shape[1])


def _split(start: np.ndarray, end: np.ndarray, axis: int, first: int, last: int, merge_before: bool):
    """Cut segments `start, end (n,2)` at the integer lines x = k (axis 0)
    or y = k (axis 1), keeping each piece's direction. Only bands `first` to
    `last` are kept; with `merge_before`, pieces before `first` join band
    `first` instead of being dropped.

    Returns (band (p,) the piece's band along `axis`; (x0, y0, x1, y1) its
    ends; owner (p,) the segment it came from)."""
    a, b = start[:, axis], end[:, axis]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    band_lo = np.maximum(np.floor(lo), first).astype(np.int64)
    floor_hi = np.floor(hi)
    band_hi = np.minimum(np.maximum(floor_hi, first) if merge_before else floor_hi, last).astype(np.int64)
    count = np.maximum(band_hi - band_lo + 1, 0)
    owner = np.repeat(np.arange(len(a)), count)
    band = band_lo[owner] + (np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count))
    lo_o = lo[owner]
    c0 = np.where(band == first, lo_o, np.maximum(lo_o, band)) if merge_before else np.maximum(lo_o, band)
    c1 = np.minimum(hi[owner], band + 1.0)
    a_o, span = a[owner], (b - a)[owner]
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = np.where(span != 0, (c0 - a_o) / span, 0.0)
        t1 = np.where(span != 0, (c1 - a_o) / span, 1.0)
    t0, t1 = np.minimum(t0, t1), np.maximum(t0, t1)
    base, delta = start[owner], (end - start)[owner]
    p0, p1 = base + t0[:, None] * delta, base + t1[:, None] * delta
    return band, (p0[:, 0], p0[:, 1], p1[:, 0], p1[:, 1]), owner
