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
        """(n,c) mean W/m^2 over chart rectangles [lo, hi] ((n,2) each),
        each widened to at least one cell: the mean over a cell-sized box
        about a point is the bilinear look-up there, so a footprint smaller
        than a cell reads the layer smoothly, not as cell-sized blocks. Only
        rectangles that meet the layer are looked up."""
        centre, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 0.5 * self.cell)
        lo, hi = centre - half, centre + half
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


def layer_shares(size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(fine (m,), coarse (m,)) shares of beams `size (m,)` map cells across
    that go to the fine layer and to the coarse one; the rest goes to the
    map's own grid. Each share ramps linearly with the beam's size, over
    [BeamMap.FINE_RAMP] for the fine layer and [BeamMap.COARSE_RAMP] for the
    coarse one: a hard cut would give neighbouring beams of about the same
    size to layers of different cells, and the edge between the two sets
    would show as stair-steps wherever a layer is read finer than its
    cells."""
    (f0, f1), (c0, c1) = BeamMap.FINE_RAMP, BeamMap.COARSE_RAMP
    return np.clip((f1 - size) / (f1 - f0), 0.0, 1.0), np.clip((size - c0) / (c1 - c0), 0.0, 1.0)


class BeamMap(IlluminationMap):
    """An illumination map whose caustic comes from beams, plus the ordinary
    density estimate of the fallback photons it holds.

    Beams are rasterised with exact area coverage (`raster.py`), so flux is
    conserved exactly and a beam squeezed to nothing at a fold cannot spike.
    Beams under about 2 map cells across (the sharp part of a caustic) go
    to a grid FINE times finer, laid over where 99.9% of their flux lands (at
    most FINE_LIMIT cells a side); beams about 24 cells across or more (dim,
    wide light) to a grid COARSE_CELL times coarser; the others to the map's
    own grid, each beam's light shared between two layers where its size is
    in between (`layer_shares`). Each layer spans only its beams' bounding
    box.
    """

    FINE = 8
    FINE_LIMIT = 2048
    FINE_RAMP = (1.0, 2.5)
    COARSE_RAMP = (16.0, 32.0)
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
        """Takes the pending beams and shares each among the layers by its
        size (`layer_shares`): returns the `_Layer.of_beams` arguments of
        each layer."""
        corners = np.concatenate([c for c, _ in self._beam_parts])
        irradiance = np.concatenate([e for _, e in self._beam_parts])
        self._beam_parts = []
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        fine, coarse = layer_shares(np.ptp(corners, axis=1).max(axis=1) / self.cell)
        specs = []
        small = fine > 0.0
        if small.any():
            centre = corners[small].mean(axis=1)
            flux = fine[small] * irradiance[small].sum(axis=1) * np.abs(signed_areas(corners[small]))
            bounds = np.array([_weighted_quantiles(centre[:, a], flux, (5e-4, 1 - 5e-4)) for a in (0, 1)])
            small[small] = ((centre >= bounds[:, 0]) & (centre <= bounds[:, 1])).all(axis=1)
            fine = np.where(small, fine, 0.0)
            # a beam with a fine share reaches at most 2.5 map cells from its centre
            fine_lo, fine_hi = bounds[:, 0] - 2.5 * self.cell, bounds[:, 1] + 2.5 * self.cell
            cell = max(self.cell / self.FINE, float((fine_hi - fine_lo).max()) / self.FINE_LIMIT)
            specs.append((fine_lo, fine_hi, cell, corners[small], irradiance[small] * fine[small, None]))
        own = (1.0 - fine) * (1.0 - coarse)
        for share, cell in ((own, self.cell), (coarse, self.COARSE_CELL * self.cell)):
            chosen = share > 0.0
            if chosen.any():
                # over the chosen beams' bounding box only
                points = corners[chosen].reshape(-1, 2)
                box_lo, box_hi = np.maximum(lo, points.min(axis=0)), np.minimum(hi, points.max(axis=0))
                specs.append((box_lo, box_hi + cell, cell, corners[chosen], irradiance[chosen] * share[chosen, None]))
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

    def irradiance(self) -> np.ndarray:
        """(h,w,3) W/m^2 in every cell: the fallback photons' estimate at its
        centre plus the beams' exact mean over it, so that a bake keeps each
        beam's flux in the cells it covers (a point sample of the finer
        layers would alias the caustic's sharp lines)."""
        h, w = self.shape
        rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        lo = self.chart.origin + self.cell * np.stack([cols.ravel(), rows.ravel()], axis=1)
        self.prepare()
        out = IlluminationMap.irradiance_at(self, lo + 0.5 * self.cell)
        for layer in self._layers:
            out += layer.mean_over(lo, lo + self.cell)
        return out.reshape(h, w, 3)

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return super().mean_over(lo, hi) + sum(layer.mean_over(lo, hi) for layer in self._layers)
