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

When a material disperses, every wavelength band traces its own grid with
its own IOR and carries the band's RGB weight (spectrum.py): beams of
different bands land apart, which is the colour of a dispersive caustic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..emission.beam_sources import BeamSource
from ..maps.illumination_map import IlluminationMap
from ..maps.raster import signed_areas
from ..optics.media import beer_lambert
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS
from ..util.rows import row_ids, take_rows
from ..util.vectors import DIVISION_FLOOR, max_channel
from .bounce import orient, scatter

# Branches below this fraction of their vertex's starting weight stop.
MIN_BRANCH_WEIGHT = 1e-4
# A cell whose two triangles' landed areas differ by more than this factor is
# split (measured on the ball lens: lower factors spend paths for no gain).
REFINE_RATIO = 8.0
# Families whose throughput is below this (reflections off the outside, weak
# internal reflections) never split a cell: too little flux for the paths.
REFINE_THROUGHPUT = 0.2
# Beams smaller than this fraction of the chart's area squared fall back to photons.
_MIN_AREA_FRACTION = 1e-16
_SIGNATURE_PRIME = np.uint64(0x100000001B3)


@dataclass
class Landings:
    """Where a band's vertex paths landed on receivers.

    vertex (n,) the path's index among those traced (band_beams makes it a
    grid key), family (n,) uint64 signature,
    obj (n,) receiver object index, xy (n,2) chart metres, scale (n,) chart
    area per world area, weight (n,3) the path's starting weight times its
    Fresnel, tint and absorption factors, throughput (n,) that product of
    factors (max channel)."""

    vertex: np.ndarray
    family: np.ndarray
    obj: np.ndarray
    xy: np.ndarray
    scale: np.ndarray
    weight: np.ndarray
    throughput: np.ndarray

    @staticmethod
    def concat(parts: list["Landings"]) -> "Landings":
        return Landings(*(np.concatenate([getattr(p, f) for p in parts])
                          for f in ("vertex", "family", "obj", "xy", "scale", "weight", "throughput")))


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
    floor = MIN_BRANCH_WEIGHT * max_channel(weight)
    specular = np.zeros(len(origins), dtype=bool)
    landed = []
    for _ in range(max_depth + 1):
        if len(vertex) == 0:
            break
        hits = accel.intersect(origins, dirs, medium)
        keep = hits.hit
        origins, dirs, weight, vertex, family, medium, floor, specular = take_rows(
            keep, origins, dirs, weight, vertex, family, medium, floor, specular)
        hits = hits.select(keep)
        points = hits.points
        inside = medium != MISS
        if inside.any():
            weight[inside] *= beer_lambert(np.take(materials.absorption, medium[inside], axis=0), hits.t[inside])

        land = specular & materials.receiver[hits.obj] & np.isin(hits.obj, list(maps))
        for index in np.unique(hits.obj[land]):
            sel = land & (hits.obj == index)
            local = hits.prim[sel] - accel.prim_offset[index]
            chart = maps[index].chart
            landed.append(Landings(vertex[sel], family[sel], hits.obj[sel],
                                   chart.coords(local, hits.u[sel], hits.v[sel], points[sel]),
                                   chart.area_scale(local), weight[sel],
                                   max_channel(weight[sel]) * MIN_BRANCH_WEIGHT / floor[sel]))

        bounce = materials.specular_surface[hits.obj]
        origins, dirs, weight, vertex, family, medium, floor = take_rows(
            bounce, origins, dirs, weight, vertex, family, medium, floor)
        hits = hits.select(bounce)
        points = hits.points
        if len(vertex) == 0:
            break
        surface = orient(accel, hits, dirs, points, materials, medium, band)
        tint = np.take(materials.color, hits.obj, axis=0)
        branches = []
        for event, mirror in ((0, True), (1, False)):
            new_dirs, crossed = scatter(surface, dirs, np.full(len(dirs), mirror))
            share = surface.fresnel if mirror else np.where(crossed, 1.0 - surface.fresnel, 0.0)
            new_weight = weight * tint * share[:, None]
            new_medium = np.where(crossed, np.where(surface.entering, hits.obj, MISS), medium)
            alive = (max_channel(new_weight) >= floor) & (mirror | materials.dielectric[hits.obj])
            branches.append(take_rows(alive, accel.offset(points, surface.facing, new_dirs), new_dirs, new_weight,
                                      vertex, _mix(family, hits.obj, event), new_medium, floor))
        origins, dirs, weight, vertex, family, medium, floor = (np.concatenate(parts) for parts in zip(*branches))
        specular = np.ones(len(vertex), dtype=bool)
    if not landed:
        empty = np.zeros(0)
        return Landings(empty.astype(np.int64), empty.astype(np.uint64), empty.astype(np.int64),
                        np.zeros((0, 2)), empty, np.zeros((0, 3)), empty)
    return Landings.concat(landed)


@dataclass
class BandBeams:
    """Beams and fallback photons from one band of a source's grid, per receiver.

    beams[obj] = (corners (m,3,2) chart metres, irradiance (m,3) W/m^2)
    photons[obj] = (xy (k,2), flux (k,3) W, scale (k,))
    flux_landed (3,) W carried by both; paths: the band's grid points (its
    last row is the next band's first, and counts there) and the `refined`
    points refinement added; rays cast"""

    beams: dict
    photons: dict
    paths: int
    refined: int
    rays: int
    flux_landed: np.ndarray


class _Lookup:
    """Landings indexed by grid vertex and by family group.

    Vertices are keys on a grid 2^levels times finer than the source's,
    key = row * width + col; a group is one (family, receiver), and a pair
    (element, group) is numbered element * stride + group."""

    def __init__(self, landings: Landings, keys: int):
        self.landings, self.keys = landings, keys
        self.group = row_ids(np.stack([landings.family, landings.obj.astype(np.uint64)], axis=1))
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


def _cell_corners(row: np.ndarray, col: np.ndarray, size: np.ndarray, width: int) -> np.ndarray:
    """(n,4) vertex keys of square cells: (r, c), (r+s, c), (r, c+s), (r+s, c+s)."""
    return np.stack([row * width + col, (row + size) * width + col,
                     row * width + col + size, (row + size) * width + col + size], axis=1)


def _diverging(lookup: _Lookup, corners: np.ndarray) -> np.ndarray:
    """(n,) bool: cells whose paths diverge. Some but not all of a cell's
    corners land in a family of throughput at least REFINE_THROUGHPUT (a
    silhouette, total internal reflection), or its two triangles land with
    opposite orientation (a fold of the caustic crosses it) or areas more
    than REFINE_RATIO apart."""
    element, group, landing, count = lookup.pairs(corners)
    split = np.zeros(len(corners), dtype=bool)
    split[element[(count < 4) & (lookup.landings.throughput[landing] >= REFINE_THROUGHPUT)]] = True
    cell, group = lookup.first_of_each(element[count == 4], group[count == 4])
    xy = [lookup.landings.xy[lookup.find(group, corners[cell, k])] for k in range(4)]
    a = signed_areas(np.stack([xy[0], xy[1], xy[3]], axis=1))
    b = signed_areas(np.stack([xy[0], xy[3], xy[2]], axis=1))
    small, large = np.minimum(np.abs(a), np.abs(b)), np.maximum(np.abs(a), np.abs(b))
    split[cell[(a * b <= 0.0) | (large > REFINE_RATIO * small)]] = True
    return split


def band_beams(source: BeamSource, first_row: int, end_row: int, accel: Accelerator, materials: Materials,
               maps: dict[int, IlluminationMap], max_depth: int, start_medium: int = MISS,
               levels: int = 0, band: int = 0) -> BandBeams:
    """Trace grid rows [first_row, end_row) of `source` in wavelength band
    `band`, whose paths start inside object `start_medium`, splitting cells
    where their paths diverge (`levels` times at most), and turn the landed
    paths into beams (coherent triangles) and fallback photons."""
    rays_before = accel.rays_cast
    scale = 1 << levels
    width = (source.grid - 1) * scale + 1
    keys = width * ((source.grid - 1) * scale + 1)

    def trace(vertex: np.ndarray) -> Landings:
        origins, dirs, weight = source.rays_at(np.stack([vertex // width, vertex % width], axis=1) / scale)
        weight *= materials.band_weights[band]
        landed = trace_paths(accel, materials, maps, origins, dirs, weight, max_depth, start_medium, band)
        landed.vertex = vertex[landed.vertex]
        return landed

    row, col = (a.ravel() * scale for a in np.meshgrid(np.arange(first_row, end_row - 1),
                                                         np.arange(source.grid - 1), indexing="ij"))
    size = np.full(len(row), scale)
    traced = np.unique(_cell_corners(row, col, size, width))
    on_grid = len(traced)
    owned = on_grid - (source.grid if end_row < source.grid else 0)
    landings = trace(traced)
    for _ in range(levels):
        split = _diverging(_Lookup(landings, keys), _cell_corners(row, col, size, width)) & (size > 1)
        if not split.any():
            break
        half = size[split] // 2
        r, c = row[split], col[split]
        row = np.concatenate([row[~split], r, r + half, r, r + half])
        col = np.concatenate([col[~split], c, c, c + half, c + half])
        size = np.concatenate([size[~split]] + [half] * 4)
        children = np.unique(_cell_corners(row, col, size, width))
        fresh = children[~np.isin(children, traced, assume_unique=True)]
        landings = Landings.concat([landings, trace(fresh)])
        traced = np.union1d(traced, fresh)

    triangles, area, centres = _crack_free_triangles(row, col, size, width, traced)
    landings = Landings.concat([landings, trace(centres)])
    measure = source.cell_measure * area / scale ** 2
    beams, photons, flux_landed = _beams_and_photons(_Lookup(landings, keys), triangles, measure, maps)
    refined = len(traced) + len(centres) - on_grid
    return BandBeams(beams, photons, owned + refined, refined, accel.rays_cast - rays_before, flux_landed)


def _crack_free_triangles(row: np.ndarray, col: np.ndarray, size: np.ndarray, width: int, traced: np.ndarray):
    """Triangles over the leaf cells that share every traced vertex with
    their neighbours, so that beams of a split cell and of its unsplit
    neighbour meet without cracks. A cell with no traced point inside its
    edges is two triangles; one with such points (a split neighbour's) is a
    fan from its centre through its boundary points in order.

    Returns (triangles (n,3) vertex keys, area (n,) in fine grid units
    squared, centres (k,) vertex keys of the fan centres, still to trace)."""
    count = 4 * size
    cell = np.repeat(np.arange(len(size)), count)
    j = np.arange(len(cell)) - np.repeat(np.cumsum(count) - count, count)
    s, side, along = size[cell], j // size[cell], j % size[cell]
    # the boundary walked counter-clockwise in (col, row): bottom, right, top, left
    r = row[cell] + np.choose(side, [0 * along, along, s, s - along])
    c = col[cell] + np.choose(side, [along, s, s - along, 0 * along])
    key = r * width + c
    pos = np.searchsorted(traced, key).clip(0, len(traced) - 1)
    kept = (along == 0) | (traced[pos] == key)
    kept_per_cell = np.bincount(cell[kept], minlength=len(size))
    fan = kept_per_cell > 4

    corners = _cell_corners(row[~fan], col[~fan], size[~fan], width)
    halves = 0.5 * size[~fan].astype(np.float64) ** 2
    on_fan = kept & fan[cell]
    ring_cell, ring_key = cell[on_fan], key[on_fan]
    new_cell = np.r_[True, ring_cell[1:] != ring_cell[:-1]][:len(ring_cell)]
    ring_next = np.roll(ring_key, -1)
    ring_next[np.roll(new_cell, -1)] = ring_key[new_cell]
    half = size // 2
    centre_key = (row + half) * width + col + half
    centres = centre_key[fan]
    tri_centre = centre_key[ring_cell]
    cr, cc = tri_centre // width, tri_centre % width
    ar, ac, br, bc = ring_key // width, ring_key % width, ring_next // width, ring_next % width
    fan_area = 0.5 * np.abs((ac - cc) * (br - cr) - (ar - cr) * (bc - cc)).astype(np.float64)
    triangles = np.concatenate([corners[:, [0, 1, 3]], corners[:, [0, 3, 2]],
                                np.stack([tri_centre, ring_key, ring_next], axis=1)])
    return triangles, np.concatenate([halves, halves, fan_area]), centres


def _beams_and_photons(lookup: _Lookup, triangles: np.ndarray, measure: np.ndarray,
                       maps: dict[int, IlluminationMap]):
    """Triangles `triangles (n,3)` (vertex keys) of emission measure
    `measure (n,)` (sr or m^2) whose three paths landed in one family become
    beams; the landed corners of the others carry a third of the triangle's
    flux each, as photons. Returns (beams, photons, flux_landed) as in
    BandBeams."""
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
    good = area > _MIN_AREA_FRACTION * chart_area[obj]
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = land.scale[idx]
        irradiance = flux * ((scale[:, 0] + scale[:, 1] + scale[:, 2]) / (3.0 * area))[:, None]

    # fallback: each landed corner of an incoherent or degenerate triangle
    # carries a third of that triangle's flux
    pair = element * lookup.stride + group
    degenerate = tri[~good] * lookup.stride + tri_group[~good]
    loose = (count < 3) | np.isin(pair, degenerate)
    share = np.bincount(landing[loose], weights=measure[element[loose]] / 3.0, minlength=len(land.vertex))
    holders = np.flatnonzero(share > 0)
    photon_flux = share[holders, None] * np.take(land.weight, holders, axis=0)

    beams, photons = {}, {}
    for o in np.unique(obj[good]):
        sel = good & (obj == o)
        beams[int(o)] = tuple(take_rows(sel, xy, irradiance))
    for o in np.unique(land.obj[holders]):
        sel = land.obj[holders] == o
        photons[int(o)] = (land.xy[holders[sel]], photon_flux[sel], land.scale[holders[sel]])
    return beams, photons, flux[good].sum(axis=0) + photon_flux.sum(axis=0)
