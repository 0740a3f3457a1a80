"""The illumination map of beam mode: beams rasterised with exact area
coverage, plus the ordinary density estimate of the fallback photons."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..util.rows import take_rows
from .grid import bilinear_sample, channel_tables, rect_means
from .illumination_map import IlluminationMap
from .raster import rasterise_triangles, signed_areas


@dataclass
class _Layer:
    """A grid of irradiance `values (c,h,w)` W/m^2, each cell the exact mean
    over it, cells of edge `cell` m from chart corner `origin (2,)` (x, y),
    and its summed-area tables (c, h+1, w+1). One channel (c = 1) holds
    white light."""

    origin: np.ndarray
    cell: float
    values: np.ndarray
    tables: np.ndarray

    @staticmethod
    def of_beams(lo: np.ndarray, hi: np.ndarray, cell: float, corners: np.ndarray,
                 irradiance: np.ndarray) -> "_Layer":
        """Beams `corners (m,3,2)` chart metres, `irradiance (m,3)` W/m^2,
        rasterised over the chart box [lo, hi]; parts outside it are dropped."""
        shape = tuple(np.maximum(np.ceil((hi - lo) / cell).astype(int), 1)[::-1])
        if (irradiance == irradiance[:, :1]).all():
            irradiance = irradiance[:, :1]
        values = np.ascontiguousarray(rasterise_triangles(shape, (corners - lo) / cell, irradiance))
        return _Layer(lo, cell, values, channel_tables(values))

    def _rc(self, xy: np.ndarray) -> np.ndarray:
        """(n,2) continuous (row, col), cell centres at integers."""
        return (xy[:, ::-1] - self.origin[::-1]) / self.cell - 0.5

    def at(self, xy: np.ndarray) -> np.ndarray:
        """(n,c) W/m^2 at chart points `xy (n,2)`, bilinear between cell
        centres; zero off the layer."""
        rc = self._rc(xy)
        top = np.array(self.values.shape[1:]) - 0.5
        inside = (rc[:, 0] >= -0.5) & (rc[:, 1] >= -0.5) & (rc[:, 0] <= top[0]) & (rc[:, 1] <= top[1])
        out = np.zeros((len(xy), len(self.values)))
        out[inside] = bilinear_sample(self.values, rc[inside])
        return out

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """(n,c) mean W/m^2 over chart rectangles [lo, hi] ((n,2) each); only
        those that meet the layer are looked up."""
        end = self.origin + self.cell * np.array(self.values.shape[:0:-1])
        meets = ((hi[:, 0] > self.origin[0]) & (hi[:, 1] > self.origin[1])
                 & (lo[:, 0] < end[0]) & (lo[:, 1] < end[1]))
        out = np.zeros((len(lo), len(self.values)))
        out[meets] = rect_means(self.tables, self.origin[::-1], self.cell, *take_rows(meets, lo, hi))
        return out


def _weighted_quantiles(values: np.ndarray, weights: np.ndarray, q) -> np.ndarray:
    order = np.argsort(values)
    cdf = np.cumsum(weights[order])
    return values[order][np.searchsorted(cdf, np.asarray(q) * cdf[-1]).clip(0, len(values) - 1)]


class BeamMap(IlluminationMap):
    """An illumination map whose caustic comes from beams, plus the ordinary
    density estimate of the fallback photons it holds.

    Beams are rasterised with exact area coverage (`raster.py`), so flux is
    conserved exactly and a beam squeezed to nothing at a fold cannot spike.
    Beams under 2 map cells across (the sharp part of a caustic) go to a grid
    FINE times finer, laid over where 99.9% of their flux lands (at most
    FINE_LIMIT cells a side); beams COARSE cells across or more (dim, wide
    light) to a grid COARSE_CELL times coarser; the others to the map's own
    grid. Each layer spans only its beams' bounding box.
    """

    FINE = 8
    FINE_LIMIT = 2048
    COARSE = 16
    COARSE_CELL = 4

    def __init__(self, *args, threads: int = 1, **kwargs):
        super().__init__(*args, **kwargs)
        self.threads = threads
        self._beam_parts: list[tuple[np.ndarray, np.ndarray]] = []
        self._layers: list[_Layer] = []
        self.beams = 0

    def add_beams(self, corners: np.ndarray, irradiance: np.ndarray) -> None:
        """Beams `corners (m,3,2)` chart metres, `irradiance (m,3)` W/m^2."""
        with self._lock:
            self._beam_parts.append((corners, irradiance))
            self.beams += len(corners)

    def _take_layer_specs(self) -> list[tuple]:
        """Takes the pending beams and sorts them into layers: returns the
        `_Layer.of_beams` arguments of each."""
        corners = np.concatenate([c for c, _ in self._beam_parts])
        irradiance = np.concatenate([e for _, e in self._beam_parts])
        self._beam_parts = []
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        size = np.ptp(corners, axis=1).max(axis=1) / self.cell
        small = size < 2.0
        specs = []
        if small.any():
            centre = corners[small].mean(axis=1)
            flux = irradiance[small].sum(axis=1) * np.abs(signed_areas(corners[small]))
            bounds = np.array([_weighted_quantiles(centre[:, a], flux, (5e-4, 1 - 5e-4)) for a in (0, 1)])
            small[small] = ((centre >= bounds[:, 0]) & (centre <= bounds[:, 1])).all(axis=1)
            # a small beam reaches at most 2 map cells from its centre
            fine_lo, fine_hi = bounds[:, 0] - 2.0 * self.cell, bounds[:, 1] + 2.0 * self.cell
            cell = max(self.cell / self.FINE, float((fine_hi - fine_lo).max()) / self.FINE_LIMIT)
            specs.append((fine_lo, fine_hi, cell, corners[small], irradiance[small]))
        large = size >= self.COARSE
        for chosen, cell in ((~small & ~large, self.cell), (large, self.COARSE_CELL * self.cell)):
            if chosen.any():
                # over the chosen beams' bounding box only
                points = corners[chosen].reshape(-1, 2)
                box_lo, box_hi = np.maximum(lo, points.min(axis=0)), np.minimum(hi, points.max(axis=0))
                specs.append((box_lo, box_hi + cell, cell, corners[chosen], irradiance[chosen]))
        return specs

    def prepare(self) -> None:
        """Rasterise the pending beams, a layer per thread (of `threads`),
        and prepare the fallback photons' map."""
        super().prepare()
        with self._lock:
            if self._beam_parts:
                specs = self._take_layer_specs()
                with ThreadPoolExecutor(max(1, min(self.threads, len(specs)))) as pool:
                    self._layers += pool.map(lambda spec: _Layer.of_beams(*spec), specs)

    def irradiance_at(self, xy: np.ndarray) -> np.ndarray:
        return super().irradiance_at(xy) + sum(layer.at(xy) for layer in self._layers)

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return super().mean_over(lo, hi) + sum(layer.mean_over(lo, hi) for layer in self._layers)
