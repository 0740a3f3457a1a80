"""The sky, the world without its sun (world_sun.py), as suns for the pass
from the lamps, so that its light through the casters lands in the
illumination maps as a lamp's does: beams without noise, which a bake and
Live carry to the receivers' materials.

The lat-long image is cut into regions of equal light, the
median cut of Debevec ("A Median Cut Algorithm for Light Probe Sampling",
SIGGRAPH 2005 poster): the region that holds the most light is halved,
by its luminance times solid angle, across its longer side in angle, and
a region wider than a quarter turn across its longitude, so that none
spans half the sky. How many regions follows the sky's share of the lamp
rays (`region_count`): from MIN_REGIONS to SKY_REGIONS, each a grid of
about REGION_RAYS rays or more. Each region is one sun (`SkyRegion`), toward the
centroid c of its light, of strength

    S = sum_i L_i Omega_i (d_i . c)

the irradiance its pixels (radiance L_i, solid angle Omega_i, direction
d_i) bring to a plane facing c. A flat receiver lit through lossless
glass then gets n . c S = n . sum_i L_i Omega_i d_i, the region's own
irradiance, wherever the region's colour is even (the centroid weighs
luminance). Its `cell` is the flat quadrilateral of the region's corner
directions, grown to the region's solid angle (`region_cells`), over whose
image its beams spread (lamp_points.py, beam.py), so that the regions'
caustics, each sharp, sum to the sky's soft one; photons leave a cone of
the region's solid angle around c instead.

A world of one colour is a uniform image of UNIFORM_SIZE pixels. The
regions whose light meets something opaque before any caster (the sky
below a floor) are left out (`reaching`): the lamp rays go to those
that light the casters."""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..sampling.warps import concentric_disc, frames
from ..scene import Light, Scene, SunLight, World
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS
from .aims import Sphere, casters_and_bounds, disc_points, flux_toward, sun_widening, upstream_distance
from .environment import luminance, uv_to_directions
from .kept_worlds import per_world

# The regions the sky is cut into, at most and at the least: each one sun, and one beam grid.
SKY_REGIONS = 256
MIN_REGIONS = 64
# Lamp rays a wavelength band's grid of a region gets, about, where the sky's
# share of them calls for fewer regions than SKY_REGIONS.
REGION_RAYS = 32
# Rows and columns of the image that stands for a world of one colour.
UNIFORM_SIZE = (64, 128)
# A region is cut across its longitude while it spans more than this share of a turn.
MAX_TURN = 0.25
# Probe rays across each of a region's aims per side, along each of its
# centre's and corners' directions (`reaching`).
PROBES = 6


@dataclass
class SkyRegion(SunLight):
    """A sun that stands for a region of the sky: `angle` is the cone of
    the region's solid angle (photons), `cell (4,3)` the directions its
    corners' light travels along less `direction` (beams)."""

    cell: Optional[np.ndarray] = field(default=None, repr=False)


def lighting_casters(scene: Scene, sky: World, accel: Accelerator, lamps: list[Light],
                     rays: float) -> list[SkyRegion]:
    """The suns of the regions of `sky` whose light reaches the casters of
    `scene`, as many regions as its share of `rays` lamp rays a wavelength
    band, beside the `lamps`, calls for (`region_count`)."""
    targets, scene_sphere = casters_and_bounds(scene)
    casters = np.array([o.is_caster for o in scene.objects], dtype=bool)
    count = region_count(sky, lamps, targets, scene_sphere, rays)
    return reaching(sky_lamps(sky, count), accel, casters, targets, scene_sphere)


def region_count(sky: World, lamps: list[Light], targets: list[Sphere], scene_sphere: Sphere, rays: float) -> int:
    """How many regions `sky` is cut into beside `lamps`: the power of two
    that gives each region about REGION_RAYS of the sky's share of `rays`,
    by its flux toward the `targets` (a sun's is its strength times the
    area of its disc, aims.Aim.flux), between MIN_REGIONS and SKY_REGIONS.
    A dim world beside a lamp had SKY_REGIONS grids of 3 x 3 at a Live
    preview's rays, the least a grid has, which took as long to trace as
    the lamp's and, cut by the caster's edges, went to photons. A power of
    two keeps the count, and the cut kept for it, while a caster moves."""
    regions = sky_lamps(sky, SKY_REGIONS)
    widen = sun_widening(np.array([region.angle for region in regions]))
    sky_flux = math.pi * sum(s.radius ** 2 for s in targets) * float(
        np.array([region.strength for region in regions]) @ widen ** 2)
    if not sky_flux > 0.0:
        return SKY_REGIONS
    lamp_flux = sum(flux_toward(lamp, targets, scene_sphere) for lamp in lamps)
    wanted = rays * sky_flux / (sky_flux + lamp_flux) / REGION_RAYS
    return int(np.clip(2 ** math.floor(math.log2(max(wanted, 1.0))), MIN_REGIONS, SKY_REGIONS))


@per_world
def sky_lamps(sky: World, count: int) -> list[SkyRegion]:
    """The sky `sky` as at most `count` suns, one per region of its light
    (`median_cut`); none for a black sky. Kept while the same sky comes
    back with the same count (kept_worlds.py)."""
    image = sky.environment if sky.environment is not None else np.ones((*UNIFORM_SIZE, 3))
    rgb = image * sky.color
    h, w = rgb.shape[:2]
    theta = (np.arange(h) + 0.5) / h * math.pi
    phi = (0.5 - (np.arange(w) + 0.5) / w) * 2.0 * math.pi
    pixel_sr = (2.0 * math.pi / w) * (math.pi / h) * np.sin(theta)
    power = rgb * pixel_sr[:, None, None]
    weight = np.maximum(luminance(power), 0.0)
    if not weight.sum() > 0:
        return []
    boxes = median_cut(weight, count, theta)
    # each pixel's box, len(boxes) for those of none (they hold no light)
    label = np.full((h, w), len(boxes), dtype=np.int64)
    for k, (r0, r1, c0, c1) in enumerate(boxes):
        label[r0:r1, c0:c1] = k
    label = label.ravel()
    # the pixels' directions, separably: (sin t cos p, sin t sin p, cos t)
    axes = (np.sin(theta)[:, None] * np.cos(phi)[None, :], np.sin(theta)[:, None] * np.sin(phi)[None, :],
            np.broadcast_to(np.cos(theta)[:, None], (h, w)))
    bins = len(boxes) + 1
    toward = np.stack([np.bincount(label, (weight * a).ravel(), bins) for a in axes], axis=1)
    solid = np.bincount(label, np.broadcast_to(pixel_sr[:, None], (h, w)).ravel(), bins)
    lit = np.linalg.norm(toward, axis=1) > 0
    centre = toward / np.maximum(np.linalg.norm(toward, axis=1), 1e-300)[:, None]
    facing = sum(np.take(centre[:, k], label).reshape(h, w) * axes[k] for k in range(3))
    strength = np.stack([np.bincount(label, (power[..., c] * facing).ravel(), bins) for c in range(3)], axis=1)
    kept = np.flatnonzero(lit & (strength.max(axis=1) > 0))
    r0, r1, c0, c1 = np.array(boxes, dtype=np.float64).reshape(-1, 4)[kept].T
    uv = np.stack([np.stack([c0, r0], 1), np.stack([c1, r0], 1), np.stack([c1, r1], 1), np.stack([c0, r1], 1)], 1)
    corners = uv_to_directions((uv / np.array([w, h])).reshape(-1, 2)).reshape(-1, 4, 3)
    cells = region_cells(centre[kept], corners, solid[kept])
    peaks = strength[kept].max(axis=1)
    return [SkyRegion(-centre[k], float(peak), strength[k] / peak, name="the sky",
                      angle=2.0 * math.acos(max(-1.0, 1.0 - solid[k] / (2.0 * math.pi))), of_world=True, cell=cell)
            for k, peak, cell in zip(kept, peaks, cells)]


def region_cells(centres: np.ndarray, corners: np.ndarray, solid_angles: np.ndarray) -> np.ndarray:
    """(k,4,3) regions' cells: the directions their corners' light travels
    along less their centre's, c - corners for unit `centres` c (k,3) and
    `corners (k,4,3)`, grown about c until the flat quadrilateral they
    span has the region's solid angle, `solid_angles (k,)`: the chords
    between the corners of a region at the pole cut off a third of it, and
    its light would gather."""
    cells = centres[:, None, :] - corners
    a, b, c, d = (corners[:, i] for i in range(4))
    flat = 0.5 * (np.linalg.norm(np.cross(b - a, c - a), axis=1) + np.linalg.norm(np.cross(c - a, d - a), axis=1))
    grow = np.sqrt(np.divide(solid_angles, flat, out=np.ones_like(flat), where=flat > 0))
    return cells * grow[:, None, None]


def median_cut(weight: np.ndarray, count: int, theta: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Boxes (row0, row1, col0, col1), half-open, that tile the lat-long
    `weight (h,w)` (rows at polar angles `theta (h,)`): the heaviest box is
    cut in two of equal weight, across its longer side in angle (its width
    at its widest row), or across its columns while it spans more than
    MAX_TURN of a turn, until there are `count` or none can be cut, and
    then each box wider than MAX_TURN still is; each box shrunk to the rows
    and columns that hold its weight. `weight` holds some."""
    h, w = weight.shape
    table = np.zeros((h + 1, w + 1))
    table[1:, 1:] = weight.cumsum(axis=0).cumsum(axis=1)

    def total(r0, r1, c0, c1) -> float:
        return float(table[r1, c1] - table[r0, c1] - table[r1, c0] + table[r0, c0])

    def tight(r0, r1, c0, c1) -> tuple[int, int, int, int]:
        """The box shrunk to its rows and columns that hold light."""
        rows = np.flatnonzero(np.diff(table[r0:r1 + 1, c1] - table[r0:r1 + 1, c0]) > 0)
        cols = np.flatnonzero(np.diff(table[r1, c0:c1 + 1] - table[r0, c0:c1 + 1]) > 0)
        return r0 + rows[0], r0 + rows[-1] + 1, c0 + cols[0], c0 + cols[-1] + 1

    def wide(box: tuple[int, int, int, int]) -> bool:
        return box[3] - box[2] > MAX_TURN * w

    heap = [(-total(0, h, 0, w), 0, tight(0, h, 0, w))]
    done, order = [], 1
    while heap:
        if len(heap) + len(done) < count:
            _, _, (r0, r1, c0, c1) = heapq.heappop(heap)
        else:
            spans = [k for k, (_, _, box) in enumerate(heap) if wide(box)]
            if not spans:
                break
            _, _, (r0, r1, c0, c1) = heap.pop(spans[0])
            heapq.heapify(heap)
        turn = (c1 - c0) / w
        width = turn * 2.0 * math.pi * float(np.sin(theta[r0:r1]).max())
        across_columns = c1 - c0 > 1 and (turn > MAX_TURN or width >= (r1 - r0) / h * math.pi or r1 - r0 == 1)
        if across_columns:
            sums = table[r1, c0 + 1:c1] - table[r0, c0 + 1:c1] - table[r1, c0] + table[r0, c0]
        elif r1 - r0 > 1:
            sums = table[r0 + 1:r1, c1] - table[r0 + 1:r1, c0] - table[r0, c1] + table[r0, c0]
        else:
            done.append((r0, r1, c0, c1))
            continue
        cut = 1 + int(np.argmin(np.abs(sums - 0.5 * total(r0, r1, c0, c1))))
        halves = ([(r0, r1, c0, c0 + cut), (r0, r1, c0 + cut, c1)] if across_columns
                  else [(r0, r0 + cut, c0, c1), (r0 + cut, r1, c0, c1)])
        for box in halves:
            heapq.heappush(heap, (-total(*box), order, tight(*box)))
            order += 1
    return done + [box for _, _, box in heap]


def reaching(regions: list[SkyRegion], accel: Accelerator, casters: np.ndarray, targets: list[Sphere],
             scene_sphere: Sphere) -> list[SkyRegion]:
    """The `regions` whose light reaches a caster (`casters (m,)` bool by
    object) before anything else, as PROBES x PROBES rays across each of
    their aims (aims.aims: a disc over each target, widened by the region's
    angle) along their centre's and each corner's direction find: a region
    none of whose probes meets a caster first is left out. All regions'
    probes are one batch."""
    if not regions or not targets:
        return []
    disc = concentric_disc((np.stack(np.meshgrid(np.arange(PROBES), np.arange(PROBES)), axis=-1).reshape(-1, 2)
                            + 0.5) / PROBES)
    axis = np.array([region.direction for region in regions])
    tangent, bitangent = frames(axis)
    toward = axis[:, None, :] + np.concatenate([np.zeros((len(regions), 1, 3)),
                                                np.array([region.cell for region in regions])], axis=1)
    toward /= np.linalg.norm(toward, axis=2)[:, :, None]
    widen = sun_widening(np.array([region.angle for region in regions]))
    start = upstream_distance(scene_sphere)
    origins = []
    for sphere in targets:
        # (k, probes, 3): Aim.crossing of each region's disc over the sphere
        crossing = disc_points(sphere.center, (sphere.radius * widen)[:, None, None], tangent[:, None, :],
                               bitangent[:, None, :], disc[None])
        origins.append(crossing[:, None, :, :] - start * toward[:, :, None, :])
    shape = (len(regions), toward.shape[1], len(disc), 3)
    dirs = np.broadcast_to(toward[:, :, None, :], shape)
    hits = accel.intersect(np.concatenate([o.reshape(-1, 3) for o in origins]),
                           np.concatenate([dirs.reshape(-1, 3)] * len(targets)))
    met = ((hits.obj != MISS) & np.take(casters, np.maximum(hits.obj, 0))).reshape(len(targets), len(regions), -1)
    return [region for region, lit in zip(regions, met.any(axis=(0, 2))) if lit]
