"""Kernels over regular grids of cells: bilinear splats and look-ups, summed-area tables, exact rectangle means and box sums."""

from __future__ import annotations

import math

import numpy as np

from ..util.jit import inline, kernel


def bilinear_splat(planes: np.ndarray, rc: np.ndarray, values: np.ndarray) -> None:
    """Add `values (n,c)` to C-contiguous `planes (c,h,w)`, each spread
    bilinearly to the 4 cells nearest its continuous (row, col) position
    `rc (n,2)` (cell centres at integers), in the photons' order. Weights
    reaching past the border fold onto the edge cells."""
    if not planes.flags.c_contiguous:
        raise ValueError("bilinear_splat adds in place: planes must be C-contiguous")
    _bilinear_splat(planes, np.ascontiguousarray(rc, dtype=np.float64), np.ascontiguousarray(values, dtype=np.float64))


@kernel("void(f8[:, :, ::1], f8[:, ::1], f8[:, ::1])")
def _bilinear_splat(planes, rc, values):
    h, w = planes.shape[1], planes.shape[2]
    for n in range(len(rc)):
        i, j = math.floor(rc[n, 0]), math.floor(rc[n, 1])
        fy, fx = rc[n, 0] - i, rc[n, 1] - j
        for di in range(2):
            wi = fy if di else 1.0 - fy
            row = min(max(i + di, 0), h - 1)
            for dj in range(2):
                weight = wi * (fx if dj else 1.0 - fx)
                col = min(max(j + dj, 0), w - 1)
                for k in range(len(planes)):
                    planes[k, row, col] += weight * values[n, k]


def bilinear_sample(planes: np.ndarray, rc: np.ndarray) -> np.ndarray:
    """(n,c) values of `planes (c,h,w)` interpolated bilinearly at continuous
    (row, col) positions `rc (n,2)` (cell centres at integers), clamped to
    the outermost centres."""
    return _bilinear_sample(np.ascontiguousarray(planes, dtype=np.float64), np.ascontiguousarray(rc, dtype=np.float64))


@inline
def bilinear1(plane, y, x):
    """`plane (h,w)` interpolated bilinearly at the continuous (row, col)
    position (y, x), cell centres at integers, clamped to the outermost
    centres."""
    h, w = plane.shape
    down, right = (1 if h > 1 else 0), (1 if w > 1 else 0)
    y, x = min(max(y, 0.0), h - 1.0), min(max(x, 0.0), w - 1.0)
    i, j = min(math.floor(y), max(h - 2, 0)), min(math.floor(x), max(w - 2, 0))
    fy, fx = y - i, x - j
    return ((1 - fy) * (1 - fx) * plane[i, j] + (1 - fy) * fx * plane[i, j + right]
            + fy * (1 - fx) * plane[i + down, j] + fy * fx * plane[i + down, j + right])


@kernel("f8[:, ::1](f8[:, :, ::1], f8[:, ::1])")
def _bilinear_sample(planes, rc):
    out = np.empty((len(rc), len(planes)))
    for n in range(len(rc)):
        for k in range(len(planes)):
            out[n, k] = bilinear1(planes[k], rc[n, 0], rc[n, 1])
    return out


@kernel("void(f8[:, :, ::1], f8[::1], f8, f8[:, ::1], f8[:, ::1])")
def add_within(planes, origin, cell, xy, out):
    """out[n] += `planes (c,h,w)` bilinear between cell centres (bilinear1)
    at chart points `xy (n,2)`, for the points on the grid: cells of edge
    `cell` m from chart corner `origin (2,)` (x, y). One plane (c = 1)
    adds to every channel of `out (n,3)`."""
    h, w = planes.shape[1], planes.shape[2]
    for n in range(len(xy)):
        y, x = (xy[n, 1] - origin[1]) / cell - 0.5, (xy[n, 0] - origin[0]) / cell - 0.5
        if y >= -0.5 and x >= -0.5 and y <= h - 0.5 and x <= w - 0.5:
            for k in range(out.shape[1]):
                out[n, k] += bilinear1(planes[min(k, len(planes) - 1)], y, x)


def rect_means(tables: np.ndarray, origin_rc: np.ndarray, cell: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,c) means over chart rectangles [lo, hi] ((n,2) x, y) of a
    cell-constant grid whose summed-area tables are `tables (c, h+1, w+1)`
    and whose first corner is at chart (y, x) `origin_rc`. Exact: the grid's
    integral function is bilinear between cell corners, so the rectangle's
    integral is 16 table entries (4 per corner) times signed weights
    (`_taps`). Rectangles narrower than a thousandth of a cell are widened
    to it."""
    return _rect_means(np.ascontiguousarray(tables, dtype=np.float64), np.ascontiguousarray(origin_rc, dtype=np.float64),
                       float(cell), np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64))


@inline
def _taps(lo, hi, size, entries, weights):
    """The entries (4,) along one axis of a summed-area table, and their
    signed weights (4,), that interpolate it linearly at `hi` minus at `lo`,
    positions in [0, size]."""
    for k in range(2):
        at = hi if k == 0 else lo
        sign = 1.0 if k == 0 else -1.0
        base = min(math.floor(at), size - 1)
        frac = at - base
        entries[k], entries[k + 2] = base, base + 1
        weights[k], weights[k + 2] = sign * (1.0 - frac), sign * frac


@kernel("f8[:, ::1](f8[:, :, ::1], f8[::1], f8, f8[:, ::1], f8[:, ::1])")
def _rect_means(tables, origin_rc, cell, lo, hi):
    h, w = tables.shape[1] - 1, tables.shape[2] - 1
    out = np.empty((len(lo), len(tables)))
    rows, cols = np.empty(4, dtype=np.int64), np.empty(4, dtype=np.int64)
    row_weights, col_weights = np.empty(4), np.empty(4)
    origin_y, origin_x = origin_rc[0], origin_rc[1]
    for n in range(len(lo)):
        scale = _rect_taps1(h, w, origin_y, origin_x, cell, lo[n, 0], lo[n, 1], hi[n, 0], hi[n, 1], rows, cols,
                            row_weights, col_weights)
        for c in range(len(tables)):
            out[n, c] = _tapped1(tables, c, rows, cols, row_weights, col_weights) * scale
    return out


def add_cell_means(tables: np.ndarray, origin: np.ndarray, cell: float, grid_origin: np.ndarray, step: float,
                   rows: range, columns: int, out: np.ndarray) -> None:
    """out (n,3) += the mean over each cell of another grid, row by row
    (n = len(rows) * columns): cells of edge `step` from chart point
    `grid_origin (2,)` (x, y), rows `rows` and columns 0..columns-1, of
    the cell-constant grid of edge `cell` from chart corner `origin (2,)`
    (x, y) whose summed-area tables are `tables (c, h+1, w+1)` (c = 1: the
    same in each channel), each cell widened to at least one of the
    grid's: what rect_means gives for the same rectangles, bit for bit,
    without their arrays. Cells off the grid get nothing."""
    _add_cell_means(np.ascontiguousarray(tables, dtype=np.float64), np.ascontiguousarray(origin, dtype=np.float64),
                    float(cell), np.ascontiguousarray(grid_origin, dtype=np.float64), float(step), rows.start,
                    rows.stop, columns, out)


@kernel("void(f8[:, :, ::1], f8[::1], f8, f8[::1], f8, i8, i8, i8, f8[:, ::1])")
def _add_cell_means(tables, origin, cell, grid_origin, step, first_row, end_row, columns, out):
    h, w = tables.shape[1] - 1, tables.shape[2] - 1
    origin_x, origin_y = origin[0], origin[1]
    end_x, end_y = origin_x + cell * w, origin_y + cell * h
    rows, cols = np.empty(4, dtype=np.int64), np.empty(4, dtype=np.int64)
    row_weights, col_weights = np.empty(4), np.empty(4)
    for r in range(first_row, end_row):
        for q in range(columns):
            n = (r - first_row) * columns + q
            lo_x, lo_y = grid_origin[0] + step * q, grid_origin[1] + step * r
            hi_x, hi_y = lo_x + step, lo_y + step
            cx, cy = 0.5 * (lo_x + hi_x), 0.5 * (lo_y + hi_y)
            half_x, half_y = max(0.5 * (hi_x - lo_x), 0.5 * cell), max(0.5 * (hi_y - lo_y), 0.5 * cell)
            x0, y0, x1, y1 = cx - half_x, cy - half_y, cx + half_x, cy + half_y
            if x1 > origin_x and y1 > origin_y and x0 < end_x and y0 < end_y:
                scale = _rect_taps1(h, w, origin_y, origin_x, cell, x0, y0, x1, y1, rows, cols, row_weights,
                                    col_weights)
                for c in range(len(tables)):
                    mean = _tapped1(tables, c, rows, cols, row_weights, col_weights) * scale
                    for k in range(c, c + 1 if len(tables) > 1 else out.shape[1]):
                        out[n, k] += mean


@inline
def _rect_taps1(h, w, origin_y, origin_x, cell, lo_x, lo_y, hi_x, hi_y, rows, cols, row_weights, col_weights):
    """Into `rows, cols (4,)` and `row_weights, col_weights (4,)`, the taps
    (`_taps`) of the rectangle [lo, hi] on the grid of h x w cells from
    chart corner (origin_x, origin_y) (rect_means); returns the scale from
    their sum to its mean."""
    cx, cy = 0.5 * (lo_x + hi_x), 0.5 * (lo_y + hi_y)
    half_x, half_y = max(0.5 * (hi_x - lo_x), 1e-3 * cell), max(0.5 * (hi_y - lo_y), 1e-3 * cell)
    x0, x1, y0, y1 = cx - half_x, cx + half_x, cy - half_y, cy + half_y
    _taps(min(max((y0 - origin_y) / cell, 0.0), h), min(max((y1 - origin_y) / cell, 0.0), h), h, rows, row_weights)
    _taps(min(max((x0 - origin_x) / cell, 0.0), w), min(max((x1 - origin_x) / cell, 0.0), w), w, cols, col_weights)
    return cell * cell / ((x1 - x0) * (y1 - y0))


@inline
def _tapped1(tables, c, rows, cols, row_weights, col_weights):
    """The sum of the taps (`_rect_taps1`) of table `c` of `tables`, at least 0."""
    total = 0.0
    for a in range(4):
        for b in range(4):
            total += row_weights[a] * col_weights[b] * tables[c, rows[a], cols[b]]
    return max(total, 0.0)


@inline
def box_sum(table, i, j, r):
    """The sum over the window [i-r, i+r] x [j-r, j+r] (clipped to the
    grid) of the grid whose summed-area table is `table (h+1, w+1)`: four
    entries. The four partial sums cancel to a few ulp, not 0, where
    nothing landed: at least 0."""
    h, w = table.shape[0] - 1, table.shape[1] - 1
    i0, i1 = min(max(i - r, 0), h), min(max(i + r + 1, 0), h)
    j0, j1 = min(max(j - r, 0), w), min(max(j + r + 1, 0), w)
    return max(table[i1, j1] - table[i0, j1] - table[i1, j0] + table[i0, j0], 0.0)


def summed_area_table(grid: np.ndarray) -> np.ndarray:
    """Summed-area table (h+1, w+1) of `grid (h, w)`, zero-padded: each
    entry the sum of the grid's cells above and left of it, T[r, c] =
    (sum of row r-1 up to column c-1) + T[r-1, c]."""
    return _summed_area_table(np.ascontiguousarray(grid, dtype=np.float64))


@kernel("f8[:, ::1](f8[:, ::1])")
def _summed_area_table(grid):
    table = np.zeros((grid.shape[0] + 1, grid.shape[1] + 1))
    for r in range(1, len(table)):
        run = 0.0
        for c in range(1, table.shape[1]):
            run += grid[r - 1, c - 1]
            table[r, c] = run + table[r - 1, c]
    return table


def channel_tables(planes: np.ndarray) -> np.ndarray:
    """Summed-area tables (c, h+1, w+1), one per channel of `planes (c,h,w)`,
    or one for all when the channels are equal (white light): the look-ups
    return that one column, which broadcasts."""
    if all(np.array_equal(planes[0], plane) for plane in planes[1:]):
        planes = planes[:1]
    return np.stack([summed_area_table(plane) for plane in planes])


def as_rgb(values: np.ndarray) -> np.ndarray:
    """(n,3) of look-up results (n,1) (one table for all channels) or (n,3)."""
    return values if values.shape[1] == 3 else np.repeat(values, 3, axis=1)
