"""Caustic beams: noise-free caustics from photons on a structured grid.

Photons leave a lamp on a G x G grid laid over its target cone (equal-area:
Shirley and Chiu's concentric square-to-disc map, then the cone's
cos(theta) = 1 - rho^2 (1 - cos_max)), or over a sun's target disc. At a
dielectric each path splits deterministically into its reflected (weight F)
and refracted (weight 1 - F) branch, so a path's *family* is its sequence of
(surface, event). Three grid neighbours of the same family that land on the
same receiver bound a beam: the grid triangle's flux, spread evenly over the
triangle the three land on, is irradiance flux / area there (beam tracing,
Heckbert and Hanrahan 1984; Watt 1990). The eye pass sums the beams that
contain each of its points, so the caustic has no noise and sharp edges.

Grid triangles whose three paths disagree (a silhouette, total internal
reflection on one side, different surfaces) fall back to photons: each
landed corner carries a third of the triangle's flux into the map's ordinary
density estimate.

When a material disperses, every wavelength band traces its own grid with
its own IOR and carries the band's RGB weight (spectrum.py): beams of
different bands land apart, which is the colour of a dispersive caustic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import units
from .accel import Accelerator, MISS
from .emission import Sphere, orthonormal_basis, target_cone, visible_targets
from .illumination_map import IlluminationMap, summed_area_table, bilinear_sample, bilinear_splat, rect_means
from .interface import orient, scatter
from .materials import Materials
from .optics import beer_lambert
from .scene import Light, SunLight

# Branches below this fraction of their vertex's starting weight stop.
MIN_BRANCH_WEIGHT = 1e-4
# Beams smaller than this fraction of the chart's area squared fall back to photons.
_MIN_AREA_FRACTION = 1e-16
_SIGNATURE_PRIME = np.uint64(0x100000001B3)


def concentric_disc(uv: np.ndarray) -> np.ndarray:
    """Shirley and Chiu's equal-area map of the unit square `uv (n,2)` onto
    the unit disc, (n,2)."""
    a, b = 2.0 * uv[:, 0] - 1.0, 2.0 * uv[:, 1] - 1.0
    first = np.abs(a) > np.abs(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(first, a, b)
        phi = np.where(first, 0.25 * math.pi * b / a, 0.5 * math.pi - 0.25 * math.pi * a / b)
    phi = np.where((a == 0) & (b == 0), 0.0, phi)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


@dataclass
class BeamSource:
    """One gridded cone (point or spot lamp) or disc (sun) of a lamp.

    For a cone: `axis`, `cos_max`; for a disc: `center`, `radius` of the
    target, crossed by parallel light from `start_distance` upstream.
    `cell_measure` is the solid angle (sr) or area (m^2) of one grid cell.
    `overlap` lists every source of the same lamp, to share directions or
    positions that several cones or discs cover (the balance heuristic).
    """

    light: Light
    energy: float
    grid: int
    axis: np.ndarray = None
    cos_max: float = 0.0
    center: np.ndarray = None
    radius: float = 0.0
    start_distance: float = 0.0
    overlap: list = field(default_factory=list)

    @property
    def is_disc(self) -> bool:
        return isinstance(self.light, SunLight)

    @property
    def measure(self) -> float:
        if self.is_disc:
            return math.pi * self.radius ** 2
        return 2.0 * math.pi * (1.0 - self.cos_max)

    @property
    def cell_measure(self) -> float:
        return self.measure / (self.grid - 1) ** 2

    def contains(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        if self.is_disc:
            rel = origins - self.center
            along = rel @ self.light.direction
            perp = rel - along[:, None] * self.light.direction
            return np.einsum("ij,ij->i", perp, perp) <= self.radius ** 2 * (1 + 1e-9)
        return dirs @ self.axis >= self.cos_max - 1e-12

    def vertices(self, first_row: int, end_row: int):
        """Grid rows [first_row, end_row): (origins (n,3), dirs (n,3),
        weight (n,3) intensity (W/sr) or irradiance (W/m^2) times the overlap
        share)."""
        rows, cols = np.meshgrid(np.arange(first_row, end_row), np.arange(self.grid), indexing="ij")
        uv = np.stack([rows.ravel(), cols.ravel()], axis=1) / (self.grid - 1)
        disc = concentric_disc(uv)
        if self.is_disc:
            t, b = orthonormal_basis(self.light.direction)
            origins = (self.center + self.radius * (disc[:, :1] * t + disc[:, 1:] * b)
                       - self.start_distance * self.light.direction)
            dirs = np.broadcast_to(self.light.direction, origins.shape).copy()
            weight = np.broadcast_to(units.sun_irradiance(self.light, self.energy), origins.shape).copy()
        else:
            rho2 = np.einsum("ij,ij->i", disc, disc)
            cos_t = 1.0 - rho2 * (1.0 - self.cos_max)
            sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
            rho = np.sqrt(rho2)
            with np.errstate(invalid="ignore", divide="ignore"):
                c = np.where(rho > 0, disc[:, 0] / rho, 1.0)
                s = np.where(rho > 0, disc[:, 1] / rho, 0.0)
            t, b = orthonormal_basis(self.axis)
            dirs = (sin_t * c)[:, None] * t + (sin_t * s)[:, None] * b + cos_t[:, None] * self.axis
            origins = np.broadcast_to(self.light.position, dirs.shape).copy()
            weight = units.intensity(self.light, self.energy, dirs).copy()
        density = sum(src.contains(origins, dirs) / src.cell_measure for src in self.overlap)
        weight *= ((1.0 / self.cell_measure) / density)[:, None]
        return origins, dirs, weight


def beam_sources(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, energy: float,
                 vertices: int) -> list[BeamSource]:
    """Grids over every lamp's targets, about `vertices` grid points in all,
    shared in proportion to the flux each cone or disc receives."""
    start_distance = 2.0 * scene_sphere.radius + 1.0
    sources = []
    for light in lights:
        per_light = []
        for sphere in visible_targets(light, targets):
            if isinstance(light, SunLight):
                per_light.append(BeamSource(light, energy, 2, center=sphere.center, radius=sphere.radius,
                                            start_distance=start_distance))
                continue
            axis, cos_max = target_cone(light.position, sphere)
            per_light.append(BeamSource(light, energy, 2, axis=axis, cos_max=cos_max))
        for src in per_light:
            src.overlap = per_light
        sources += per_light
    if not sources:
        return []
    flux = np.array([s.measure * (s.light.strength if s.is_disc else s.light.power) for s in sources])
    for src, share in zip(sources, vertices * flux / flux.sum()):
        src.grid = max(3, int(round(math.sqrt(share))))
    return sources


@dataclass
class Landings:
    """Where a band's vertex paths landed on receivers.

    vertex (n,) grid index within the band, family (n,) uint64 signature,
    obj (n,) receiver object index, xy (n,2) chart metres, scale (n,) chart
    area per world area, weight (n,3) the path's starting weight times its
    Fresnel, tint and absorption factors."""

    vertex: np.ndarray
    family: np.ndarray
    obj: np.ndarray
    xy: np.ndarray
    scale: np.ndarray
    weight: np.ndarray


def _mix(family: np.ndarray, obj: np.ndarray, event: int) -> np.ndarray:
    with np.errstate(over="ignore"):
        return (family * _SIGNATURE_PRIME) ^ (obj.astype(np.uint64) * np.uint64(4) + np.uint64(event + 1))


def trace_paths(accel: Accelerator, materials: Materials, maps: dict[int, IlluminationMap], origins: np.ndarray,
                dirs: np.ndarray, weight: np.ndarray, max_depth: int, start_medium: int = MISS,
                band: int = 0) -> Landings:
    """Follow every branch of every vertex path, starting inside object
    `start_medium` (MISS: in air), until it lands on a receiver (after at
    least one specular event), leaves, or fades below MIN_BRANCH_WEIGHT.
    Dielectrics refract with their IOR in wavelength band `band`."""
    vertex = np.arange(len(origins))
    family = np.zeros(len(origins), dtype=np.uint64)
    medium = np.full(len(origins), start_medium, dtype=np.int64)
    floor = MIN_BRANCH_WEIGHT * weight.max(axis=1)
    specular = np.zeros(len(origins), dtype=bool)
    landed = []
    for _ in range(max_depth + 1):
        if len(vertex) == 0:
            break
        hits = accel.intersect(origins, dirs, medium)
        keep = hits.hit
        origins, dirs, weight, vertex, family, medium, floor, specular = (
            a[keep] for a in (origins, dirs, weight, vertex, family, medium, floor, specular))
        hits = hits.select(keep)
        points = hits.points
        inside = medium != MISS
        if inside.any():
            weight[inside] *= beer_lambert(materials.absorption[medium[inside]], hits.t[inside])

        land = specular & materials.receiver[hits.obj] & np.isin(hits.obj, list(maps))
        for index in np.unique(hits.obj[land]):
            sel = land & (hits.obj == index)
            local = hits.prim[sel] - accel.prim_offset[index]
            chart = maps[index].chart
            landed.append(Landings(vertex[sel], family[sel], hits.obj[sel],
                                   chart.coords(local, hits.u[sel], hits.v[sel], points[sel]),
                                   chart.area_scale(local), weight[sel]))

        glass = materials.dielectric[hits.obj]
        origins, dirs, weight, vertex, family, medium, floor, points = (
            a[glass] for a in (origins, dirs, weight, vertex, family, medium, floor, points))
        hits = hits.select(glass)
        if len(vertex) == 0:
            break
        surface = orient(accel, hits, dirs, points, materials.ior_bands[hits.obj, band], medium)
        tint = materials.color[hits.obj]
        branches = []
        for event, mirror in ((0, True), (1, False)):
            new_dirs, crossed = scatter(surface, dirs, np.full(len(dirs), mirror))
            share = surface.fresnel if mirror else np.where(crossed, 1.0 - surface.fresnel, 0.0)
            new_weight = weight * tint * share[:, None]
            new_medium = np.where(crossed, np.where(surface.entering, hits.obj, MISS), medium)
            alive = new_weight.max(axis=1) >= floor
            branches.append((accel.offset(points, surface.facing, new_dirs)[alive], new_dirs[alive],
                             new_weight[alive], vertex[alive], _mix(family, hits.obj, event)[alive],
                             new_medium[alive], floor[alive]))
        origins, dirs, weight, vertex, family, medium, floor = (np.concatenate(parts) for parts in zip(*branches))
        specular = np.ones(len(vertex), dtype=bool)
    if not landed:
        empty = np.zeros(0)
        return Landings(empty.astype(np.int64), empty.astype(np.uint64), empty.astype(np.int64),
                        np.zeros((0, 2)), empty, np.zeros((0, 3)))
    return Landings(*(np.concatenate([getattr(l, f) for l in landed])
                      for f in ("vertex", "family", "obj", "xy", "scale", "weight")))


def grid_triangles(rows: int, cols: int) -> np.ndarray:
    """(2 (rows-1)(cols-1), 3) vertex indices of a rows x cols grid's
    triangles, two per cell, counter-clockwise in (row, col)."""
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(cols - 1), indexing="ij")
    v00 = (r * cols + c).ravel()
    v10, v01 = v00 + cols, v00 + 1
    v11 = v10 + 1
    return np.concatenate([np.stack([v00, v10, v11], axis=1), np.stack([v00, v11, v01], axis=1)])


@dataclass
class BandBeams:
    """Beams and fallback photons from one band of a source's grid, per receiver.

    beams[obj] = (corners (m,3,2) chart metres, irradiance (m,3) W/m^2)
    photons[obj] = (xy (k,2), flux (k,3) W, scale (k,))
    flux_landed (3,) W carried by both"""

    beams: dict
    photons: dict
    rays: int
    flux_landed: np.ndarray


def band_beams(source: BeamSource, first_row: int, end_row: int, accel: Accelerator, materials: Materials,
               maps: dict[int, IlluminationMap], max_depth: int, start_medium: int = MISS,
               band: int = 0) -> BandBeams:
    """Trace grid rows [first_row, end_row) of `source` in wavelength band
    `band`, whose paths start inside object `start_medium`, and turn the
    landed paths into beams (coherent triangles) and fallback photons."""
    rays_before = accel.rays_cast
    origins, dirs, weight = source.vertices(first_row, end_row)
    weight *= materials.band_weights[band]
    landings = trace_paths(accel, materials, maps, origins, dirs, weight, max_depth, start_medium, band)
    triangles = grid_triangles(end_row - first_row, source.grid)
    triangle_measure = 0.5 * source.cell_measure
    beams, photons = {}, {}
    flux_landed = np.zeros(3)
    keys = np.stack([landings.family, landings.obj.astype(np.uint64)], axis=1)
    groups, group_of = (np.unique(keys, axis=0, return_inverse=True) if len(keys)
                        else (np.zeros((0, 2), dtype=np.uint64), np.zeros(0, dtype=np.int64)))
    n_vertices = (end_row - first_row) * source.grid
    for g in range(len(groups)):
        members = np.flatnonzero(group_of.reshape(-1) == g)
        slot = np.full(n_vertices, -1, dtype=np.int64)
        slot[landings.vertex[members]] = members
        corner = slot[triangles]
        landed = corner >= 0
        coherent = landed.all(axis=1)
        obj = int(groups[g, 1])
        chart_area = float(np.prod(np.maximum(maps[obj].chart.size, 1e-300)))

        idx = corner[coherent]
        xy = landings.xy[idx]
        e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
        area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        flux = triangle_measure * landings.weight[idx].mean(axis=1)
        good = area > _MIN_AREA_FRACTION * chart_area
        scale = landings.scale[idx].mean(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            irradiance = flux * (scale / area)[:, None]
        corners_b, irr_b = xy[good], irradiance[good]
        flux_landed += flux[good].sum(axis=0)
        old = beams.get(obj)
        beams[obj] = (corners_b, irr_b) if old is None else (np.concatenate([old[0], corners_b]),
                                                              np.concatenate([old[1], irr_b]))

        # fallback: each landed corner of an incoherent or degenerate triangle
        # carries a third of that triangle's flux
        loose = ~coherent & landed.any(axis=1)
        degenerate = np.zeros(len(triangles), dtype=bool)
        degenerate[np.flatnonzero(coherent)[~good]] = True
        loose |= degenerate
        per_corner = corner[loose][landed[loose]]
        if len(per_corner):
            counts = np.bincount(per_corner, minlength=len(landings.vertex))[members]
            holders = members[counts > 0]
            share = counts[counts > 0][:, None] * (triangle_measure / 3.0) * landings.weight[holders]
            flux_landed += share.sum(axis=0)
            old = photons.get(obj)
            new = (landings.xy[holders], share, landings.scale[holders])
            photons[obj] = new if old is None else tuple(np.concatenate([a, b]) for a, b in zip(old, new))
    return BandBeams(beams, photons, accel.rays_cast - rays_before, flux_landed)


def _weighted_quantiles(values: np.ndarray, weights: np.ndarray, q) -> np.ndarray:
    order = np.argsort(values)
    cdf = np.cumsum(weights[order])
    return values[order][np.searchsorted(cdf, np.asarray(q) * cdf[-1]).clip(0, len(values) - 1)]


def triangle_samples(corners: np.ndarray, per_side: int) -> np.ndarray:
    """(m, per_side^2, 2) points spread evenly over each triangle `corners
    (m,3,2)`: a per_side x per_side lattice on the unit square, folded onto
    the triangle (the fold preserves area, so the points stay uniform)."""
    ticks = (np.arange(per_side) + 0.5) / per_side
    a, b = (g.ravel() for g in np.meshgrid(ticks, ticks, indexing="ij"))
    fold = a + b > 1.0
    a, b = np.where(fold, 1.0 - a, a), np.where(fold, 1.0 - b, b)
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return corners[:, None, 0] + a[None, :, None] * e1[:, None] + b[None, :, None] * e2[:, None]


@dataclass
class _Layer:
    """A grid of beam flux: `flux (h,w,3)` W per cell of edge `cell` m, its
    first corner at chart `origin (2,)`, and its summed-area table."""

    origin: np.ndarray
    cell: float
    flux: np.ndarray
    table: np.ndarray = None

    @staticmethod
    def covering(lo: np.ndarray, hi: np.ndarray, cell: float) -> "_Layer":
        """An empty layer over the chart box [lo, hi] with a cell of margin."""
        shape = tuple((np.ceil((hi - lo) / cell).astype(int) + 2)[::-1])
        return _Layer(lo - cell, cell, np.zeros(shape + (3,)))

    def rc(self, xy: np.ndarray) -> np.ndarray:
        return (xy[:, ::-1] - self.origin[::-1]) / self.cell - 0.5

    def add(self, corners: np.ndarray, flux: np.ndarray, spacing: float, points_per_splat: int) -> None:
        """Spread each beam's flux over a lattice inside it, `spacing` cells
        apart (at most MAX_SIDE points a side), splatting in batches. A
        lattice as coarse as the grid aliases against it."""
        per_side = np.ceil(np.ptp(corners, axis=1).max(axis=1) / (spacing * self.cell))
        per_side = per_side.clip(1, BeamMap.MAX_SIDE).astype(np.int64)
        points, values, held = [], [], 0
        for k in np.unique(per_side):
            chosen = np.flatnonzero(per_side == k)
            for batch in np.array_split(chosen, max(1, len(chosen) * int(k) ** 2 // points_per_splat)):
                points.append(triangle_samples(corners[batch], int(k)).reshape(-1, 2))
                values.append(np.repeat(flux[batch] / (k * k), k * k, axis=0))
                held += len(points[-1])
                if held >= points_per_splat:
                    self.flux += bilinear_splat(self.flux.shape[:2], self.rc(np.concatenate(points)),
                                                np.concatenate(values))
                    points, values, held = [], [], 0
        if held:
            self.flux += bilinear_splat(self.flux.shape[:2], self.rc(np.concatenate(points)), np.concatenate(values))
        self.table = summed_area_table(self.flux)

    def at(self, xy: np.ndarray) -> np.ndarray:
        """(n,3) W/m^2 at chart points, zero off the layer."""
        rc = self.rc(xy)
        inside = ((rc >= -0.5) & (rc <= np.array(self.flux.shape[:2]) - 0.5)).all(axis=1)
        out = np.zeros((len(xy), 3))
        out[inside] = bilinear_sample(self.flux / self.cell ** 2, rc[inside])
        return out

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return rect_means(self.table, self.origin[::-1], self.cell, lo, hi) / self.cell ** 2


class BeamMap(IlluminationMap):
    """An illumination map whose caustic comes from beams, plus the ordinary
    density estimate of the fallback photons it holds.

    Each beam's flux is spread over a lattice of points inside it and
    splatted bilinearly, so flux is conserved exactly and a beam squeezed to
    nothing at a fold cannot spike. Beams go to a layer whose cells match
    their size: under 2 map cells (the sharp part of a caustic) to a grid
    FINE times finer, laid over where 99.9% of their flux lands; up to 16
    cells to the map's own grid; larger (dim, smooth) to one 4 times coarser,
    sampled less densely.
    """

    FINE = 8
    FINE_LIMIT = 2048
    MAX_SIDE = 32
    _POINTS_PER_SPLAT = 1 << 22

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._beam_parts: list[tuple[np.ndarray, np.ndarray]] = []
        self._layers: list[_Layer] = []
        self.beams = 0

    def add_beams(self, corners: np.ndarray, irradiance: np.ndarray) -> None:
        """Beams `corners (m,3,2)` chart metres, `irradiance (m,3)` W/m^2."""
        with self._lock:
            self._beam_parts.append((corners, irradiance))
            self.beams += len(corners)

    def _rasterise_beams(self) -> None:
        corners = np.concatenate([c for c, _ in self._beam_parts])
        irradiance = np.concatenate([e for _, e in self._beam_parts])
        self._beam_parts = []
        e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
        flux = irradiance * (0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))[:, None]
        size = np.ptp(corners, axis=1).max(axis=1) / self.cell
        lo, hi = self.chart.origin, self.chart.origin + self.chart.size
        small = size < 2.0
        if small.any():
            centre = corners[small].mean(axis=1)
            weight = flux[small].sum(axis=1)
            bounds = np.array([_weighted_quantiles(centre[:, a], weight, (5e-4, 1 - 5e-4)) for a in (0, 1)])
            fine_lo, fine_hi = bounds[:, 0] - self.cell, bounds[:, 1] + self.cell
            small[small] = ((centre >= fine_lo) & (centre <= fine_hi)).all(axis=1)
            cell = max(self.cell / self.FINE, float((fine_hi - fine_lo).max()) / self.FINE_LIMIT)
            self._add_layer(_Layer.covering(fine_lo, fine_hi, cell), corners[small], flux[small], 0.5)
        large = size >= 16.0
        self._add_layer(_Layer.covering(lo, hi, self.cell), corners[~small & ~large], flux[~small & ~large], 0.5)
        self._add_layer(_Layer.covering(lo, hi, 4.0 * self.cell), corners[large], flux[large], 1.0)

    def _add_layer(self, layer: _Layer, corners: np.ndarray, flux: np.ndarray, spacing: float) -> None:
        if len(corners):
            layer.add(corners, flux, spacing, self._POINTS_PER_SPLAT)
            self._layers.append(layer)

    def prepare(self) -> None:
        super().prepare()
        with self._lock:
            if self._beam_parts:
                self._rasterise_beams()

    def irradiance_at(self, xy: np.ndarray) -> np.ndarray:
        return super().irradiance_at(xy) + sum(layer.at(xy) for layer in self._layers)

    def mean_over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        return super().mean_over(lo, hi) + sum(layer.mean_over(lo, hi) for layer in self._layers)
