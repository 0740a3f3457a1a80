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
from ..emission.world_sun import extract_sun
from ..maps.deposits import Deposits
from ..maps.illumination_map import IlluminationMap
from ..maps.receivers import GUTTER_CELLS
from ..maps.raster import signed_areas
from ..sampling.hash import hash_uniform
from ..scene import Light, RenderSettings, Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS, Hits
from ..util.parallel import Monitor, run_chunks
from ..util.rows import row_ids, take_rows
from ..util.vectors import DIVISION_FLOOR, cross_rows, length, max_channel
from .bounce import SCATTERED, Interface, facets, on_maps, split, trace
from .lamp_pass import JobResult, LampPassStats, deliverer, lamp_medium
from .paths import MIN_BRANCH_WEIGHT, Paths, relative_floor
from .photon import FACET_STREAM, photon_jobs

# A cell whose two triangles' landed areas differ by more than this factor is
# split (measured on the ball lens: lower factors spend paths for no gain).
REFINE_RATIO = 8.0
# Families whose throughput is below this (reflections off the outside, weak
# internal reflections) never split a cell: too little flux for the paths.
REFINE_THROUGHPUT = 0.2
# A band holds at most chunk_size / BAND_SHARE grid points: each becomes up
# to four with refinement, with its landings, lookups and beams (about 3.5 kB
# a point in all), so that two bands in flight stay near 0.25 GB each.
BAND_SHARE = 4
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
            weight, floor = np.take(paths.weight, rows, axis=0), np.take(paths.floor, rows)
            with np.errstate(divide="ignore", invalid="ignore"):
                throughput = np.where(floor > 0, max_channel(weight) * MIN_BRANCH_WEIGHT / floor, 0.0)
            self.landed.append(Landings(np.take(paths.ids, rows), np.take(paths.family, rows),
                                        np.full(len(rows), obj), island, np.take(hits.points, rows, axis=0), xy,
                                        scale, weight, throughput))

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        if surface.rough.any():
            uv = np.stack([hash_uniform(paths.ids, FACET_STREAM + 2 * depth + k, self.seed) for k in (0, 1)], axis=1)
            surface = facets(surface, paths.dirs, self.materials, hits.obj, uv)
        return split(self.accel, self.materials, paths, hits, surface, carries_light=True)


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


class _Lookup:
    """Landings indexed by grid vertex and by family group.

    Vertices are keys on a grid 2^levels times finer than the source's,
    key = row * width + col; a group is one (family, receiver, island of
    its chart, unless the chart `projects` beams into any island), and a
    pair (element, group) is numbered element * stride + group."""

    def __init__(self, landings: Landings, keys: int, maps: dict[int, IlluminationMap]):
        self.landings, self.keys = landings, keys
        projects = np.zeros(max(maps, default=-1) + 1, dtype=bool)
        for index, imap in maps.items():
            projects[index] = imap.chart.projects
        piece = np.where(projects[landings.obj], 0, landings.island)
        self.group = row_ids(np.stack([landings.family, landings.obj.astype(np.uint64),
                                       piece.astype(np.uint64)], axis=1))
        self.stride = max(int(self.group.max(initial=-1)) + 1, 1)
        combo = self.group * keys + landings.vertex
        self._combo_order = np.argsort(combo)
        self._combo = combo[self._combo_order]
        self._vertex_order = np.argsort(landings.vertex, kind="stable")
        self._vertex = landings.vertex[self._vertex_order]

    def find(self, group: np.ndarray, vertex: np.ndarray) -> np.ndarray:
        """(n,) index of the landing of `group` at `vertex` (both (n,)); the
        caller knows it exists."""
        pos = np.searchsorted(self._combo, group * self.keys + vertex)
        return self._combo_order[pos.clip(0, max(len(self._combo) - 1, 0))]

    def pairs(self, corners: np.ndarray):
        """Every landing at a corner of every element (a cell or a triangle
        with k corners, `corners (n,k)` vertex keys). Returns (element (p,),
        group (p,), landing (p,), count (p,) how many of the element's
        corners landed in that group)."""
        start = np.searchsorted(self._vertex, corners.ravel(), side="left")
        found = np.searchsorted(self._vertex, corners.ravel(), side="right") - start
        element = np.repeat(np.repeat(np.arange(len(corners)), corners.shape[1]), found)
        offset = np.arange(len(element)) - np.repeat(np.cumsum(found) - found, found)
        landing = self._vertex_order[np.repeat(start, found) + offset]
        group = self.group[landing]
        _, inverse, count = np.unique(element * self.stride + group, return_inverse=True,
                                      return_counts=True)
        return element, group, landing, count[inverse.reshape(-1)]

    def first_of_each(self, element: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The distinct (element, group) pairs among rows of `pairs`."""
        _, first = np.unique(element * self.stride + group, return_index=True)
        return element[first], group[first]


@dataclass
class _Cells:
    """Square cells of stacked grids: the corner `row, col (n,)` nearest
    each grid's origin and the edge `size (n,)`, in fine grid steps, on the
    grid whose vertex keys start at `base (n,)` (key = base + row * width +
    col)."""

    row: np.ndarray
    col: np.ndarray
    size: np.ndarray
    base: np.ndarray

    def corners(self, width: int) -> np.ndarray:
        """(n,4) vertex keys: (r, c), (r+s, c), (r, c+s), (r+s, c+s)."""
        row, col, size = self.row, self.col, self.size
        return self.base[:, None] + np.stack([row * width + col, (row + size) * width + col,
                                              row * width + col + size, (row + size) * width + col + size], axis=1)

    def take(self, rows) -> "_Cells":
        return _Cells(self.row[rows], self.col[rows], self.size[rows], self.base[rows])

    def split(self, rows: np.ndarray) -> "_Cells":
        """These cells with those at `rows` (bool) cut in four."""
        cut = self.take(rows)
        half = cut.size // 2
        kept = self.take(~rows)
        return _Cells(np.concatenate([kept.row, cut.row, cut.row + half, cut.row, cut.row + half]),
                      np.concatenate([kept.col, cut.col, cut.col, cut.col + half, cut.col + half]),
                      np.concatenate([kept.size] + [half] * 4),
                      np.concatenate([kept.base] + [cut.base] * 4))


def _cell_halves(corners: np.ndarray, cells: _Cells, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The two triangles (n,3) of each cell `corners (n,4)`, split along the
    diagonal that points at the grid's centre. The concentric map that lays
    the grid over an aim bends along the square's two diagonals, so a
    triangle across one lands distorted: its beam comes out too bright and
    its neighbour too dim, a dotted seam. Cut this way, no triangle crosses
    them."""
    half = 0.5 * (width - 1)
    toward = (cells.row + 0.5 * cells.size - half) * (cells.col + 0.5 * cells.size - half) >= 0.0
    main = np.stack([corners[:, [0, 1, 3]], corners[:, [0, 3, 2]]])
    anti = np.stack([corners[:, [0, 1, 2]], corners[:, [1, 3, 2]]])
    chosen = np.where(toward[None, :, None], main, anti)
    return chosen[0], chosen[1]


def _diverging(lookup: _Lookup, cells: _Cells, width: int) -> np.ndarray:
    """(n,) bool: the cells whose paths diverge. Some but not all of a
    cell's corners land in a family of throughput at least
    REFINE_THROUGHPUT (a silhouette, total internal reflection), or its two
    triangles land with opposite orientation (a fold of the caustic crosses
    it) or areas more than REFINE_RATIO apart. Paths a rough surface
    scattered (SCATTERED families) part from every neighbour, and splitting
    would not bring them together: they split no cell."""
    corners = cells.corners(width)
    element, group, landing, count = lookup.pairs(corners)
    split = np.zeros(len(corners), dtype=bool)
    strong = lookup.landings.throughput[landing] >= REFINE_THROUGHPUT
    scattered = (lookup.landings.family[landing] & SCATTERED) != 0
    split[element[(count < 4) & strong & ~scattered]] = True
    cell, group = lookup.first_of_each(element[count == 4], group[count == 4])
    first, second = _cell_halves(corners[cell], cells.take(cell), width)
    a, b = (signed_areas(np.stack([lookup.landings.xy[lookup.find(group, tri[:, k])] for k in range(3)], axis=1))
            for tri in (first, second))
    small, large = np.minimum(np.abs(a), np.abs(b)), np.maximum(np.abs(a), np.abs(b))
    # across a box chart's seam chart areas do not compare
    island = np.stack([lookup.landings.island[lookup.find(group, corners[cell, k])] for k in range(4)], axis=1)
    seam = (island != island[:, :1]).any(axis=1)
    split[cell[~seam & ((a * b <= 0.0) | (large > REFINE_RATIO * small))]] = True
    return split


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
    cells = _Cells(np.tile(row, len(sources)), np.tile(col, len(sources)), np.full(len(row) * len(sources), scale),
                   np.repeat(np.arange(len(sources)) * keys, len(row)))
    traced = np.unique(cells.corners(width))
    on_grid = len(traced)
    owned = on_grid - (grid * len(sources) if end_row < grid else 0)
    landings = trace_vertices(traced)
    for _ in range(levels):
        diverge = _diverging(_Lookup(landings, keys * len(sources), maps), cells, width) & (cells.size > 1)
        if not diverge.any():
            break
        cells = cells.split(diverge)
        children = np.unique(cells.corners(width))
        fresh = children[~np.isin(children, traced, assume_unique=True)]
        landings = Landings.concat([landings, trace_vertices(fresh)])
        traced = np.union1d(traced, fresh)

    triangles, area, centres = _crack_free_triangles(cells, width, traced)
    landings = Landings.concat([landings, trace_vertices(centres)])
    cell_measure = np.array([source.cell_measure for source in sources])
    measure = cell_measure[triangles[:, 0] // keys] * area / scale ** 2
    deposits, beams, flux_landed = _beams_and_photons(_Lookup(landings, keys * len(sources), maps), triangles, measure,
                                                      maps)
    refined = len(traced) + len(centres) - on_grid
    return JobResult(deposits, LampPassStats(owned + refined, refined, beams, flux_landed))


def _crack_free_triangles(cells: _Cells, width: int, traced: np.ndarray):
    """Triangles over the leaf cells that share every traced vertex with
    their neighbours, so that beams of a split cell and of its unsplit
    neighbour meet without cracks. A cell with no traced point inside its
    edges is two triangles; one with such points (a split neighbour's) is a
    fan from its centre through its boundary points in order.

    Returns (triangles (n,3) vertex keys, area (n,) in fine grid units
    squared, centres (k,) vertex keys of the fan centres, still to trace)."""
    row, col, size, base = cells.row, cells.col, cells.size, cells.base
    count = 4 * size
    cell = np.repeat(np.arange(len(size)), count)
    j = np.arange(len(cell)) - np.repeat(np.cumsum(count) - count, count)
    s, side, along = size[cell], j // size[cell], j % size[cell]
    # the boundary walked counter-clockwise in (col, row): bottom, right, top, left
    r = row[cell] + np.choose(side, [0 * along, along, s, s - along])
    c = col[cell] + np.choose(side, [along, s, s - along, 0 * along])
    key = base[cell] + r * width + c
    pos = np.searchsorted(traced, key).clip(0, len(traced) - 1)
    kept = (along == 0) | (traced[pos] == key)
    kept_per_cell = np.bincount(cell[kept], minlength=len(size))
    fan = kept_per_cell > 4

    plain = cells.take(~fan)
    corners = plain.corners(width)
    halves = 0.5 * plain.size.astype(np.float64) ** 2
    on_fan = kept & fan[cell]
    ring_cell, ring_key = cell[on_fan], key[on_fan]
    new_cell = np.r_[True, ring_cell[1:] != ring_cell[:-1]][:len(ring_cell)]
    ring_next = np.roll(ring_key, -1)
    ring_next[np.roll(new_cell, -1)] = ring_key[new_cell]
    half = size // 2
    centre_key = base + (row + half) * width + col + half
    centres = centre_key[fan]
    tri_centre = centre_key[ring_cell]
    local = [(k - base[ring_cell]) for k in (tri_centre, ring_key, ring_next)]
    (cr, cc), (ar, ac), (br, bc) = (np.divmod(k, width) for k in local)
    fan_area = 0.5 * np.abs((ac - cc) * (br - cr) - (ar - cr) * (bc - cc)).astype(np.float64)
    first, second = _cell_halves(corners, plain, width)
    triangles = np.concatenate([first, second, np.stack([tri_centre, ring_key, ring_next], axis=1)])
    return triangles, np.concatenate([halves, halves, fan_area]), centres


def _beams_and_photons(lookup: _Lookup, triangles: np.ndarray, measure: np.ndarray,
                       maps: dict[int, IlluminationMap]):
    """Triangles `triangles (n,3)` (vertex keys) of emission measure
    `measure (n,)` (sr or m^2) whose three paths landed in one family become
    beams; the landed corners of the others carry a third of the triangle's
    flux each, as photons. Returns (the deposits, the number of beams, the
    flux (3,) W that beams and photons carry)."""
    land = lookup.landings
    element, group, landing, count = lookup.pairs(triangles)
    tri, tri_group = lookup.first_of_each(element[count == 3], group[count == 3])
    idx = np.stack([lookup.find(tri_group, triangles[tri, k]) for k in range(3)], axis=1)
    obj = land.obj[idx[:, 0]]
    xy = np.take(land.xy, idx, axis=0)
    area = np.abs(signed_areas(xy))
    corner_weight = np.take(land.weight, idx, axis=0)
    flux = measure[tri, None] * (corner_weight[:, 0] + corner_weight[:, 1] + corner_weight[:, 2]) / 3.0
    chart_area = np.zeros(max(maps, default=-1) + 1)
    for index, imap in maps.items():
        chart_area[index] = np.prod(np.maximum(imap.chart.size, DIVISION_FLOOR))
    scale = land.scale[idx]
    mean_scale = (scale[:, 0] + scale[:, 1] + scale[:, 2]) / 3.0
    world = np.take(land.points, idx, axis=0)
    world_area = 0.5 * length(cross_rows(world[:, 1] - world[:, 0], world[:, 2] - world[:, 0]))
    good = (area > _MIN_AREA_FRACTION * chart_area[obj]) & (world_area * mean_scale <= _MAX_STRETCH * area)
    with np.errstate(divide="ignore", invalid="ignore"):
        irradiance = flux * (mean_scale / area)[:, None]
    island = land.island[idx]
    copies = _seam_copies(island, world, world_area, obj, maps)
    copied = copies[:, 0]
    good &= (island[:, 0] == island[:, 1]) & (island[:, 0] == island[:, 2])

    # fallback: each landed corner of an incoherent or degenerate triangle
    # carries a third of that triangle's flux
    pair = element * lookup.stride + group
    degenerate = tri[~good & ~copied] * lookup.stride + tri_group[~good & ~copied]
    loose = (count < 3) | np.isin(pair, degenerate)
    share = np.bincount(landing[loose], weights=measure[element[loose]] / 3.0, minlength=len(land.vertex))
    holders = np.flatnonzero(share > 0)
    photon_flux = share[holders, None] * np.take(land.weight, holders, axis=0)

    deposits = Deposits()
    for o in np.unique(obj[good]):
        deposits.add_beams(int(o), *take_rows(good & (obj == o), xy, irradiance))
    for k in range(3):
        rows = np.flatnonzero(copies[:, k])
        for o in np.unique(obj[rows]):
            mine = rows[obj[rows] == o]
            corners = maps[int(o)].chart.project(island[mine, k], np.take(world, mine, axis=0))
            deposits.add_beams(int(o), corners, np.take(flux, mine, axis=0) / world_area[mine, None])
    good |= copied
    for o in np.unique(land.obj[holders]):
        sel = np.flatnonzero(land.obj[holders] == o)
        at = np.take(holders, sel)
        deposits.add_photons(int(o), np.take(land.xy, at, axis=0), np.take(photon_flux, sel, axis=0),
                             np.take(land.scale, at))
    return deposits, int(good.sum()), flux[good].sum(axis=0) + photon_flux.sum(axis=0)


def _seam_copies(island: np.ndarray, world: np.ndarray, world_area: np.ndarray, obj: np.ndarray,
                 maps: dict[int, IlluminationMap]) -> np.ndarray:
    """(m,3) bool: for beams whose corners landed on different islands of
    a chart that `projects` (`island (m,3)`, world corners `world
    (m,3,3)`), the corners whose island gets a copy of the whole beam, one
    per island, projected into it, of irradiance flux / world area: the
    beam's light reaches across the seam on both sides (the part past an
    island's edge falls in its gutter, unseen), where photons would leave a
    line. Only beams shorter than the gutter, less SEAM_MARGIN_CELLS, so no
    copy reaches another island, and of positive area. Over a crease (a
    rim's edge) both sides get the beam's mean irradiance, a strip one beam
    wide: still closer than photons (measured on a bowl's rim)."""
    reach = np.zeros(len(obj))
    for index, imap in maps.items():
        reach[obj == index] = (GUTTER_CELLS - SEAM_MARGIN_CELLS) * imap.cell if imap.chart.projects else 0.0
    edges = np.maximum(np.maximum(length(world[:, 1] - world[:, 0]), length(world[:, 2] - world[:, 1])),
                       length(world[:, 0] - world[:, 2]))
    mixed = (island[:, 0] != island[:, 1]) | (island[:, 0] != island[:, 2])
    mixed &= (edges < reach) & (world_area > 0.0)
    first = np.stack([np.ones(len(obj), dtype=bool), island[:, 1] != island[:, 0],
                      (island[:, 2] != island[:, 0]) & (island[:, 2] != island[:, 1])], axis=1)
    return first & mixed[:, None]


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


def beam_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials, maps: dict,
              monitor: Monitor, share: float) -> LampPassStats:
    """Trace every source's grid in bands of rows into beams on `maps`, once
    per wavelength band, with the lamp rays shared among them; a lamp with
    a size is points of it (lamp_points.py). Neighbouring bands of rows
    share a row, so every grid triangle is in one."""
    count = materials.band_count
    targets, scene_sphere = casters_and_bounds(scene)
    receivers = np.concatenate([o.mesh.vertices for o in scene.receivers])
    # the world's sun comes as beams, the rest of its light as photons, and
    # so does the light of lamps that light a rough caster; each their
    # share of the lamp rays by its flux
    sun, world = extract_sun(scene.world)
    lights = scene.lights + ([sun] if sun is not None else [])
    as_photons = photon_lamps(lights, scene)
    emitters = [e for e in make_emitters(lights, world, targets, scene_sphere, "targeted", settings.energy,
                                         settings.lamp_rays, settings.seed)
                if e.light is None or any(e.light is light for light in as_photons)]
    beamed = [light for light in lights if not any(light is other for other in as_photons)]
    from_photons = sum(e.count for e in emitters)
    lamps = beam_lamps(beamed, targets, scene_sphere, (receivers.min(axis=0), receivers.max(axis=0)),
                       min(imap.cell for imap in maps.values()), (settings.lamp_rays - from_photons) // count)
    sources = beam_sources(lamps, targets, scene_sphere, settings.energy,
                           (settings.lamp_rays - from_photons) // count)
    stacks: dict[tuple[int, int], list[BeamSource]] = {}
    for source in sources:
        stacks.setdefault((source.grid, lamp_medium(accel, source.light)), []).append(source)
    jobs = []
    for (grid, medium), stack in stacks.items():
        # one band of rows per thread, of at most chunk_size / BAND_SHARE points: a
        # band's cost is mostly numpy work per bounce and refinement level,
        # whatever its paths, so fewer bands are faster (measured on the ball
        # lens: 0.19 s against 0.29 s for two per thread), and grids of one
        # size are traced together
        rows = max(1, min(settings.chunk_size // (BAND_SHARE * grid * len(stack)),
                          -(-(grid - 1) // settings.threads)))
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
