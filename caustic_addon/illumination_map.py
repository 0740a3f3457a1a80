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
map's grid). Window sums come from summed-area tables, four reads per window.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .accel import triangle_normals
from .emission import orthonormal_basis
from .scene import Object

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


class Chart:
    """A receiver's 2D parameterisation in metres.

    origin (2,) and size (2,): the rectangle of chart coordinates it covers.
    """

    origin: np.ndarray
    size: np.ndarray

    def coords(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(n,2) chart coordinates of surface points given by triangle `prim`
        (local index), barycentrics `u, v` and world position `points (n,3)`."""
        raise NotImplementedError

    def area_scale(self, prim: np.ndarray) -> np.ndarray:
        """(n,) chart area per world area at triangle `prim`."""
        raise NotImplementedError


class PlaneChart(Chart):
    """A flat receiver: coordinates along two unit axes in its plane."""

    def __init__(self, point: np.ndarray, normal: np.ndarray, vertices: np.ndarray):
        self.point, self.normal = point, normal
        self.axis_x, self.axis_y = orthonormal_basis(normal)
        local = self._local(vertices)
        self.origin, self.size = local.min(axis=0), np.ptp(local, axis=0)

    def _local(self, points: np.ndarray) -> np.ndarray:
        rel = points - self.point
        return np.stack([rel @ self.axis_x, rel @ self.axis_y], axis=1)

    def coords(self, prim, u, v, points):
        return self._local(points)

    def area_scale(self, prim):
        return np.ones(len(prim))

    def footprint(self, origins: np.ndarray, dirs: np.ndarray, d_origins: np.ndarray, d_dirs: np.ndarray,
                  stratum: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The chart rectangle that stands for the footprint of a pixel
        stratum, `stratum` pixels wide, around each ray `origins, dirs
        (n,3)` whose change per pixel step is `d_origins, d_dirs (n,2,3)`
        (camera.ray_differentials): (lo (n,2), hi (n,2), ok (n,) bool); not
        ok where the ray misses the plane.

        To first order the footprint is the parallelogram that J, the chart
        point's derivative per pixel step (2x2), spans around the hit, and a
        pixel is the mean over its square, uniform in pixel space. The
        rectangle with the same centre and, along each chart axis, the same
        variance (J_x^2 + J_y^2) stratum^2 / 12 keeps that mean to second
        order along each axis; the parallelogram's bounding box is wider
        where it is sheared (off the image's centre lines) and blurs a
        caustic's fold. The hit moves by dp = do + s dd - d (N.(do + s dd))
        / (N.d), s the distance along the ray (Igehy 1999)."""
        along = dirs @ self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            s = ((self.point - origins) @ self.normal) / along
        ok = np.isfinite(s) & (s > 0)
        s, along = np.where(ok, s, 0.0), np.where(ok, along, 1.0)
        moved = (d_origins + s[:, None, None] * d_dirs).reshape(-1, 3)
        across = np.repeat(dirs / along[:, None], 2, axis=0)
        d_points = moved - across * (moved @ self.normal)[:, None]
        jacobian = (d_points @ np.stack([self.axis_x, self.axis_y], axis=1)).reshape(-1, 2, 2)
        half = 0.5 * stratum * np.sqrt(jacobian[:, 0] ** 2 + jacobian[:, 1] ** 2)
        centre = self._local(origins + s[:, None] * dirs)
        return centre - half, centre + half, ok

    def world(self, xy: np.ndarray) -> np.ndarray:
        """(n,3) world points of chart coordinates `xy (n,2)`."""
        return self.point + xy[:, :1] * self.axis_x + xy[:, 1:] * self.axis_y


class UVChart(Chart):
    """A curved receiver, through its UV map scaled to metres: one UV unit is
    `metres_per_uv` metres, chosen so that chart and world areas agree in total."""

    def __init__(self, corner_uvs: np.ndarray, world_areas: np.ndarray):
        self.corner_uvs = corner_uvs
        e1, e2 = corner_uvs[:, 1] - corner_uvs[:, 0], corner_uvs[:, 2] - corner_uvs[:, 0]
        uv_areas = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        self.metres_per_uv = math.sqrt(world_areas.sum() / max(uv_areas.sum(), 1e-300))
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = uv_areas * self.metres_per_uv ** 2 / world_areas
        self._area_scale = np.where(np.isfinite(scale), scale, 0.0)
        flat = corner_uvs.reshape(-1, 2) * self.metres_per_uv
        self.origin, self.size = flat.min(axis=0), np.ptp(flat, axis=0)

    def coords(self, prim, u, v, points):
        c = self.corner_uvs[prim]
        uv = (1.0 - u - v)[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        return uv * self.metres_per_uv

    def area_scale(self, prim):
        return self._area_scale[prim]


def make_chart(obj: Object, planarity_tolerance: float = 1e-6) -> Optional[Chart]:
    """The chart of a receiver: its plane if it is flat, else its UV map; None
    if it is curved and has no UVs."""
    mesh = obj.mesh
    normals, areas = triangle_normals(mesh.corners)
    if areas.sum() <= 0:
        return None
    normal = (normals * areas[:, None]).sum(axis=0)
    if np.linalg.norm(normal) > 0:
        normal /= np.linalg.norm(normal)
        center = mesh.vertices.mean(axis=0)
        size = np.ptp(mesh.vertices, axis=0).max()
        if np.abs((mesh.vertices - center) @ normal).max() <= planarity_tolerance * max(size, 1e-300):
            return PlaneChart(center, normal, mesh.vertices)
    if mesh.corner_uvs is not None:
        return UVChart(mesh.corner_uvs, areas)
    return None


def bilinear_splat(planes: np.ndarray, rc: np.ndarray, values: np.ndarray) -> None:
    """Add `values (n,c)` to C-contiguous `planes (c,h,w)`, each spread
    bilinearly to the 4 cells nearest its continuous (row, col) position
    `rc (n,2)` (cell centres at integers). Weights reaching past the border
    fold onto the edge cells. Sums per cell come from one bincount per
    channel: over only the cells the batch touches when it has fewer than
    h w / 64 photons, else over the whole grid."""
    if not planes.flags.c_contiguous:
        raise ValueError("bilinear_splat adds through a flat view: planes must be C-contiguous")
    h, w = planes.shape[1:]
    base = np.floor(rc).astype(np.int64)
    frac = rc - base
    index, weight = [], []
    for di in (0, 1):
        wi = frac[:, 0] if di else 1.0 - frac[:, 0]
        row = np.clip(base[:, 0] + di, 0, h - 1)
        for dj in (0, 1):
            weight.append(wi * (frac[:, 1] if dj else 1.0 - frac[:, 1]))
            index.append(row * w + np.clip(base[:, 1] + dj, 0, w - 1))
    index, weight = np.concatenate(index), np.concatenate(weight)
    cells, size = slice(None), h * w
    if len(index) < h * w // 16:
        cells, index = np.unique(index, return_inverse=True)
        size = len(cells)
    for plane, value in zip(planes.reshape(len(planes), h * w), values.T):
        plane[cells] += np.bincount(index, weights=weight * np.tile(value, 4), minlength=size)


def bilinear_sample(planes: np.ndarray, rc: np.ndarray) -> np.ndarray:
    """(n,c) values of `planes (c,h,w)` interpolated bilinearly at continuous
    (row, col) positions `rc (n,2)` (cell centres at integers), clamped to
    the outermost centres."""
    h, w = planes.shape[1:]
    rc = np.clip(rc, 0.0, [h - 1, w - 1])
    base = np.minimum(np.floor(rc).astype(np.int64), [max(h - 2, 0), max(w - 2, 0)])
    frac = rc - base
    down, right = (w if h > 1 else 0), (1 if w > 1 else 0)
    index = (base[:, 0] * w + base[:, 1])[:, None] + [0, right, down, down + right]
    fy, fx = frac[:, 0], frac[:, 1]
    weights = np.stack([(1 - fy) * (1 - fx), (1 - fy) * fx, fy * (1 - fx), fy * fx], axis=1)
    return np.stack([np.einsum("nk,nk->n", weights, np.take(plane, index)) for plane in planes], axis=1)


def rect_means(tables: np.ndarray, origin_rc: np.ndarray, cell: float, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,c) means over chart rectangles [lo, hi] ((n,2) x, y) of a
    cell-constant grid whose summed-area tables are `tables (c, h+1, w+1)`
    and whose first corner is at chart (y, x) `origin_rc`. Exact: the grid's
    integral function is bilinear between cell corners, so the rectangle's
    integral is 16 table entries (4 per corner) times signed weights.
    Rectangles narrower than a thousandth of a cell are widened to it."""
    h, w = tables.shape[1] - 1, tables.shape[2] - 1
    centre, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 1e-3 * cell)
    lo, hi = centre - half, centre + half
    r0 = np.clip((lo[:, ::-1] - origin_rc) / cell, 0.0, [h, w])
    r1 = np.clip((hi[:, ::-1] - origin_rc) / cell, 0.0, [h, w])
    rows, row_weights = _signed_taps(r0[:, 0], r1[:, 0], h)
    cols, col_weights = _signed_taps(r0[:, 1], r1[:, 1], w)
    index = (rows[:, None] * (w + 1) + cols[None, :]).reshape(16, -1)
    weight = (row_weights[:, None] * col_weights[None, :]).reshape(16, -1)
    total = np.stack([np.einsum("kn,kn->n", weight, np.take(table, index)) for table in tables], axis=1)
    return np.maximum(total, 0.0) * (cell * cell / ((hi[:, 0] - lo[:, 0]) * (hi[:, 1] - lo[:, 1])))[:, None]


def _signed_taps(lo: np.ndarray, hi: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Entries (4,n) along one axis of a summed-area table, and their signed
    weights (4,n), that interpolate it linearly at `hi` minus at `lo` (n,),
    positions in [0, size]."""
    at = np.stack([hi, lo])
    base = np.minimum(np.floor(at), size - 1).astype(np.int64)
    frac = at - base
    sign = np.array([[1.0], [-1.0]])
    return np.concatenate([base, base + 1]), np.concatenate([sign * (1.0 - frac), sign * frac])


def _box_sums(tables: np.ndarray, i: np.ndarray, j: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(n,c) sums over the windows [i-r, i+r] x [j-r, j+r] (clipped to the
    grid) of the grid whose summed-area tables are `tables (c, h+1, w+1)`."""
    h, w = tables.shape[1] - 1, tables.shape[2] - 1
    i0, i1 = np.clip(i - r, 0, h), np.clip(i + r + 1, 0, h)
    j0, j1 = np.clip(j - r, 0, w), np.clip(j + r + 1, 0, w)
    row0, row1 = i0 * (w + 1), i1 * (w + 1)
    index = np.stack([row1 + j1, row0 + j1, row1 + j0, row0 + j0])
    corners = np.stack([np.take(table, index) for table in tables], axis=2)
    # the four partial sums cancel to a few ulp, not 0, where nothing landed
    return np.maximum(corners[0] - corners[1] - corners[2] + corners[3], 0.0)


def summed_area_table(grid: np.ndarray) -> np.ndarray:
    """Summed-area table (h+1, w+1) of `grid (h, w)`, zero-padded. Rows are
    summed down one at a time, each a contiguous vector add: numpy's cumsum
    along axis 0 strides a row apart per element (1024 x 1024: 5.7 ms
    against 18 ms)."""
    table = np.zeros((grid.shape[0] + 1, grid.shape[1] + 1))
    np.cumsum(grid, axis=1, out=table[1:, 1:])
    for row in range(2, len(table)):
        table[row] += table[row - 1]
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
        self._lock = threading.Lock()

    def _cell_coords(self, xy: np.ndarray) -> np.ndarray:
        """(n,2) continuous (row, col) positions, cell centres at integers."""
        return (xy[:, ::-1] - self.chart.origin[::-1]) / self.cell - 0.5

    def deposit(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray, points: np.ndarray,
                flux: np.ndarray) -> None:
        """Store photons (flux (n,3) W at world `points (n,3)` on local
        triangles `prim`). They are splatted in large batches, when the
        pending ones outnumber the map's cells or the map is read. Safe to call
        from several threads."""
        xy = self.chart.coords(prim, u, v, points)
        self.add_photons(xy, flux, self.chart.area_scale(prim))

    def add_photons(self, xy: np.ndarray, flux: np.ndarray, scale: np.ndarray) -> None:
        """Hold photons given in chart coordinates `xy (n,2)`, with flux
        (n,3) W and chart area per world area `scale (n,)`."""
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
            if self._tables is None:
                adaptive = self.estimate.k_nearest is not None
                self._tables = (summed_area_table(self._cells[0])[None] if adaptive else None,
                                channel_tables(self._cells[1:]))

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

    def irradiance(self) -> np.ndarray:
        """(h,w,3) W/m^2 at every cell centre: the map a bake writes."""
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
            enough = _box_sums(count_table, i, j, _WINDOW_RADII[mid])[:, 0] >= self.estimate.k_nearest
            hi = np.where(active & enough, mid, hi)
            lo = np.where(active & ~enough, mid + 1, lo)
            active = lo < hi
        radius = np.maximum(_WINDOW_RADII[lo], min_radius)
        flux = _box_sums(flux_table, i, j, radius)
        rows = np.minimum(i + radius + 1, h) - np.maximum(i - radius, 0)
        cols = np.minimum(j + radius + 1, w) - np.maximum(j - radius, 0)
        return as_rgb(flux) / (rows * cols * self.cell ** 2)[:, None]


def auto_cell_size(chart: Chart, limit: int) -> float:
    """Cell edge (m) that fits the chart's longer side in `limit` cells."""
    return float(max(chart.size.max(), 1e-300) / limit)
