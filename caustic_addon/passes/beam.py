"""Caustic beams: noise-free caustics from photons on a structured grid.

Photons leave a lamp on a G x G grid laid over its target cone (equal-area:
Shirley and Chiu's concentric square-to-disc map, then the cone's
cos(theta) = 1 - rho^2 (1 - cos_max)), or over a sun's target disc. At a
dielectric each path splits deterministically into its reflected (weight F)
and refracted (weight 1 - F) branch; at a reflector it only reflects (weight
its reflectance). A path's *family* is its sequence of (surface, event), so
paths that meet the same surfaces in the same order, glass or mirror, make
beams together. Three grid neighbours of the same family that land on the
same receiver bound a beam: the grid triangle's flux, spread evenly over the
triangle the three land on, is irradiance flux / area there (beam tracing,
Heckbert and Hanrahan 1984; Watt 1990). `beam_map.BeamMap` rasterises the
beams with exact area coverage, so the caustic has no noise and sharp edges.

Grid cells whose paths diverge (a silhouette, total internal reflection on
one side, different surfaces, or a fold of the caustic inside the cell) are
split in four and their new corners traced, up to `levels` times.
Triangles whose three paths still disagree fall back to photons: each
landed corner carries a third of the triangle's flux into the map's ordinary
density estimate.

A lamp that can light a rough caster sends photons instead
(`photon_lamps`); grid paths that meet a rough surface all the same (a
spot's light turned toward one by another caster) scatter about microfacet
normals of their own and land as photons.

When a material disperses, every wavelength band traces its own grid with
its own IOR and carries the band's RGB weight (spectrum.py): beams of
different bands land apart, which is the colour of a dispersive caustic.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ..emission.aims import Sphere, casters_and_bounds, visible_targets
from ..emission.beam_sources import BeamSource, beam_sources
from ..emission.lamp_points import beam_lamps
from ..emission.photons import make_emitters
from ..maps.deposits import Deposits
from ..maps.illumination_map import IlluminationMap
from ..maps.receivers import GUTTER_CELLS
from ..maps.raster import signed_area1
from ..sampling.hash import hash_uniform
from ..scene import Light, RenderSettings, Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS, Hits
from ..util.parallel import Monitor, run_chunks
from ..util.jit import inline, kernel
from ..util.rows import take, take_rows
from ..util.vectors import DIVISION_FLOOR, max_channel1, row
from .beam_grid import Cells, LandingIndex, coherent_triangles, crack_free_triangles, diverging, fallback_shares
from .bounce import Interface, facets, on_maps, split, trace
from .lamp_pass import JobResult, LampPassStats, deliverer, lamp_medium
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
    channel)."""

    vertex: np.ndarray
    family: np.ndarray
    obj: np.ndarray
    island: np.ndarray
    points: np.ndarray
    xy: np.ndarray
    scale: np.ndarray
    weight: np.ndarray
    throughput: np.ndarray

    @staticmethod
    def concat(parts: list["Landings"]) -> "Landings":
        if not parts:
            empty = np.zeros(0)
            return Landings(empty.astype(np.int64), empty.astype(np.uint64), empty.astype(np.int64),
                            empty.astype(np.int64), np.zeros((0, 3)), np.zeros((0, 2)), empty, np.zeros((0, 3)),
                            empty)
        return Landings(*(np.concatenate([getattr(p, f) for p in parts])
                          for f in ("vertex", "family", "obj", "island", "points", "xy", "scale", "weight",
                                    "throughput")))


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
        for obj, rows, xy, scale, island in on_maps(self.accel, self.maps, paths, hits):
            weight, floor = take(paths.weight, rows), take(paths.floor, rows)
            throughput = np.empty(len(rows))
            _throughputs(weight, floor, throughput)
            self.landed.append(Landings(take(paths.ids, rows), take(paths.family, rows), np.full(len(rows), obj),
                                        island, take(hits.points, rows), xy, scale, weight, throughput))

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
                dirs: np.ndarray, weight: np.ndarray, vertex: np.ndarray, max_depth: int, start_medium: int = MISS,
                band: int = 0, seed: int = 0) -> Landings:
    """Follow every branch of the vertex paths `vertex (n,)`, starting
    inside object `start_medium` (MISS: in air), until it lands on a
    receiver (after at least one specular event), leaves, or fades below
    MIN_BRANCH_WEIGHT. Dielectrics refract with their IOR in wavelength band
    `band`; rough surfaces scatter by random numbers of `seed`."""
    tracer = BeamTracer(accel, materials, maps, seed)
    paths = Paths.start(origins, dirs, weight, vertex, start_medium, relative_floor(weight),
                        np.full(len(vertex), band, dtype=np.int64), family=True)
    trace(accel, materials, paths, max_depth, tracer)
    return Landings.concat(tracer.landed)


def band_beams(sources: list[BeamSource], first_row: int, end_row: int, accel: Accelerator, materials: Materials,
               maps: dict[int, IlluminationMap], max_depth: int, start_medium: int = MISS,
               levels: int = 0, band: int = 0, seed: int = 0) -> JobResult:
    """Trace grid rows [first_row, end_row) of `sources`, grids of one size
    traced as one batch (the points of a lamp with a size, say), in
    wavelength band `band`, whose paths start inside object `start_medium`,
    splitting cells where their paths diverge (`levels` times at most), and
    turn the landed paths into beams (coherent triangles) and fallback
    photons. The band's lamp rays are its grid points (its last row is the
    next band's first, and counts there) and those refinement added."""
    grid = sources[0].grid
    scale = 1 << levels
    width = (grid - 1) * scale + 1
    keys = width * width

    def trace_vertices(vertex: np.ndarray) -> Landings:
        which, local = np.divmod(vertex, keys)
        rays = [source.rays_at(np.stack([local[which == k] // width, local[which == k] % width], axis=1) / scale)
                for k, source in enumerate(sources)]
        origins, dirs, weight = (np.concatenate(parts) for parts in zip(*rays))
        weight *= materials.band_weights[band]
        order = np.argsort(which, kind="stable")
        return trace_paths(accel, materials, maps, origins, dirs, weight, vertex[order], max_depth, start_medium,
                           band, seed)

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

    triangles, area, centres = crack_free_triangles(cells, width, traced)
    landings = Landings.concat([landings, trace_vertices(centres)])
    cell_measure = np.array([source.cell_measure for source in sources])
    measure = cell_measure[triangles[:, 0] // keys] * area / scale ** 2
    deposits, beams, flux_landed = _beams_and_photons(LandingIndex(landings, maps), triangles, measure, maps)
    refined = len(traced) + len(centres) - on_grid
    return JobResult(deposits, LampPassStats(owned + refined, refined, beams, flux_landed))


def _beams_and_photons(lookup: LandingIndex, triangles: np.ndarray, measure: np.ndarray,
                       maps: dict[int, IlluminationMap]):
    """Triangles `triangles (n,3)` (vertex keys) of emission measure
    `measure (n,)` (sr or m^2) whose three paths landed in one family become
    beams (`_beam_geometry`); the landed corners of the others carry a third
    of the triangle's flux each, as photons. Returns (the deposits, the
    number of beams, the flux (3,) W that beams and photons carry)."""
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
    for o in np.unique(obj[good]):
        deposits.add_beams(int(o), *take_rows(good & (obj == o), corners, irradiance))
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


def photon_lamps(lights: list[Light], scene: Scene) -> list[Light]:
    """The lamps whose light beam mode sends as photons: those that can
    light a rough caster (aims.visible_targets). Its light scatters about
    random microfacet normals, so neighbouring grid paths part there and
    bound no beam; and where a lamp with a size would be a grid of point
    lamps for its beams, photons leave every point of it. Measured on the
    ball lens under a sphere lamp (benchmarks/rough_glass.py), the photon
    pass beats both the beam grid's paths landing as photons past the rough
    surface and beams spread about shared microfacet normals, in time and
    in error; a smooth caster those lamps also light casts photons too."""
    rough = [Sphere.around(o.mesh.vertices) for o in scene.casters if not o.material.smooth]
    return [light for light in lights if rough and visible_targets(light, rough)]


def beam_pass(scene: Scene, lights: list[Light], settings: RenderSettings, accel: Accelerator, materials: Materials,
              maps: dict, monitor: Monitor, share: float) -> LampPassStats:
    """Trace the grids of the `lights` in bands of rows into beams on
    `maps`, once per wavelength band, with the lamp rays shared among them;
    a lamp with a size is points of it (lamp_points.py). Neighbouring bands
    of rows share a row, so every grid triangle is in one."""
    count = materials.band_count
    targets, scene_sphere = casters_and_bounds(scene)
    receivers = np.concatenate([o.mesh.vertices for o in scene.receivers])
    # the lamps that light a rough caster send photons, each lamp its share
    # of the lamp rays by its flux
    as_photons = photon_lamps(lights, scene)
    emitters = [e for e in make_emitters(lights, targets, scene_sphere, "targeted", settings.energy,
                                         settings.lamp_rays, settings.seed)
                if any(e.light is light for light in as_photons)]
    beamed = [light for light in lights if not any(light is other for other in as_photons)]
    # each wavelength band's share of the lamp rays that photons leave
    band_rays = (settings.lamp_rays - sum(e.count for e in emitters)) // count
    lamps, phases = beam_lamps(beamed, targets, scene_sphere, (receivers.min(axis=0), receivers.max(axis=0)),
                               min(imap.cell for imap in maps.values()), band_rays)
    sources = beam_sources(lamps, targets, scene_sphere, settings.energy, band_rays, phases)
    stacks: dict[tuple[int, int], list[BeamSource]] = {}
    for source in sources:
        stacks.setdefault((source.grid, lamp_medium(accel, source.light)), []).append(source)
    jobs = []
    for (grid, medium), stack in stacks.items():
        # GRID_BANDS bands of rows, of at most chunk_size / BAND_SHARE points
        # each: a band's cost is mostly work per bounce and refinement level,
        # whatever its paths, so fewer bands are faster (the pool's beam pass
        # at 2 threads: 0.13 s in 2 bands, 0.16 s in 4; the ball lens's at
        # 3,162 lamp rays 42, 61 and 52 ms in 2, 4 and 1), and grids of one
        # size are traced together
        rows = max(1, min(settings.chunk_size // (BAND_SHARE * grid * len(stack)), -(-(grid - 1) // GRID_BANDS)))
        jobs += [partial(band_beams, stack, first, min(first + rows + 1, grid), accel, materials, maps,
                         settings.max_depth, medium, settings.beam_refinement, band, settings.seed)
                 for band in range(count) for first in range(0, grid - 1, rows)]
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
