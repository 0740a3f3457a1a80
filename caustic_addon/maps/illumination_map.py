"""Illumination maps: caustic flux stored on a receiver, read back as irradiance.

The paper (section 2.3) stores each lamp ray's energy in a 2D array over the
receiver, spread bilinearly to the 4 nearest cells, and divides by the area a
cell represents when it reads the map back. `IlluminationMap` does exactly
that in a chart of the receiver measured in metres, so the result is
irradiance in W/m^2.

Map scale: the edge of one cell, in millimetres of world space. The paper
compares 5 and 40; larger cells are smoother and blurrier.

The adaptive estimate needs no map scale: at each look-up it grows a square
window of cells until it holds k photons, up to 16 cells from the centre, and
divides their flux by the window's area (k-nearest-neighbour density
estimation with a bounded radius, Silverman 1986 and Jensen 2001, on the
map's grid), the area the receiver covers in it where a chart has gaps (a
UV map's or a box chart's islands: a window half over a gap would halve the
light at the island's edge). Window sums come from summed-area tables, four
reads per window.
"""

from __future__ import annotations

import math
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..util.jit import inline, kernel
from ..util.vectors import DIVISION_FLOOR, float_rows
from .charts import Chart, ImageFrame
from .grid import as_rgb, bilinear_sample, bilinear_splat, box_sum, channel_tables, rect_means, summed_area_table

# Half-width, in cells, of the largest window the adaptive estimate tries. It
# bounds the blur: where fewer than k photons land within it, the estimate is
# its plain mean (zero far from any caustic), not a halo of flux borrowed
# from far away.
_MAX_WINDOW_RADIUS = 16
# Cells `irradiance` reads at a time: the look-ups' temporaries (~500 B a
# cell) stay bounded.
_BAKE_CELLS = 1 << 16


@dataclass
class MapEstimate:
    """How a map turns stored flux into irradiance: the paper's cells
    (`k_nearest` None) or the adaptive window of `k_nearest` photons."""

    k_nearest: Optional[int] = None


class IlluminationMap:
    """Caustic flux landed on one receiver.

    flux and count (properties) hold the landed flux and photon count per
    cell, bilinearly splatted (the paper's scheme).
    Cell (i, j) covers chart x in origin_x + [j, j+1) * cell and
    y in origin_y + [i, i+1) * cell.
    """

    def __init__(self, name: str, chart: Chart, cell: float, estimate: MapEstimate):
        self.name, self.chart, self.cell, self.estimate = name, chart, cell, estimate
        self.shape = (max(1, int(math.ceil(chart.size[1] / cell))), max(1, int(math.ceil(chart.size[0] / cell))))
        # photon count (plane 0) and flux W (planes 1..3) landed per cell
        self._cells = np.zeros((4,) + self.shape)
        self.photons = 0
        self._tables = None
        # summed-area table of the share of each cell the receiver covers,
        # made at the first adaptive read; None: every cell is covered
        self._covered = None
        self._covered_ready = False
        self._lock = threading.Lock()

    def _cell_coords(self, xy: np.ndarray) -> np.ndarray:
        """(n,2) continuous (row, col) positions, cell centres at integers."""
        return (xy[:, ::-1] - self.chart.origin[::-1]) / self.cell - 0.5

    def add_photons(self, xy: np.ndarray, flux: np.ndarray, scale: np.ndarray) -> None:
        """Splat photons given in chart coordinates `xy (n,2)`, with flux
        (n,3) W and chart area per world area `scale (n,)` (the paper's
        figure 2). Safe to call from several threads."""
        with self._lock:
            bilinear_splat(self._cells, self._cell_coords(xy), np.c_[np.ones(len(xy)), flux * scale[:, None]])
            self.photons += len(xy)
            self._tables = None

    @property
    def flux(self) -> np.ndarray:
        """(h,w,3) W landed in each cell."""
        self.prepare()
        return np.moveaxis(self._cells[1:], 0, -1)

    @property
    def count(self) -> np.ndarray:
        """(h,w) photons landed in each cell (bilinear shares)."""
        self.prepare()
        return self._cells[0]

    def prepare(self) -> None:
        """Build the look-up tables, so that concurrent reads need no lock.
        The count's table serves only the adaptive estimate."""
        with self._lock:
            adaptive = self.estimate.k_nearest is not None
            if self._tables is None:
                self._tables = (summed_area_table(self._cells[0])[None] if adaptive else None,
                                channel_tables(self._cells[1:]))
            if adaptive and not self._covered_ready:
                share = self.chart.coverage(self.chart.origin, self.cell, self.shape)
                self._covered = None if share is None else summed_area_table(share)[None]
                self._covered_ready = True

    @property
    def nbytes(self) -> int:
        """Bytes of the map's arrays: its cells and their look-up tables."""
        tables = [t for t in (self._tables or ()) if t is not None]
        return self._cells.nbytes + sum(t.nbytes for t in tables) + (
            self._covered.nbytes if self._covered is not None else 0)

    def irradiance_at(self, xy: np.ndarray) -> np.ndarray:
        """Caustic irradiance (n,3) W/m^2 at chart coordinates `xy (n,2)`."""
        self.prepare()
        if self.estimate.k_nearest is None:
            out = bilinear_sample(self._cells[1:], self._cell_coords(xy)) / self.cell ** 2
        else:
            out = self._adaptive(xy, xy)
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        outside = (xy[:, 0] < lo[0]) | (xy[:, 1] < lo[1]) | (xy[:, 0] > hi[0]) | (xy[:, 1] > hi[1])
        out[outside] = 0.0
        return out

    def image_frame(self) -> ImageFrame:
        """Where the image of `irradiance()` lies on the receiver."""
        h, w = self.shape
        return self.chart.image_frame(self.chart.origin, np.array([w * self.cell, h * self.cell]))

    def irradiance(self, threads: int = 1) -> np.ndarray:
        """(h,w,3) W/m^2 in every cell (`_cell_irradiance`): the map a bake
        writes, read in bands of rows on up to `threads` threads. Row 0 is
        the chart's lowest y, the first row of `image_frame()`."""
        h, w = self.shape
        self.prepare()
        out = np.empty((h, w, 3))
        step = max(1, min(_BAKE_CELLS // w, -(-h // max(1, threads))))

        def fill(first: int) -> None:
            rows = range(first, min(first + step, h))
            out[rows.start:rows.stop] = self._cell_irradiance(rows).reshape(-1, w, 3)

        with ThreadPoolExecutor(max(1, threads)) as pool:
            list(pool.map(fill, range(0, h, step)))
        return out

    def _cell_irradiance(self, rows: range) -> np.ndarray:
        """(n,3) W/m^2 of the cells of `rows`, row by row: at their centres."""
        return self.irradiance_at((self._indices(rows) + 0.5) * self.cell + self.chart.origin)

    def _indices(self, rows: range) -> np.ndarray:
        """(n,2) (column, row) of the cells of `rows`, row by row."""
        cols, rows = np.meshgrid(np.arange(self.shape[1]), np.arange(rows.start, rows.stop))
        return np.stack([cols.ravel(), rows.ravel()], axis=1)

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Mean caustic irradiance (n,3) W/m^2 over chart rectangles [lo, hi]
        (each (n,2)): what a pixel whose footprint they stand for
        (`PlaneChart.footprint`) should show. The adaptive window is at
        least as large as the rectangle."""
        self.prepare()
        if self.estimate.k_nearest is None:
            return as_rgb(rect_means(self._tables[1], self.origin_rc, self.cell, lo, hi)) / self.cell ** 2
        return self._adaptive(lo, hi)

    def seen_mean(self, pixels: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Mean caustic irradiance (n,3) W/m^2 that the camera rays
        through flat image pixels `pixels (n,)` see, their footprints the
        chart rectangles [lo, hi] (`PlaneChart.footprint`)."""
        return self.mean_over(lo, hi)

    def sees(self, view) -> bool:
        """Whether the map serves camera `view` (screen_layer.ImageView)
        as well as the camera it was traced for."""
        return True

    @property
    def origin_rc(self) -> np.ndarray:
        """(2,) chart (y, x) of the grid's first corner."""
        return self.chart.origin[::-1]

    def _adaptive(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """(n,3) `_adaptive_estimate` over chart rectangles [lo, hi] ((n,2)
        each; lo = hi: at points)."""
        count_table, flux_table = self._tables
        covered = np.zeros((0, 1, 1)) if self._covered is None else self._covered
        out = np.empty((len(lo), 3))
        _adaptive_estimate(count_table[0], flux_table, covered, *float_rows(lo, hi),
                           np.ascontiguousarray(self.chart.origin, dtype=np.float64), float(self.estimate.k_nearest),
                           self.cell, out)
        return out


@inline
def _window_cell1(v, origin, cell, size):
    """The cell, of `size`, whose centre is nearest chart coordinate `v`
    along an axis from `origin` (continuous cell coordinate, centres at
    integers, rounded half up), clamped to the grid."""
    return min(max(int(np.floor(((v - origin) / cell - 0.5) + 0.5)), 0), size - 1)


@kernel("void(f8[:, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8, f8, f8[:, ::1])")
def _adaptive_estimate(count_table, flux_tables, covered, lo, hi, origin, k_nearest, cell, out):
    """Into `out (n,3)`, the irradiance W/m^2 of the adaptive estimate over
    each chart rectangle [lo, hi] ((n,2) each): the flux in the smallest
    square window about the cell nearest its centre, of half-width up to
    _MAX_WINDOW_RADIUS and at least the rectangle's (half its longer side
    in cells, less half a cell, rounded up), that holds `k_nearest`
    photons (a binary search, since the count only grows with the radius),
    over the window's area, the area the receiver covers in it where
    `covered (1, h+1, w+1)` (summed-area table of the covered share;
    (0,1,1): all) is given. Tables: `count_table (h+1, w+1)`, `flux_tables
    (c, h+1, w+1)` (c = 1: white, the same in each channel of `out`);
    the grid's first corner is chart point `origin (2,)` (x, y)."""
    h, w = count_table.shape[0] - 1, count_table.shape[1] - 1
    channels = len(flux_tables)
    for n in range(len(lo)):
        half = 0.5 * max(hi[n, 0] - lo[n, 0], hi[n, 1] - lo[n, 1]) / cell
        min_radius = int(np.ceil(half - 0.5))
        i = _window_cell1(0.5 * (lo[n, 1] + hi[n, 1]), origin[1], cell, h)
        j = _window_cell1(0.5 * (lo[n, 0] + hi[n, 0]), origin[0], cell, w)
        low, high = min(min_radius, _MAX_WINDOW_RADIUS), _MAX_WINDOW_RADIUS
        while low < high:
            mid = (low + high) // 2
            if box_sum(count_table, i, j, mid) >= k_nearest:
                high = mid
            else:
                low = mid + 1
        r = max(low, min_radius)
        if len(covered) == 0:
            cells = float((min(i + r + 1, h) - max(i - r, 0)) * (min(j + r + 1, w) - max(j - r, 0)))
        else:
            cells = box_sum(covered[0], i, j, r)
        for c in range(3):
            out[n, c] = 0.0
            if cells > 0:
                out[n, c] = box_sum(flux_tables[min(c, channels - 1)], i, j, r) / (cells * cell ** 2)


def auto_cell_size(chart: Chart, limit: int) -> float:
    """Cell edge (m) that fits the chart's longer side in `limit` cells."""
    return float(max(chart.size.max(), DIVISION_FLOOR) / limit)
