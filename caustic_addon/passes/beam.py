"""Caustic beams: noise-free caustics from photons on a structured grid.

Photons leave a lamp on a G x G grid laid over its target cone (equal-area:
Shirley and Chiu's concentric square-to-disc map, then the cone's
cos(theta) = 1 - rho^2 (1 - cos_max)), or over a sun's target disc. At a
dielectric each path splits deterministically into its reflected (weight F)
and refracted (weight 1 - F) branch; at a reflector it only reflects (weight
its reflectance). A path's *family* is its sequence of (surface, event), so
paths that meet the same surfaces in the same order, glass or mirror, make
beams together. Three grid neighbours of the same family that land on the
same receiver bound a beam: the grid triangle's flux (its flat triangle's
share of the aim's measure, beam_sources.disc_shares), spread evenly over the
triangle the three land on, is irradiance flux / area there (beam tracing,
Heckbert and Hanrahan 1984; Watt 1990). `beam_map.BeamMap` rasterises the
beams with exact area coverage, so the caustic has no noise and sharp edges.

Grid cells whose paths diverge (a silhouette, total internal reflection on
one side, different surfaces, or a fold of the caustic inside the cell) are
split in four and their new corners traced, up to `levels` times.
Triangles whose three paths still disagree fall back to photons: each
landed corner carries a third of the triangle's flux into the map's ordinary
density estimate.

A lamp with a size is points of it, each standing for a cell of the lamp
(lamp_points.py). Their paths carry ray differentials across the cell,
toward the same point of the aim (SourceBatch.differentials, carried through
the bounces by differentials.py), and each beam of theirs is spread over
where its cell's light lands, the landing's image of the cell
(`_spread_beams`): the points' caustics, each sharp, then sum to the soft
one rather than to a lattice of dots, one a point.

A lamp sends photons toward the rough casters it can light and beams
toward the smooth ones (`photon_lamps`); grid paths that meet a rough
surface all the same (light a smooth glass turns toward a rough one)
scatter about microfacet normals of their own and land as photons.

When a material disperses, every wavelength band traces its own grid with
its own IOR and carries the band's RGB weight (spectrum.py): beams of
different bands land apart, which is the colour of a dispersive caustic.
The bands' grids of a lamp are traced in one batch, as the grids of one
size are: a batch's cost is mostly its work per bounce.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Optional

import numpy as np

from ..emission.aims import Sphere, casters_and_bounds, smooth_and_rough, visible_targets
from ..emission.beam_sources import BeamSource, SourceBatch, beam_sources, disc_shares
from ..emission.lamp_points import beam_lamps
from ..emission.photons import Emitter, make_emitters
from ..emission.sky_lamps import SkyRegion
from ..maps.deposits import Deposits
from ..maps.illumination_map import IlluminationMap
from ..maps.receivers import GUTTER_CELLS
from ..maps.raster import signed_area1
from ..sampling.hash import hash_uniform
from ..scene import Light, MeshLight, RenderSettings, Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS, Hits
from ..util.parallel import Monitor, run_chunks
from ..util.jit import inline, kernel
from ..util.rows import take, take_rows
from ..util.vectors import DIVISION_FLOOR, max_channel1, row
from .beam_grid import Cells, LandingIndex, coherent_triangles, crack_free_triangles, diverging, fallback_shares
from .bounce import facets, on_maps, split, trace
from .interface import Interface
from .differentials import landing_differentials
from .lamp_pass import JobResult, LampPassStats, deliverer, lamp_media
from .paths import MIN_BRANCH_WEIGHT, Paths, relative_floor
from .photon import FACET_STREAM, photon_jobs

# A band holds at most chunk_size / BAND_SHARE grid points: each becomes up
# to four with refinement, with its landings, lookups and beams (about 3.5 kB
# a point in all), so that two bands in flight stay near 0.25 GB each.
BAND_SHARE = 4
# A grid is cut into at least this many bands of rows, whatever the
# machine's threads: where the bands part changes the beams along their
# borders and the order the maps sum them in, and a render must be the same
# on every machine (a farm's nodes render the chunks of one frame range).
# Each band's casts split over its share of the cores (threads_here).
GRID_BANDS = 2
# Beams smaller than this fraction of the chart's area squared fall back to photons.
_MIN_AREA_FRACTION = 1e-16
# A beam whose corners span a world triangle more than this many times the
# area its chart triangle stands for crosses a gap in its chart island (a
# bowl's bottom to its rim, over the wall, which lies in other islands): it
# falls back to photons.
_MAX_STRETCH = 1.5
# A beam's hull (_spread_beams) drops corners whose turn's sine is under
# this: rounding would keep points in the middle of an edge as corners.
_COLLINEAR = 1e-9
# A beam from a point of a lamp with a size is copies over its lamp cell's
# image (_spread_beams), 2 or more along each way, as many as it takes for
# each part to be no wider than half the beam or than PART_CELLS map cells,
# whichever is wider, and at most SPREAD_PARTS (a lamp's point, whose cell's
# image is a few map cells) or SKY_SPREAD_PARTS (a region of the sky, whose
# image is wider than its beams: with 2 parts, rings of seams crossed a
# floor under a pane along its grid); their moves are halved along a
# direction where the beam is MOVE_RATIO times as wide as the image, and
# copies that move less than _STILL of that are one, and a part kept less
# than _STILL is none.
SPREAD_PARTS = 2
SKY_SPREAD_PARTS = 4
PART_CELLS = 2.0
MOVE_RATIO = 4.0
_STILL = 0.02
# A beam across a box chart's seam is copied into each island when it is
# shorter than the gutter between islands less this many cells (a bilinear
# look-up's reach, and rounding).
SEAM_MARGIN_CELLS = 2


@dataclass
class Landings:
    """Where a band's vertex paths landed on receivers.

    vertex (n,) the path's grid key, family (n,) uint64 signature,
    obj (n,) receiver object index, island (n,) of its chart, points (n,3)
    world, xy (n,2) chart metres, scale (n,) chart area per world area,
    weight (n,3) the path's starting weight times its Fresnel, tint and
    absorption factors, throughput (n,) that product of factors (max
    channel), d_xy (n,k,2) chart metres: how the landing moves with the
    path's differentials (BeamTracer: k = 2, per unit along the lamp cell's
    axes; band_beams: k = 4, to each corner of the cell), or None where no
    path stands for a lamp's cell (lamps of size 0)."""

    vertex: np.ndarray
    family: np.ndarray
    obj: np.ndarray
    island: np.ndarray
    points: np.ndarray
    xy: np.ndarray
    scale: np.ndarray
    weight: np.ndarray
    throughput: np.ndarray
    d_xy: Optional[np.ndarray] = None

    @staticmethod
    def concat(parts: list["Landings"]) -> "Landings":
        if not parts:
            empty = np.zeros(0)
            return Landings(empty.astype(np.int64), empty.astype(np.uint64), empty.astype(np.int64),
                            empty.astype(np.int64), np.zeros((0, 3)), np.zeros((0, 2)), empty, np.zeros((0, 3)),
                            empty)
        out = Landings(*(np.concatenate([getattr(p, f) for p in parts])
                         for f in ("vertex", "family", "obj", "island", "points", "xy", "scale", "weight",
                                   "throughput")))
        shapes = [p.d_xy.shape[1:] for p in parts if p.d_xy is not None]
        if shapes:
            out.d_xy = np.concatenate([np.zeros((len(p.vertex),) + shapes[0]) if p.d_xy is None else p.d_xy
                                       for p in parts])
        return out


class BeamTracer:
    """The beam pass's choices in the bounce (bounce.trace): record where
    each branch lands on a receiver's map after a specular event, and follow
    both branches at every specular hit; at a rough one, about a microfacet
    normal of the vertex's own (random numbers from its grid key, its bounce
    and `seed`), which gives the branch a family of its own."""

    def __init__(self, accel: Accelerator, materials: Materials, maps: dict, seed: int):
        self.accel, self.materials, self.maps, self.seed = accel, materials, maps, seed
        self.landed: list[Landings] = []

    def escaped(self, paths: Paths) -> None:
        pass

    def arrived(self, paths: Paths, hits: Hits) -> None:
        for obj, rows, xy, scale, island, basic in on_maps(self.accel, self.materials, self.maps, paths, hits):
            weight, floor = take(paths.weight, rows), take(paths.floor, rows)
            throughput = np.empty(len(rows))
            _throughputs(weight, floor, throughput)
            weight *= basic[:, None]
            points = take(hits.points, rows)
            landed = Landings(take(paths.ids, rows), take(paths.family, rows), np.full(len(rows), obj),
                              island, points, xy, scale, weight, throughput)
            if paths.d_origins is not None:
                landed.d_xy = self._chart_differentials(obj, paths.take(rows), hits.take(rows), points, xy)
            self.landed.append(landed)

    def _chart_differentials(self, obj: int, paths: Paths, hits: Hits, points: np.ndarray,
                             xy: np.ndarray) -> np.ndarray:
        """(n,2,2) chart metres: how the landings `xy (n,2)` of `paths` at
        `hits` (world `points (n,3)`) on receiver `obj` move with the
        paths' two differentials: every chart is affine on each triangle."""
        dp, duv = landing_differentials(self.accel, paths, hits)
        local = hits.prim - self.accel.prim_offset[obj]
        chart = self.maps[obj].chart
        return np.stack([chart.coords(local, hits.u + duv[:, k, 0], hits.v + duv[:, k, 1], points + dp[:, k]) - xy
                         for k in (0, 1)], axis=1)

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        if surface.rough.any():
            uv = np.stack([hash_uniform(paths.ids, FACET_STREAM + 2 * depth + k, self.seed) for k in (0, 1)], axis=1)
            surface = facets(surface, paths.dirs, self.materials, hits.obj, uv)
        return split(self.accel, self.materials, paths, hits, surface, carries_light=True)


@kernel("void(f8[:, ::1], f8[::1], f8[::1])")
def _throughputs(weight, floor, out):
    """Landings.throughput of paths of `weight (n,3)` and `floor (n,)`: the
    product of their factors, max channel(weight) * MIN_BRANCH_WEIGHT /
    floor (the floor is MIN_BRANCH_WEIGHT of the starting weight); 0 where
    the floor is."""
    for i in range(len(floor)):
        out[i] = max_channel1(row(weight, i)) * MIN_BRANCH_WEIGHT / floor[i] if floor[i] > 0.0 else 0.0


def trace_paths(accel: Accelerator, materials: Materials, maps: dict[int, IlluminationMap], origins: np.ndarray,
                dirs: np.ndarray, weight: np.ndarray, vertex: np.ndarray, bands: np.ndarray, max_depth: int,
                start_media: tuple[int, int] = (MISS, MISS), seed: int = 0,
                differentials: Optional[tuple[np.ndarray, np.ndarray]] = None) -> Landings:
    """Follow every branch of the vertex paths `vertex (n,)`, starting
    inside the objects `start_media` (Paths.start), until it lands on a
    receiver (after at least one specular event), leaves, or fades below
    MIN_BRANCH_WEIGHT. Dielectrics refract with their IOR in each path's
    wavelength band `bands (n,)`; rough surfaces scatter by random numbers of `seed`. The paths
    carry `differentials` (d_origins, d_dirs (n,2,3)) through their bounces
    where given (their landings' d_xy)."""
    tracer = BeamTracer(accel, materials, maps, seed)
    paths = Paths.start(origins, dirs, weight, vertex, start_media, relative_floor(weight), bands, family=True)
    if differentials is not None:
        paths = replace(paths, d_origins=differentials[0].astype(np.float32),
                        d_dirs=differentials[1].astype(np.float32))
    trace(accel, materials, paths, max_depth, tracer)
    return Landings.concat(tracer.landed)


def band_beams(batch: SourceBatch, first_row: int, end_row: int, accel: Accelerator, materials: Materials,
               maps: dict[int, IlluminationMap], max_depth: int, start_media: tuple[int, int], levels: int,
               bands: np.ndarray, seed: int) -> JobResult:
    """Trace grid rows [first_row, end_row) of the sources of `batch`, grids
    of one size traced as one batch (the points of a lamp with a size, say,
    and each point's grid once per wavelength band), source k in wavelength band
    `bands[k]`, whose paths start inside the objects `start_media`,
    splitting cells where their paths diverge (`levels` times at most), and
    turn the landed paths into beams (coherent triangles) and fallback
    photons. The lamp rays are the grid points (the last row is the next
    row band's first, and counts there) and those refinement added."""
    sources, grid = batch.sources, batch.grid
    scale = 1 << levels
    width = (grid - 1) * scale + 1
    keys = width * width

    def trace_vertices(vertex: np.ndarray) -> Landings:
        order = np.argsort(vertex // keys, kind="stable")
        which, local = np.divmod(vertex[order], keys)
        origins, dirs, weight = batch.rays(which, np.stack([local // width, local % width], axis=1) / scale)
        band = bands[which]
        weight *= materials.band_weights[band]
        differentials = None
        if batch.spreading:
            # where the rays first meet the scene, a sun's pivot
            first = accel.intersect(origins, dirs).t if batch.disc.any() else np.full(len(dirs), np.inf)
            differentials = batch.differentials(which, dirs, first)
        landed = trace_paths(accel, materials, maps, origins, dirs, weight, vertex[order], band, max_depth,
                             start_media, seed, differentials)
        if batch.spreading and landed.d_xy is not None:
            # per unit along the cell's axes, to each of its corners
            landed.d_xy = np.einsum("nkj,njc->nkc", np.take(batch.cell_corners, landed.vertex // keys, axis=0),
                                    landed.d_xy)
        return landed

    row, col = (a.ravel() * scale for a in np.meshgrid(np.arange(first_row, end_row - 1), np.arange(grid - 1),
                                                         indexing="ij"))
    cells = Cells(np.tile(row, len(sources)), np.tile(col, len(sources)), np.full(len(row) * len(sources), scale),
                   np.repeat(np.arange(len(sources)) * keys, len(row)))
    traced = np.unique(cells.corners(width))
    on_grid = len(traced)
    owned = on_grid - (grid * len(sources) if end_row < grid else 0)
    landings = trace_vertices(traced)
    for _ in range(levels):
        diverge = diverging(LandingIndex(landings, maps), cells, width)
        if not diverge.any():
            break
        cells = cells.split(diverge)
        children = np.unique(cells.corners(width))
        fresh = children[~np.isin(children, traced, assume_unique=True)]
        landings = Landings.concat([landings, trace_vertices(fresh)])
        traced = np.union1d(traced, fresh)

    triangles, _, centres = crack_free_triangles(cells, width, traced)
    landings = Landings.concat([landings, trace_vertices(centres)])
    aim_measure = np.array([source.aim.measure for source in sources])
    local = triangles % keys
    measure = aim_measure[triangles[:, 0] // keys] * disc_shares(
        np.stack([local // width, local % width], axis=-1) / scale, grid)
    most_parts = np.array([SKY_SPREAD_PARTS if isinstance(source.light, SkyRegion) else SPREAD_PARTS
                           for source in sources])
    deposits, beams, flux_landed = _beams_and_photons(LandingIndex(landings, maps), triangles, measure, maps,
                                                      np.take(most_parts, triangles[:, 0] // keys))
    refined = len(traced) + len(centres) - on_grid
    return JobResult(deposits, LampPassStats(owned + refined, refined, beams, flux_landed))


def _beams_and_photons(lookup: LandingIndex, triangles: np.ndarray, measure: np.ndarray,
                       maps: dict[int, IlluminationMap], most_parts: np.ndarray):
    """Triangles `triangles (n,3)` (vertex keys) of emission measure
    `measure (n,)` (sr or m^2) whose three paths landed in one family become
    beams (`_beam_geometry`), spread over their lamp cell's image in at
    most `most_parts (n,)` parts each way; the landed corners of the others
    carry a third of the triangle's flux each, as photons. Returns (the
    deposits, the number of beams, the flux (3,) W that beams and photons
    carry)."""
    land = lookup.landings
    tri, idx = coherent_triangles(lookup, triangles)
    min_area, reach = np.zeros(max(maps, default=-1) + 1), np.zeros(max(maps, default=-1) + 1)
    for index, imap in maps.items():
        min_area[index] = _MIN_AREA_FRACTION * np.prod(np.maximum(imap.chart.size, DIVISION_FLOOR))
        reach[index] = (GUTTER_CELLS - SEAM_MARGIN_CELLS) * imap.cell if imap.chart.projects else 0.0
    corners, flux, irradiance, world_area, good, copies = _beam_geometry(
        tri, idx, measure, *(np.ascontiguousarray(a) for a in (land.xy, land.weight, land.scale, land.points)),
        land.island, land.obj, min_area, reach)
    obj = np.take(land.obj, idx[:, 0])
    kept = good | copies[:, 0]
    share = fallback_shares(lookup, triangles, measure, tri, idx, kept)
    holders = np.flatnonzero(share > 0)
    photon_flux = share[holders, None] * np.take(land.weight, holders, axis=0)

    deposits = Deposits()
    spread = None
    if land.d_xy is not None:
        d_xy = land.d_xy
        spread = (np.take(d_xy, idx[:, 0], axis=0) + np.take(d_xy, idx[:, 1], axis=0)
                  + np.take(d_xy, idx[:, 2], axis=0)) / 3.0
    for o in np.unique(obj[good]):
        if spread is None:
            deposits.add_beams(int(o), *take_rows(good & (obj == o), corners, irradiance))
        else:
            # the copies that stay triangles apart from the hulls: each holds the memory of its corners
            mine = good & (obj == o)
            spread_triangles, triangle_light, hulls, hull_light = _spread_beams(
                *take_rows(mine, corners, irradiance, spread), np.take(most_parts, tri[mine]), maps[int(o)].cell)
            for part, light in ((spread_triangles, triangle_light), (hulls, hull_light)):
                if len(part):
                    deposits.add_beams(int(o), part, light)
    for k in range(3):
        rows = np.flatnonzero(copies[:, k])
        for o in np.unique(obj[rows]):
            mine = rows[obj[rows] == o]
            projected = maps[int(o)].chart.project(np.take(land.island, idx[mine, k]),
                                                   np.take(land.points, idx[mine], axis=0))
            deposits.add_beams(int(o), projected, np.take(flux, mine, axis=0) / world_area[mine, None])
    for o in np.unique(land.obj[holders]):
        sel = np.flatnonzero(land.obj[holders] == o)
        at = np.take(holders, sel)
        deposits.add_photons(int(o), np.take(land.xy, at, axis=0), np.take(photon_flux, sel, axis=0),
                             np.take(land.scale, at))
    return deposits, int(kept.sum()), flux[kept].sum(axis=0) + photon_flux.sum(axis=0)


@inline
def _world_area(a, b, c):
    """Area of the world triangle a, b, c ((3,) each): |(b - a) x (c - a)| / 2."""
    e1x, e1y, e1z = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    e2x, e2y, e2z = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
    return 0.5 * np.sqrt(nx * nx + ny * ny + nz * nz)


@inline
def _distance(a, b):
    """|b - a| of (3,) points."""
    return np.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2)


@kernel("Tuple((f8[:, :, ::1], f8[:, ::1], f8[:, ::1], f8[::1], b1[::1], b1[:, ::1]))(i8[::1], i8[:, ::1], f8[::1], "
        "f8[:, ::1], f8[:, ::1], f8[::1], f8[:, ::1], i8[::1], i8[::1], f8[::1], f8[::1])")
def _beam_geometry(tri, idx, measure, xy, weight, scale, points, island, obj, min_area, reach):
    """Beams of grid triangles `tri (b,)` (of emission measure `measure`,
    sr or m^2) whose corners landed as landings `idx (b,3)` (by landing:
    chart `xy (L,2)`, `weight (L,3)`, chart area per world area `scale
    (L,)`, world `points (L,3)`, `island (L,)`, receiver `obj (L,)`).

    A beam's flux is Phi = measure (w0 + w1 + w2) / 3 (W), spread evenly
    over the triangle its corners land on: irradiance E = Phi s / A, A its
    chart area and s its mean chart area per world area (Heckbert and
    Hanrahan 1984). It is good where A > `min_area` of its receiver (by
    object), its corners share an island, and its world triangle is at most
    _MAX_STRETCH times what A stands for (A / s): more crosses a gap in the
    chart island (a bowl's bottom to its rim, over the wall, in other
    islands).

    Across a box chart's seam (corners on different islands of a chart that
    projects) a beam shorter than the receiver's `reach` (m, 0: none),
    the gutter less SEAM_MARGIN_CELLS, and of positive world area, is
    copied into each island, projected there, of irradiance Phi / world
    area: the light reaches across the seam on both sides (the part past an
    island's edge falls in its gutter, unseen), where photons would leave a
    line; over a crease (a rim's edge) both sides get the beam's mean
    irradiance, a strip one beam wide, still closer than photons (measured
    on a bowl's rim). `copies (b,3)` marks the corners whose island gets
    one: the first corner's, and each later one on an island not yet
    named.

    Returns (corners (b,3,2) chart metres, flux (b,3) W, irradiance (b,3)
    W/m^2, world_area (b,) m^2, good (b,), copies (b,3))."""
    count = len(tri)
    corners, flux, irradiance = np.empty((count, 3, 2)), np.empty((count, 3)), np.zeros((count, 3))
    world_area, good, copies = np.empty(count), np.zeros(count, dtype=np.bool_), np.zeros((count, 3), dtype=np.bool_)
    for b in range(count):
        i0, i1, i2 = idx[b, 0], idx[b, 1], idx[b, 2]
        for k in range(3):
            corners[b, k, 0], corners[b, k, 1] = xy[idx[b, k], 0], xy[idx[b, k], 1]
            flux[b, k] = measure[tri[b]] * (weight[i0, k] + weight[i1, k] + weight[i2, k]) / 3.0
        area = abs(signed_area1(xy[i0], xy[i1], xy[i2]))
        mean_scale = (scale[i0] + scale[i1] + scale[i2]) / 3.0
        world_area[b] = _world_area(points[i0], points[i1], points[i2])
        if area > 0.0:
            for k in range(3):
                irradiance[b, k] = flux[b, k] * (mean_scale / area)
        one_island = island[i0] == island[i1] and island[i0] == island[i2]
        good[b] = (one_island and area > min_area[obj[i0]]
                   and world_area[b] * mean_scale <= _MAX_STRETCH * area)
        longest = max(max(_distance(points[i0], points[i1]), _distance(points[i1], points[i2])),
                      _distance(points[i2], points[i0]))
        if not one_island and longest < reach[obj[i0]] and world_area[b] > 0.0:
            copies[b, 0] = True
            copies[b, 1] = island[i1] != island[i0]
            copies[b, 2] = island[i2] != island[i0] and island[i2] != island[i1]
    return corners, flux, irradiance, world_area, good, copies


@inline
def _turns_right(a, b, c):
    """Whether the 2D path a, b, c ((2,) each) turns clockwise or goes
    straight on (_COLLINEAR)."""
    return 2.0 * signed_area1(a, b, c) <= _COLLINEAR * _distance_2d(a, b) * _distance_2d(a, c)


@inline
def _distance_2d(a, b):
    """|b - a| of 2D points."""
    return np.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2)


@inline
def _width(corners, b, ux, uy):
    """The width of beam `b` of `corners (b,3,2)` along (ux, uy); 0 for u = 0."""
    lo, hi = np.inf, -np.inf
    for k in range(3):
        along = corners[b, k, 0] * ux + corners[b, k, 1] * uy
        lo, hi = min(lo, along), max(hi, along)
    size = np.sqrt(ux * ux + uy * uy)
    return (hi - lo) / size if size > 0.0 else 0.0


@inline
def _taper(width, ux, uy, ratio):
    """1 / (1 + (w / (ratio |u|))^4) for a beam of `width` w along (ux,
    uy): 1 for a beam much narrower than u, 1/2 at `ratio` times as wide,
    0 for a far wider one (and for u = 0)."""
    size = np.sqrt(ux * ux + uy * uy)
    if size == 0.0:
        return 0.0
    return 1.0 / (1.0 + (width / (ratio * size)) ** 4)


@inline
def _parts(width, ux, uy, most, cell):
    """Parts of the image along (ux, uy) for a beam of `width` along it: as
    many as it takes for each to be no wider than half the beam, or than
    PART_CELLS map cells of `cell` m, 2 at least and `most` at most."""
    part = max(0.5 * width, PART_CELLS * cell, 1e-300)
    return min(most, max(2, int(np.ceil(np.sqrt(ux * ux + uy * uy) / part))))


@inline
def _bilinear(spread, b, s, t, axis):
    """Coordinate `axis` of the point (s, t) of the unit square on the
    quadrilateral `spread[b] (4,2)` (corners at (0,0), (1,0), (1,1), (0,1))."""
    return ((1.0 - s) * (1.0 - t) * spread[b, 0, axis] + s * (1.0 - t) * spread[b, 1, axis]
            + s * t * spread[b, 2, axis] + (1.0 - s) * t * spread[b, 3, axis])


@inline
def _part_area(spread, b, s0, s1, r0, r1):
    """The signed area of the flat quadrilateral whose corners are the
    points (s0, r0), (s1, r0), (s1, r1), (s0, r1) of `spread[b]`'s
    (`_bilinear`): the parts of a split tile the whole, and their areas
    add up to its area."""
    x0, y0 = _bilinear(spread, b, s0, r0, 0), _bilinear(spread, b, s0, r0, 1)
    x1, y1 = _bilinear(spread, b, s1, r0, 0), _bilinear(spread, b, s1, r0, 1)
    x2, y2 = _bilinear(spread, b, s1, r1, 0), _bilinear(spread, b, s1, r1, 1)
    x3, y3 = _bilinear(spread, b, s0, r1, 0), _bilinear(spread, b, s0, r1, 1)
    return 0.5 * ((x0 * y1 - x1 * y0) + (x1 * y2 - x2 * y1) + (x2 * y3 - x3 * y2) + (x3 * y0 - x0 * y3))


@inline
def _in_axes(x, y, ux, uy, vx, vy, det, keep_u, keep_v):
    """The 2D vector (x, y) = a u + c v with a times `keep_u` and c times
    `keep_v` (det = u x v, not 0)."""
    a = keep_u * (x * vy - y * vx) / det
    c = keep_v * (ux * y - uy * x) / det
    return a * ux + c * vx, a * uy + c * vy


@inline
def _spread_plan1(corners, spread, b, most, cell):
    """How `_spread_beams` spreads beam `b`: (u, v (2 each), det, the
    moves' tapers along u and v, the parts along u and v, the parts'
    tapers along u and v, whether the parts are hulls)."""
    ux = 0.5 * (spread[b, 1, 0] + spread[b, 2, 0] - spread[b, 0, 0] - spread[b, 3, 0])
    uy = 0.5 * (spread[b, 1, 1] + spread[b, 2, 1] - spread[b, 0, 1] - spread[b, 3, 1])
    vx = 0.5 * (spread[b, 2, 0] + spread[b, 3, 0] - spread[b, 0, 0] - spread[b, 1, 0])
    vy = 0.5 * (spread[b, 2, 1] + spread[b, 3, 1] - spread[b, 0, 1] - spread[b, 1, 1])
    det = ux * vy - uy * vx
    width_u, width_v = _width(corners, b, ux, uy), _width(corners, b, vx, vy)
    move_u, move_v = _taper(width_u, ux, uy, MOVE_RATIO), _taper(width_v, vx, vy, MOVE_RATIO)
    split_u = _parts(width_u, ux, uy, most, cell) if move_u > _STILL else 1
    split_v = _parts(width_v, vx, vy, most, cell) if move_v > _STILL else 1
    keep_u = _taper(width_u, ux / split_u, uy / split_u, 1.0)
    keep_v = _taper(width_v, vx / split_v, vy / split_v, 1.0)
    hulled = det != 0.0 and keep_u > _STILL and keep_v > _STILL
    return ux, uy, vx, vy, det, move_u, move_v, split_u, split_v, keep_u, keep_v, hulled


@kernel("Tuple((f8[:, :, ::1], f8[:, ::1], f8[:, :, ::1], f8[:, ::1]))(f8[:, :, ::1], f8[:, ::1], f8[:, :, ::1], "
        "i8[::1], f8)")
def _spread_beams(corners, irradiance, spread, most_parts, cell):
    """Beams of `corners (b,3,2)` chart metres and `irradiance (b,3)`
    spread over the image of the lamp's cell their paths stand for, the
    quadrilateral `spread (b,4,2)` (where the cell's corners move the
    landing, the mean of the beam's corners'; u, v its mean edges): to
    first order the cell's light through the grid triangle, the beam
    convolved with the image.

    The convolution is copies of the beam, up to `most_parts (b,)` along
    each of the image's ways (`_parts`), each moved to the centre of its part of
    the image (its split into as many parts)
    with its part's share of the image's area of the light: copies of a tiling tile, so light that is
    even stays even. A beam much smaller than its part (a focus, where a
    lamp point's light gathers) is spread over it: uniformly over the
    Minkowski sum of the beam and the part (the convex hull of the 12
    points corner + part's corner, Andrew's monotone chain, at most 7
    corners; irradiance times the beam's area over the hull's), so that
    the parts tile. The hulls of wider neighbouring beams overlap at their
    corners, so the part is kept along u and along v by `_taper`(1) of the
    beam's width that way; and the copies' moves by `_taper`(MOVE_RATIO),
    copies that no longer move (a beam wider than many images, where a
    lamp point's light is as smooth as the lamp's) being one.

    Returns the copies that stay triangles (k,3,2) and their irradiance
    (k,3), and the hulls (h,7,2), each padded by repeating its last corner
    (raster.py), and theirs (h,3): each kind in arrays of its own size."""
    count = len(corners)
    triangles = hulls = 0
    for b in range(count):
        plan = _spread_plan1(corners, spread, b, most_parts[b], cell)
        if plan[11]:
            hulls += plan[7] * plan[8]
        else:
            triangles += plan[7] * plan[8]
    out_t, values_t = np.empty((triangles, 3, 2)), np.empty((triangles, 3))
    out_h, values_h = np.empty((hulls, 7, 2)), np.empty((hulls, 3))
    points, hull = np.empty((12, 2)), np.empty((24, 2))
    t = h_row = 0
    for b in range(count):
        ux, uy, vx, vy, det, move_u, move_v, split_u, split_v, keep_u, keep_v, hulled = _spread_plan1(
            corners, spread, b, most_parts[b], cell)
        moved = det != 0.0 and split_u * split_v > 1
        beam_area = abs(signed_area1(corners[b, 0], corners[b, 1], corners[b, 2]))
        whole = _part_area(spread, b, 0.0, 1.0, 0.0, 1.0)
        for i in range(split_u):
            for j in range(split_v):
                s0, s1 = i / split_u, (i + 1) / split_u
                r0, r1 = j / split_v, (j + 1) / split_v
                cx = _bilinear(spread, b, 0.5 * (s0 + s1), 0.5 * (r0 + r1), 0)
                cy = _bilinear(spread, b, 0.5 * (s0 + s1), 0.5 * (r0 + r1), 1)
                # the copy's move: to its part's centre, each way kept by its taper
                mx, my = _in_axes(cx, cy, ux, uy, vx, vy, det, move_u, move_v) if moved else (0.0, 0.0)
                n = 0
                for q in range(4 if hulled else 1):
                    qx, qy = 0.0, 0.0
                    if hulled:
                        # the part's corner about its centre, each way kept by its taper
                        s, r = s1 if q == 1 or q == 2 else s0, r1 if q >= 2 else r0
                        qx, qy = _in_axes(_bilinear(spread, b, s, r, 0) - cx, _bilinear(spread, b, s, r, 1) - cy,
                                          ux, uy, vx, vy, det, keep_u, keep_v)
                    for k in range(3):
                        x, y = corners[b, k, 0] + mx + qx, corners[b, k, 1] + my + qy
                        # sorted by (x, y) as they come
                        p = n
                        while p > 0 and (points[p - 1, 0] > x or (points[p - 1, 0] == x and points[p - 1, 1] > y)):
                            points[p, 0], points[p, 1] = points[p - 1, 0], points[p - 1, 1]
                            p -= 1
                        points[p, 0], points[p, 1] = x, y
                        n += 1
                h = 0
                for sweep in range(2):
                    # the lower chain left to right, then the upper one back, from its last point
                    floor = h + 2
                    for e in range(n):
                        p = e if sweep == 0 else n - 1 - e
                        while h >= floor and _turns_right(hull[h - 2], hull[h - 1], points[p]):
                            h -= 1
                        hull[h, 0], hull[h, 1] = points[p, 0], points[p, 1]
                        h += 1
                    h -= 1
                area = 0.0
                for k in range(1, h - 1):
                    area += signed_area1(hull[0], hull[k], hull[k + 1])
                if h > 7 or not area > 0.0:
                    h = 3
                    for k in range(3):
                        hull[k, 0], hull[k, 1] = corners[b, k, 0] + mx, corners[b, k, 1] + my
                    area = beam_area
                # each part's share of the light is its share of the image's area (a sky
                # region's cell at the pole is a triangle, whose parts are not alike)
                part = 1.0 / (split_u * split_v)
                if moved and whole != 0.0:
                    part = max(_part_area(spread, b, s0, s1, r0, r1) / whole, 0.0)
                share = beam_area / area * part
                if hulled:
                    for k in range(7):
                        out_h[h_row, k, 0], out_h[h_row, k, 1] = hull[min(k, h - 1), 0], hull[min(k, h - 1), 1]
                    for c in range(3):
                        values_h[h_row, c] = irradiance[b, c] * share
                    h_row += 1
                else:
                    for k in range(3):
                        out_t[t, k, 0], out_t[t, k, 1] = hull[k, 0], hull[k, 1]
                    for c in range(3):
                        values_t[t, c] = irradiance[b, c] * share
                    t += 1
    return out_t, values_t, out_h, values_h


def photon_lamps(lights: list[Light], smooth: list[Sphere], rough: list[Sphere]) -> tuple[list[Light], list[Light]]:
    """(the lamps whose light beam mode sends all as photons, those that send
    photons toward the rough casters and beams toward the smooth ones), of
    the `lights`, the casters' bounding spheres being `smooth` and `rough`.

    A lamp that can light a rough caster (aims.visible_targets) sends
    photons toward it: its light scatters about random microfacet normals,
    so neighbouring grid paths part there and bound no beam; and where a
    lamp with a size would be a grid of point lamps for its beams, photons
    leave every point of it. Measured on the ball lens under a sphere lamp
    at Roughness 0.05, 0.2 and 0.5 (benchmarks/rough_glass.py), the photon
    pass comes within 2% of Cycles' caustic sooner than the beam grid's
    paths landing as photons past the rough surface, and within 5% sooner
    than beams spread about shared microfacet normals; at 0.5 only the
    grid's paths reach 5%, at 8 times the lamp rays. Toward the smooth
    casters it keeps its beams. Where its aims at the two overlap, a ray
    that meets a smooth caster's bounding sphere is the beams' and one that
    meets only rough casters' spheres the photons' (aims.meets_any;
    BeamSource.rough, Emitter.beamed), so none is counted twice, and a
    smooth glass in front of or beside a rough one keeps its beams; the
    grid paths that go on to meet the rough caster land as photons. A lamp
    that lights no smooth caster, and an emitting mesh, whose pieces aim on
    their own, send all their light as photons."""
    whole, apart = [], []
    for light in lights:
        if visible_targets(light, rough):
            alone = isinstance(light, MeshLight) or not visible_targets(light, smooth)
            (whole if alone else apart).append(light)
    return whole, apart


def _photon_emitters(lights: list[Light], whole: list[Light], apart: list[Light], targets: list[Sphere],
                     smooth: list[Sphere], rough: list[Sphere], scene_sphere: Sphere,
                     settings: RenderSettings) -> list[Emitter]:
    """Beam mode's photon emitters (`photon_lamps`): the `whole` lamps'
    toward every caster of `targets`, the `apart` ones' toward the `rough`
    casters, leaving the rays that meet a `smooth` one's sphere to the
    beams, each with the share of the lamp rays that the flux it sends
    there has of the flux all the `lights` send toward the casters."""
    if not whole and not apart:
        return []
    every = make_emitters(lights, targets, scene_sphere, "targeted", settings.energy, settings.lamp_rays,
                          settings.seed)
    emitters = [e for e in every if any(e.source is light for light in whole)]
    if apart:
        def flux(some: list[Emitter]) -> float:
            return sum(aim.flux(settings.energy) for e in some for aim in e.aims)
        toward_rough = make_emitters(apart, rough, scene_sphere, "targeted", settings.energy, 1, settings.seed)
        rays = int(round(settings.lamp_rays * flux(toward_rough) / flux(every)))
        added = make_emitters(apart, rough, scene_sphere, "targeted", settings.energy, rays, settings.seed)
        # ids after every other photon's
        base = max(e.id_base + e.count for e in every)
        for e in added:
            e.id_base += base
            e.beamed = tuple(smooth)
        emitters += added
    return emitters


def beam_pass(scene: Scene, lights: list[Light], settings: RenderSettings, accel: Accelerator, materials: Materials,
              maps: dict, monitor: Monitor, share: float) -> LampPassStats:
    """Trace the grids of the `lights` in bands of rows into beams on
    `maps`, once per wavelength band, with the lamp rays shared among them
    (the bands' grids in one batch);
    a lamp with a size is points of it (lamp_points.py). Neighbouring bands
    of rows share a row, so every grid triangle is in one."""
    count = materials.band_count
    targets, scene_sphere = casters_and_bounds(scene)
    smooth, rough = smooth_and_rough(scene, targets)
    receivers = np.concatenate([o.mesh.vertices for o in scene.receivers])
    # toward rough casters lamps send photons (photon_lamps)
    whole, apart = photon_lamps(lights, smooth, rough)
    emitters = _photon_emitters(lights, whole, apart, targets, smooth, rough, scene_sphere, settings)
    beamed = [light for light in lights if not any(light is other for other in whole)]
    # each wavelength band's share of the lamp rays that photons leave
    band_rays = (settings.lamp_rays - sum(e.count for e in emitters)) // count
    lamps, phases, cells = beam_lamps(beamed, smooth, scene_sphere, (receivers.min(axis=0), receivers.max(axis=0)),
                                      min(imap.cell for imap in maps.values()), band_rays)
    sources = beam_sources(lamps, smooth, scene_sphere, settings.energy, band_rays, phases, cells)
    for source in sources:
        if visible_targets(source.light, rough):
            source.rough, source.smooth = tuple(rough), tuple(smooth)
    stacks: dict[tuple[int, tuple[int, int]], list[BeamSource]] = {}
    for source in sources:
        stacks.setdefault((source.grid, lamp_media(accel, source.light)), []).append(source)
    jobs = []
    for (grid, media), stack in stacks.items():
        bands = np.repeat(np.arange(count), len(stack))
        stack = stack * count
        # GRID_BANDS bands of rows, of at most chunk_size / BAND_SHARE points
        # each: a band's cost is mostly work per bounce and refinement level,
        # whatever its paths, so fewer bands are faster (the pool's beam pass
        # at 2 threads: 0.13 s in 2 bands, 0.16 s in 4; the ball lens's at
        # 3,162 lamp rays 42, 61 and 52 ms in 2, 4 and 1), and grids of one
        # size are traced together
        rows = max(1, min(settings.chunk_size // (BAND_SHARE * grid * len(stack)), -(-(grid - 1) // GRID_BANDS)))
        batch = SourceBatch(stack)
        jobs += [partial(band_beams, batch, first, min(first + rows + 1, grid), accel, materials, maps,
                         settings.max_depth, media, settings.beam_refinement, bands, settings.seed)
                 for first in range(0, grid - 1, rows)]
    # bands of rows spread over the grids, both ends first, in any first part
    # of the jobs: the maps lay their layers out from the first beams they get
    # (BeamMap)
    jobs = [jobs[i] for i in spread_order(len(jobs))] + photon_jobs(emitters, accel, materials, maps, settings)
    stats, deliver = deliverer(maps)
    run_chunks(jobs, settings.threads, monitor, 0.0, share, "beam pass", deliver)
    return stats


def spread_order(count: int) -> np.ndarray:
    """(count,) 0..count-1 with both ends first, then by the radical inverse
    in base 2 of their place in the range (van der Corput: 1/2, 1/4, 3/4,
    ...), so that every first part of the order spreads evenly over the
    whole range."""
    if count <= 2:
        return np.arange(count)
    bits = int(count - 1).bit_length() + 1
    index = np.arange(1 << bits)
    radical = np.zeros(len(index))
    for b in range(bits):
        radical += ((index >> b) & 1) * 0.5 ** (b + 1)
    picks = np.rint(np.concatenate([[0.0, 1.0], radical]) * (count - 1)).astype(np.int64)
    _, first = np.unique(picks, return_index=True)
    ordered = picks[np.sort(first)]
    return np.concatenate([ordered, np.setdiff1d(np.arange(count), ordered)])
