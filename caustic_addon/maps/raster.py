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


# Edge pieces per batch: bounds their temporaries (~200 B a piece), however
# many cells the triangles span.
_BATCH_PIECES = 1 << 19


def signed_areas(corners: np.ndarray) -> np.ndarray:
    """(m,) areas of 2D triangles `corners (m,3,2)`, positive when
    counter-clockwise (y up)."""
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def rasterise_triangles(shape: tuple[int, int], corners: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(c,h,w) planes holding, in each cell, the sum over triangles of
    `values (m,c)` times the triangle's area inside the cell.

    shape    (h, w) rows and columns; cell (r, c) spans x in [c, c+1], y in
             [r, r+1]
    corners  (m,3,2) triangle corners (x, y) in cell units, either winding;
             parts outside the grid are dropped
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

    def add(self, corners: np.ndarray, values: np.ndarray) -> None:
        """Add triangles `corners (m,3,2)` (cell units) of `values (m,c)`;
        one channel of buffer takes c = 1 only."""
        h, w = self.shape
        for first, end in _batches(corners):
            _accumulate(self.acc, h, w, corners[first:end], values[first:end])

    def widen(self, channels: int) -> None:
        """Hold `channels` channels from now on, each a copy of the one held."""
        if len(self.acc) < channels:
            self.acc = np.repeat(self.acc, channels, axis=0)

    def planes(self) -> np.ndarray:
        """(c,h,w) the coverage-weighted sums of everything added."""
        h, w = self.shape
        return np.cumsum(self.acc.reshape(-1, h, w + 2), axis=2)[:, :, 1:w + 1]


def _batches(corners: np.ndarray) -> list[tuple[int, int]]:
    """[first, end) runs of the triangles `corners (m,3,2)` (cell units),
    each of at most _BATCH_PIECES edge pieces (or one triangle): an edge
    from (x0, y0) to (x1, y1) is cut into at most |x1 - x0| + |y1 - y0| + 3
    pieces."""
    span = np.abs(corners - np.take(corners, [1, 2, 0], axis=1))
    total = np.cumsum(span.sum(axis=(1, 2)) + 9.0)
    bounds = [0]
    while bounds[-1] < len(corners):
        done = total[bounds[-1] - 1] if bounds[-1] else 0.0
        bounds.append(max(int(np.searchsorted(total, done + _BATCH_PIECES, side="right")), bounds[-1] + 1))
    return list(zip(bounds[:-1], bounds[1:]))


def _accumulate(acc: np.ndarray, h: int, w: int, corners: np.ndarray, values: np.ndarray) -> None:
    """Add the triangles' edge pieces to the accumulation buffer `acc (c, h (w+2))`."""
    # a counter-clockwise (y up) triangle accumulates minus its coverage
    weight = -np.sign(signed_areas(corners))[:, None] * values

    start = corners.reshape(-1, 2)
    end = np.take(corners, [1, 2, 0], axis=1).reshape(-1, 2)
    sloped = np.flatnonzero(start[:, 1] != end[:, 1])
    start, end = np.take(start, sloped, axis=0), np.take(end, sloped, axis=0)
    triangle = sloped // 3

    row, x0, x1, dy, edge = _rows(start, end, h)
    col, xmid, dy, piece = _columns(x0, x1, dy, w)
    f = xmid - col
    at = row[piece] * (w + 2) + col + 1
    index = np.concatenate([at, at + 1])
    of_piece = triangle[edge[piece]]
    for k in range(len(acc)):
        wk = weight[:, k][of_piece] * dy
        acc[k] += np.bincount(index, weights=np.concatenate([wk * (1.0 - f), wk * f]), minlength=acc.shape[1])


def _bands(lo: np.ndarray, hi: np.ndarray, first: int, last: int):
    """The integer bands [k, k+1) that spans [lo, hi] (n,) meet, k in
    [first, last]. Returns (owner (p,) the span of each piece, band (p,))."""
    band_lo = np.maximum(np.floor(lo), first).astype(np.int64)
    band_hi = np.minimum(np.floor(hi), last).astype(np.int64)
    count = np.maximum(band_hi - band_lo + 1, 0)
    owner = np.repeat(np.arange(len(lo)), count)
    return owner, band_lo[owner] + (np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count))


def _rows(start: np.ndarray, end: np.ndarray, h: int):
    """Cut sloped edges `start, end (n,2)` at the lines y = k into pieces in
    rows 0..h-1 (others are dropped). Returns (row, x0, x1, dy signed along
    the edge, edge) per piece."""
    ya, yb = start[:, 1], end[:, 1]
    lo, hi = np.minimum(ya, yb), np.maximum(ya, yb)
    slope = (end[:, 0] - start[:, 0]) / (yb - ya)
    edge, row = _bands(lo, hi, 0, h - 1)
    y0, y1 = np.maximum(lo[edge], row), np.minimum(hi[edge], row + 1.0)
    xa, ya, k = start[:, 0][edge], ya[edge], slope[edge]
    return row, xa + (y0 - ya) * k, xa + (y1 - ya) * k, (y1 - y0) * np.sign(yb - start[:, 1])[edge], edge


def _columns(x0: np.ndarray, x1: np.ndarray, dy: np.ndarray, w: int):
    """Cut row pieces at the lines x = k into pieces in columns -1..w-1:
    everything left of the grid joins column -1, where it covers whole rows
    of it; pieces right of the grid are dropped. Returns (col, xmid clipped
    to the column, dy share, row piece) per piece."""
    lo, hi = np.minimum(x0, x1), np.maximum(x0, x1)
    piece, col = _bands(lo, np.maximum(hi, -1.0), -1, w - 1)
    lo, hi, dy = lo[piece], hi[piece], dy[piece]
    c0 = np.where(col == -1, lo, np.maximum(lo, col))
    c1 = np.minimum(hi, col + 1.0)
    width = hi - lo
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(width > 0, (c1 - c0) / width, 1.0)
    return col, np.clip(0.5 * (c0 + c1), col, col + 1.0), dy * share, piece
