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
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..util.vectors import DIVISION_FLOOR
from .charts import Chart, ImageFrame
from .grid import as_rgb, bilinear_sample, bilinear_splat, box_sums, channel_tables, rect_means, summed_area_table

# Photons held back before a splat: as many as the map has cells (at least
# _MIN_FLUSH_PHOTONS), so the bincount over the whole grid costs at most about
# one pass per photon, and the splat's temporaries (~300 B a photon) stay
# bounded by the map's size, whatever the photon count.
_MIN_FLUSH_PHOTONS = 1 << 15
# Half-widths, in cells, of the windows the adaptive estimate tries. The
# largest bounds the blur: where fewer than k photons land within it, the
# estimate is its plain mean (zero far from any caustic), not a halo of flux
# borrowed from far away.
_WINDOW_RADII = np.arange(17)


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
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []
        self._pending_count = 0
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
        """Hold photons given in chart coordinates `xy (n,2)`, with flux
        (n,3) W and chart area per world area `scale (n,)`. They are
        splatted in large batches, when the pending ones outnumber the map's
        cells or the map is read. Safe to call from several threads."""
        with self._lock:
            self._pending.append((xy, flux * scale[:, None]))
            self._pending_count += len(xy)
            self.photons += len(xy)
            self._tables = None
            if self._pending_count >= max(_MIN_FLUSH_PHOTONS, self.shape[0] * self.shape[1]):
                self._flush()

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
        """Splat what is pending and build the look-up tables, so that
        concurrent reads need no lock. The count's table serves only the
        adaptive estimate."""
        with self._lock:
            self._flush()
            adaptive = self.estimate.k_nearest is not None
            if self._tables is None:
                self._tables = (summed_area_table(self._cells[0])[None] if adaptive else None,
                                channel_tables(self._cells[1:]))
            if adaptive and not self._covered_ready:
                share = self.chart.coverage(self.chart.origin, self.cell, self.shape)
                self._covered = None if share is None else summed_area_table(share)[None]
                self._covered_ready = True

    def _flush(self) -> None:
        """Splat the pending photons (the paper's figure 2)."""
        if not self._pending:
            return
        xy = np.concatenate([p[0] for p in self._pending])
        flux = np.concatenate([p[1] for p in self._pending])
        self._pending, self._pending_count = [], 0
        bilinear_splat(self._cells, self._cell_coords(xy), np.c_[np.ones(len(xy)), flux])

    def irradiance_at(self, xy: np.ndarray) -> np.ndarray:
        """Caustic irradiance (n,3) W/m^2 at chart coordinates `xy (n,2)`."""
        self.prepare()
        if self.estimate.k_nearest is None:
            out = bilinear_sample(self._cells[1:], self._cell_coords(xy)) / self.cell ** 2
        else:
            out = self._adaptive(xy)
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        outside = (xy[:, 0] < lo[0]) | (xy[:, 1] < lo[1]) | (xy[:, 0] > hi[0]) | (xy[:, 1] > hi[1])
        out[outside] = 0.0
        return out

    def image_frame(self) -> ImageFrame:
        """Where the image of `irradiance()` lies on the receiver."""
        h, w = self.shape
        return self.chart.image_frame(self.chart.origin, np.array([w * self.cell, h * self.cell]))

    def irradiance(self) -> np.ndarray:
        """(h,w,3) W/m^2 at every cell centre: the map a bake writes. Row 0
        is the chart's lowest y, the first row of `image_frame()`."""
        h, w = self.shape
        rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        xy = np.stack([(cols.ravel() + 0.5) * self.cell, (rows.ravel() + 0.5) * self.cell], axis=1)
        return self.irradiance_at(xy + self.chart.origin).reshape(h, w, 3)

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Mean caustic irradiance (n,3) W/m^2 over chart rectangles [lo, hi]
        (each (n,2)): what a pixel whose footprint they stand for
        (`PlaneChart.footprint`) should show. The adaptive window is at
        least as large as the rectangle."""
        self.prepare()
        if self.estimate.k_nearest is None:
            return as_rgb(rect_means(self._tables[1], self.origin_rc, self.cell, lo, hi)) / self.cell ** 2
        half = 0.5 * np.maximum(hi[:, 0] - lo[:, 0], hi[:, 1] - lo[:, 1]) / self.cell
        return self._adaptive(0.5 * (lo + hi), np.ceil(half - 0.5).astype(np.int64))

    @property
    def origin_rc(self) -> np.ndarray:
        """(2,) chart (y, x) of the grid's first corner."""
        return self.chart.origin[::-1]

    def _adaptive(self, xy: np.ndarray, min_radius: np.ndarray = 0) -> np.ndarray:
        count_table, flux_table = self._tables
        h, w = self.shape
        rc = np.floor(self._cell_coords(xy) + 0.5).astype(np.int64)
        i, j = np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)
        # Smallest window holding k photons, and at least min_radius: a binary
        # search per point over _WINDOW_RADII, since the count only grows with
        # the radius.
        lo = np.searchsorted(_WINDOW_RADII, np.minimum(min_radius, _WINDOW_RADII[-1]) * np.ones(len(xy), np.int64))
        hi = np.full(len(xy), len(_WINDOW_RADII) - 1)
        active = lo < hi
        while active.any():
            mid = (lo + hi) // 2
            enough = box_sums(count_table, i, j, _WINDOW_RADII[mid])[:, 0] >= self.estimate.k_nearest
            hi = np.where(active & enough, mid, hi)
            lo = np.where(active & ~enough, mid + 1, lo)
            active = lo < hi
        radius = np.maximum(_WINDOW_RADII[lo], min_radius)
        flux = box_sums(flux_table, i, j, radius)
        if self._covered is None:
            cells = (np.minimum(i + radius + 1, h) - np.maximum(i - radius, 0)) * (
                np.minimum(j + radius + 1, w) - np.maximum(j - radius, 0))
        else:
            cells = box_sums(self._covered, i, j, radius)[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(cells[:, None] > 0, as_rgb(flux) / (cells * self.cell ** 2)[:, None], 0.0)


def auto_cell_size(chart: Chart, limit: int) -> float:
    """Cell edge (m) that fits the chart's longer side in `limit` cells."""
    return float(max(chart.size.max(), DIVISION_FLOOR) / limit)
