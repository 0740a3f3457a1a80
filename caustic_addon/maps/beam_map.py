"""The illumination map of beam mode: beams rasterised with exact area
coverage, plus the ordinary density estimate of the fallback photons."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ..util.jit import kernel
from ..util.rows import take_rows
from .grid import add_cell_means, add_within, channel_tables, rect_means
from .illumination_map import IlluminationMap
from .raster import Coverage, signed_areas
from .screen_layer import ImageView, ScreenLayer


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
    def of_coverage(grid: "_LayerGrid") -> "_Layer":
        values = np.ascontiguousarray(grid.coverage.planes())
        return _Layer(grid.lo, grid.cell, values, channel_tables(values))

    def add_at(self, xy: np.ndarray, out: np.ndarray) -> None:
        """out (n,3) += W/m^2 at chart points `xy (n,2)`, bilinear between
        cell centres; nothing off the layer."""
        add_within(self.values, self.origin, self.cell, xy, out)

    def add_cell_means(self, grid_origin: np.ndarray, step: float, rows: range, columns: int,
                       out: np.ndarray) -> None:
        """out (n,3) += `mean_over` each cell of edge `step` from chart point
        `grid_origin (2,)`, of rows `rows` and columns 0..columns-1, row by
        row (grid.add_cell_means)."""
        add_cell_means(self.tables, self.origin, self.cell, grid_origin, step, rows, columns, out)

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


class _LayerGrid:
    """A layer being rasterised: cells of edge `cell` m over the chart box
    [lo (2,), hi (2,)], on the lattice of such cells from chart point
    `anchor (2,)` (so that layers of one cell laid over different boxes
    share their cells), and the coverage of the beams added so far (one
    channel while they are all white)."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, cell: float, anchor: np.ndarray):
        lo = anchor + np.floor((lo - anchor) / cell) * cell
        self.lo, self.cell = lo, cell
        self.coverage = Coverage(tuple(np.maximum(np.ceil((hi - lo) / cell).astype(int), 1)[::-1]), 1)

    def add_jobs(self, corners: np.ndarray, irradiance: np.ndarray, share: np.ndarray, white: bool,
                 bands: int) -> list[Callable[[], None]]:
        """Jobs that add beams `corners (m,k,2)` chart metres, `irradiance
        (m,3)` W/m^2, times `share (m,)`, all `white` or not, a band of the
        grid's rows each (Coverage.add_jobs); parts outside the box are
        dropped."""
        if not white:
            self.coverage.widen(3)
        return self.coverage.add_jobs(corners, irradiance, self.lo, self.cell, share, bands)


def _split(values: np.ndarray, groups: list) -> list[np.ndarray]:
    """`values (m,)` cut into the parts of `groups` (of m in all, in order)."""
    return np.split(values, np.cumsum([len(group) for group in groups])[:-1])


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


@kernel("Tuple((f8[::1], f8[:, ::1]))(f8[:, :, ::1])")
def _spans(corners):
    """(span (m,), centre (m,2)) of triangles `corners (m,3,2)` (or
    polygons, (m,k,2)): the longer side of each one's bounding box, and the
    mean of its corners."""
    span, centre = np.empty(len(corners)), np.empty((len(corners), 2))
    count = corners.shape[1]
    for t in range(len(corners)):
        span[t] = 0.0
        for a in range(2):
            c0, c1, c2 = corners[t, 0, a], corners[t, 1, a], corners[t, 2, a]
            low, high, total = min(min(c0, c1), c2), max(max(c0, c1), c2), c0 + c1 + c2
            for k in range(3, count):
                low, high, total = min(low, corners[t, k, a]), max(high, corners[t, k, a]), total + corners[t, k, a]
            span[t] = max(span[t], high - low)
            centre[t, a] = total / count
    return span, centre


@kernel("UniTuple(f8[::1], 2)(f8[:, :, ::1], b1[::1])")
def _bounding_box(corners, chosen):
    """(lo (2,), hi (2,)) the box around the `chosen (m,)` triangles (or
    polygons) of `corners (m,k,2)`."""
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    for t in range(len(corners)):
        if chosen[t]:
            for k in range(corners.shape[1]):
                for a in range(2):
                    lo[a], hi[a] = min(lo[a], corners[t, k, a]), max(hi[a], corners[t, k, a])
    return lo, hi


class BeamMap(IlluminationMap):
    """An illumination map whose caustic comes from beams, plus the ordinary
    density estimate of the fallback photons it holds.

    Beams are rasterised with exact area coverage (`raster.py`), so flux is
    conserved exactly and a beam squeezed to nothing at a fold cannot spike.
    Beams under 2 to 4 map cells across (the sharp part of a caustic) go
    to a grid FINE times finer (coarser by steps of 2^(1/4) where that would
    take more than FINE_LIMIT cells a side), laid over where the flux of
    the bright ones lands, all of it but FINE_TAIL each side; beams about
    24 cells across or more (dim, wide light) to a grid COARSE_CELL times
    coarser; the others to the map's own grid, each
    beam's light shared between two layers where its size is in between
    (`layer_shares`). Each layer spans only its beams' bounding box. A map
    read only at its own cells (a bake's image: `sub_cell` False) has no
    fine layer: its small beams go to its own grid, where exact coverage
    gives each cell its exact mean, which an unaligned fine layer would only
    approximate.

    On a flat receiver the beams also go to a `screen` layer
    (screen_layer.py), which gives the pixels that see the receiver the
    beams' exact mean over them. The first KEPT_BEAMS beams are kept, so
    that a camera moved between renders can have its own screen layer
    without tracing the lamps again (`sees`).
    """

    FINE = 8
    FINE_LIMIT = 2048
    FINE_RAMP = (2.0, 4.0)
    COARSE_RAMP = (16.0, 32.0)
    COARSE_CELL = 4
    # Beams held back before they are rasterised: bounds their memory (about
    # 100 B a beam) whatever the number of lamp rays.
    FLUSH_BEAMS = 1 << 20
    # The fine grid laid out from the first FLUSH_BEAMS beams spans their
    # flux's box widened by this share of it on each side.
    FINE_PAD = 0.1
    # The fine grid spans all but FINE_TAIL of the flux, on each side, of the
    # small beams at least FINE_BRIGHTNESS times the irradiance that the
    # brightest 1% of their flux exceeds: the caustic, a lens's fold ring
    # a hundred times dimmer than its focus among it, not the dim light (a
    # reflection off the glass) that many lamp rays also cut into small
    # beams all over the receiver. (A quantile weighted by flux times
    # irradiance was the focus's box: the ball lens's fold ring, 125 mm off
    # the axis, fell outside it at four points, and its fold pixels were up
    # to 50% off on the map's own cells.)
    FINE_BRIGHTNESS = 1e-3
    FINE_TAIL = 1e-5
    # Beams kept for another camera's screen layer (about 72 B a beam); a
    # map with more traces the lamps again when the camera moves.
    KEPT_BEAMS = 1 << 20
    # Bands of rows each layer is rasterised in, per thread: a caustic
    # crowds into a few rows, and the threads share them out as they go.
    RASTER_BANDS = 4

    def __init__(self, *args, threads: int = 1, screen: Optional[ScreenLayer] = None, sub_cell: bool = True,
                 **kwargs):
        super().__init__(*args, **kwargs)
        self.threads, self.screen, self.sub_cell = threads, screen, sub_cell
        self._kept: Optional[list[tuple[np.ndarray, np.ndarray]]] = None if screen is None else []
        self._beam_parts: list[tuple[np.ndarray, np.ndarray]] = []
        self._pending_beams = 0
        self._grids: Optional[list[Optional[_LayerGrid]]] = None
        self._layers: list[_Layer] = []
        self.beams = 0
        self._held = 0

    @property
    def nbytes(self) -> int:
        """Bytes of the map's arrays: its photons' cells, its layers and
        the beams it keeps (not its screen layer's coverage)."""
        layers = sum(layer.values.nbytes + layer.tables.nbytes for layer in self._layers)
        kept = sum(corners.nbytes + light.nbytes for corners, light in self._kept or ())
        return super().nbytes + layers + kept

    def add_beams(self, corners: np.ndarray, irradiance: np.ndarray) -> None:
        """Beams `corners (m,k,2)` chart metres (triangles, or convex
        polygons: beams spread over a lamp's cell), `irradiance (m,3)` W/m^2.
        Past FLUSH_BEAMS pending, they are rasterised into layers laid out
        over the whole chart (but the fine one, laid over the first ones'
        flux), so that later beams find a layer wherever they land. Beams
        are counted for FLUSH_BEAMS and KEPT_BEAMS as the triangles their
        memory holds, a polygon of k corners as k / 3."""
        size = len(corners) * corners.shape[1] // 3
        with self._lock:
            self._beam_parts.append((corners, irradiance))
            self._pending_beams += size
            self._held += size
            self.beams += len(corners)
            if self._kept is not None and self._held > self.KEPT_BEAMS:
                self._kept = None
            elif self._kept is not None:
                self._kept.append((corners, irradiance))
            if self._pending_beams >= self.FLUSH_BEAMS:
                self._rasterise_pending(whole_chart=True)

    def _layout(self, groups: list[np.ndarray], centres: np.ndarray, irradiance: np.ndarray, fine: np.ndarray,
                coarse: np.ndarray, whole_chart: bool) -> list[Optional[_LayerGrid]]:
        """The (fine, own, coarse) layer grids for beams `groups` (their
        corners (m_i,k_i,2), in order; `centres (m,2)` of them all) with
        `fine, coarse (m,)` shares of the fine
        and coarse layers: the fine one over where the bright ones' flux
        lands (FINE_BRIGHTNESS, FINE_TAIL), the others over the chart, or
        over their beams' bounding box unless `whole_chart`; None for a
        layer no beam has a share of."""
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        grids: list[Optional[_LayerGrid]] = [None, None, None]
        small = fine > 0.0
        if small.any():
            centre = np.take(centres, np.flatnonzero(small), axis=0)
            brightness = np.take(irradiance[:, 0] + irradiance[:, 1] + irradiance[:, 2], np.flatnonzero(small))
            areas = np.concatenate([signed_areas(np.take(corners, np.flatnonzero(chosen), axis=0))
                                    for corners, chosen in zip(groups, _split(small, groups))])
            flux = fine[small] * brightness * np.abs(areas)
            bright = brightness >= self.FINE_BRIGHTNESS * _weighted_quantiles(brightness, flux, 0.99)
            tails = (self.FINE_TAIL, 1.0 - self.FINE_TAIL)
            bounds = np.array([_weighted_quantiles(centre[bright, a], flux[bright], tails) for a in (0, 1)])
            # the map's cell over FINE, widened in steps of 2^(1/4) to fit
            # FINE_LIMIT cells: grids laid out from different beams over
            # about the same box share a lattice
            cell = self.cell / self.FINE
            while float((bounds[:, 1] - bounds[:, 0]).max()) / cell > self.FINE_LIMIT and cell < self.cell:
                cell *= 2.0 ** 0.25
            if whole_chart:
                # the first beams stand for all of them: leave room for those that land further out
                bounds += np.outer(bounds[:, 1] - bounds[:, 0], [-self.FINE_PAD, self.FINE_PAD])
            # a beam with a fine share reaches at most 4 map cells from its
            # centre, and one whose centre is up to 4 cells outside the box
            # still goes to it (the caustic's outermost fold is the box's edge)
            fine_lo, fine_hi = bounds[:, 0] - 8.0 * self.cell, bounds[:, 1] + 8.0 * self.cell
            grids[0] = _LayerGrid(fine_lo, fine_hi, cell, lo)
        # the own grid also takes the fine share of beams outside the fine grid
        for k, chosen, cell in ((1, coarse < 1.0, self.cell), (2, coarse > 0.0, self.COARSE_CELL * self.cell)):
            if whole_chart:
                grids[k] = _LayerGrid(lo, hi, cell, lo)
            elif chosen.any():
                boxes = [_bounding_box(corners, part) for corners, part in zip(groups, _split(chosen, groups))]
                box_lo = np.min([box[0] for box in boxes], axis=0)
                box_hi = np.max([box[1] for box in boxes], axis=0)
                grids[k] = _LayerGrid(np.maximum(lo, box_lo), np.minimum(hi, box_hi), cell, lo)
        return grids

    def _rasterise_pending(self, whole_chart: bool) -> None:
        """Share the pending beams among the layers by their size
        (`layer_shares`) and add them to the layers' grids, laying those out
        first if there are none; a beam whose centre is outside the fine
        grid's box gives its fine share to the map's own grid. Each layer
        is rasterised on a thread of its own (of `threads`); triangles and
        polygons of each number of corners one kind after another, each
        kind in an array of its own."""
        kinds = sorted({c.shape[1] for c, _ in self._beam_parts})
        groups = [[part for part in self._beam_parts if part[0].shape[1] == k] for k in kinds]
        groups = [(np.ascontiguousarray(np.concatenate([c for c, _ in group]), dtype=np.float64),
                   np.ascontiguousarray(np.concatenate([e for _, e in group]), dtype=np.float64)) for group in groups]
        self._beam_parts, self._pending_beams = [], 0
        spans = [_spans(corners) for corners, _ in groups]
        span, centres = np.concatenate([s for s, _ in spans]), np.concatenate([c for _, c in spans])
        irradiance = np.concatenate([e for _, e in groups])
        fine, coarse = layer_shares(span / self.cell)
        if not self.sub_cell:
            fine[:] = 0.0
        if self._grids is None:
            self._grids = self._layout([corners for corners, _ in groups], centres, irradiance, fine, coarse,
                                       whole_chart)
        grid = self._grids[0]
        if grid is not None:
            lo = grid.lo + 4.0 * self.cell
            hi = grid.lo + grid.cell * np.array(grid.coverage.shape[::-1]) - 4.0 * self.cell
            x, y = centres[:, 0], centres[:, 1]
            fine = np.where((x >= lo[0]) & (y >= lo[1]) & (x <= hi[0]) & (y <= hi[1]), fine, 0.0)
        else:
            fine = np.zeros(len(span))
        bands = self.RASTER_BANDS * self.threads
        arrays = [corners for corners, _ in groups]
        for (corners, light), fine_k, coarse_k in zip(groups, _split(fine, arrays), _split(coarse, arrays)):
            shares = (fine_k, (1.0 - fine_k) * (1.0 - coarse_k), coarse_k)
            coloured = (light[:, 0] != light[:, 1]) | (light[:, 0] != light[:, 2])
            work = [job for g, share in zip(self._grids, shares) if g is not None and (share > 0).any()
                    for job in g.add_jobs(corners, light, share, not (coloured & (share > 0.0)).any(), bands)]
            if self.screen is not None:
                work += self.screen.add_jobs(corners, light, bands)
            with ThreadPoolExecutor(max(1, min(self.threads, len(work)))) as pool:
                list(pool.map(lambda job: job(), work))

    def prepare(self) -> None:
        """Rasterise the pending beams and turn the layers' grids into
        look-up tables, and prepare the fallback photons' map."""
        super().prepare()
        with self._lock:
            if self._beam_parts:
                self._rasterise_pending(whole_chart=False)
            if self._grids is not None:
                self._layers += [_Layer.of_coverage(g) for g in self._grids if g is not None]
                self._grids = None
            if self.screen is not None:
                self.screen.prepare()

    def sees(self, view: ImageView) -> bool:
        """Whether the map has (or, from its kept beams, now makes) the
        screen layer of camera `view`, where it has one."""
        if self.screen is None or self.screen.view == view:
            return True
        if self._kept is None:
            return False
        self.prepare()
        screen = self.screen.for_view(view)
        for corners, irradiance in self._kept:
            screen.add(corners, irradiance)
        screen.prepare()
        self.screen = screen
        return True

    def seen_mean(self, pixels: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        if self.screen is None:
            return self.mean_over(lo, hi)
        return IlluminationMap.mean_over(self, lo, hi) + self.screen.at(pixels)

    def irradiance_at(self, xy: np.ndarray) -> np.ndarray:
        beams = np.zeros((len(xy), 3))
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        for layer in self._layers:
            layer.add_at(xy, beams)
        return super().irradiance_at(xy) + beams

    def _cell_irradiance(self, rows: range) -> np.ndarray:
        """The fallback photons' estimate at each cell's centre plus the
        beams' exact mean over it, so that a bake keeps each beam's flux in
        the cells it covers (a point sample of the finer layers would alias
        the caustic's sharp lines)."""
        lo = self.chart.origin + self.cell * self._indices(rows)
        band = IlluminationMap.irradiance_at(self, lo + 0.5 * self.cell)
        for layer in self._layers:
            layer.add_cell_means(self.chart.origin, self.cell, rows, self.shape[1], band)
        return band

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return super().mean_over(lo, hi) + sum(layer.mean_over(lo, hi) for layer in self._layers)
