"""A lamp with a size as lamps of size 0, for beam mode, whose grids need
rays from one point: the centroids of `m` x `m` cells of the lamp (over its
disc facing the casters, its sphere's near side, its area, or a sun's disc
of directions), each with its cell's share of the light (`lamp_cells`).
Each point's beams spread over the image of its cell (passes/beam.py), so
that their caustics, each sharp, sum to the soft one, without the lattice
of dots that the points' foci would make; `m` grows with the penumbra the
lamp's size throws onto the receivers, so that neighbouring points'
caustics land less than BEAM_SHIFT map cells apart, up to MAX_PER_AXIS,
and while each point's grid keeps MIN_GRID_POINTS of the lamp's rays.

Measured on the ball lens under a sphere lamp of radius 0.5 m against
Cycles (benchmarks/sized_lamps.py): the caustic's error falls as 1/m^2
with the points (15%, 3.7% and 2.2% for m = 4, 8 and 16 at 160,000 lamp
rays), and rises steeply once a point's grid has under about 200 rays
(m = 12 at 10,000 lamp rays: 12.5%, against 4.8% for m = 8).

Each point's grid gets a phase of its own (`grid_phases`): a grid of 200
rays has cells wider than the light of a glass's rim (its grazing
reflections come from the outer few percent of the ball's radius), and
points that all laid the same grid over the caster missed it together."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np

from ..sampling.sequences import r2_sequence
from ..sampling.warps import cone_directions
from ..scene import AreaLight, Light, MeshLight, SunLight
from ..util.vectors import DIVISION_FLOOR
from . import mesh_lights
from .aims import Sphere, aims, emitting_points, flux_toward, reach
from .sky_lamps import SkyRegion

# Map cells between the caustics of neighbouring points of a lamp.
BEAM_SHIFT = 2.0
# Points per side of a lamp's grid, at most (MAX_PER_AXIS^2 beam grids).
MAX_PER_AXIS = 16
# Lamp rays each point's beam grid keeps, at least.
MIN_GRID_POINTS = 200


def penumbra(light: Light, targets: list[Sphere], receivers: tuple[np.ndarray, np.ndarray]) -> float:
    """The widest blur, m, that the lamp's size throws from a target onto
    the receivers' bounding box `(lo (3,), hi (3,))`: the lamp's angular size
    seen from the target times the target's distance to the box."""
    lo, hi = receivers
    widest = 0.0
    for sphere in targets:
        to_box = float(np.linalg.norm(np.clip(sphere.center, lo, hi) - sphere.center)) + sphere.radius
        if isinstance(light, SunLight):
            angle = light.angle
        else:
            distance = float(np.linalg.norm(sphere.center - light.position))
            angle = 2.0 * math.atan(reach(light) / max(distance - sphere.radius, sphere.radius))
        widest = max(widest, angle * to_box)
    return widest


def points_per_axis(light: Light, targets: list[Sphere], receivers, cell: float, lamp_rays: float) -> int:
    """m for `light`, whose beam grids share `lamp_rays`: 1 for a lamp of size 0."""
    blur = penumbra(light, targets, receivers)
    budget = math.isqrt(max(int(lamp_rays // MIN_GRID_POINTS), 1))
    return int(min(MAX_PER_AXIS, budget, max(1, math.ceil(blur / (BEAM_SHIFT * cell)))))


def point_lamps(light: Light, per_axis: int, facing: np.ndarray) -> tuple[list[Light], list[Optional[np.ndarray]]]:
    """(lamps, cells): `per_axis`^2 lamps of size 0 that stand for `light`,
    at its cells' centroids with their shares of its light, and each one's
    cell's corners less its point (4,3) (`lamp_cells`); for m = 1 one lamp
    at its centre; a point or spot lamp's disc faces `facing (3,)`, the
    direction of its casters. A lamp of size 0 is itself, of no cell; a
    region of the sky (sky_lamps.py) is its one point and cell, whatever
    `per_axis`."""
    if isinstance(light, SkyRegion):
        return [replace(light, angle=0.0)], [light.cell]
    if not has_size(light):
        return [light], [None]
    cells = lamp_cells(light, per_axis, facing)
    if cells is None:
        points, corners, shares = _lamp_at(light, np.full((1, 2), 0.5), facing), [None], [1.0]
    else:
        points, corners, shares = cells[0], list(cells[1]), cells[2]
    if isinstance(light, SunLight):
        half = 0.5 * light.angle
        # each carries L x the disc's solid angle x its share, L = S / (pi sin^2 h)
        strength = light.strength * 2.0 * (1.0 - math.cos(half)) / math.sin(half) ** 2
        return [replace(light, direction=d, strength=strength * share, angle=0.0)
                for d, share in zip(points, shares)], corners
    if isinstance(light, AreaLight):
        zero = np.zeros(3)
        return [replace(light, center=p, axis_x=zero, axis_y=zero, power=light.power * share)
                for p, share in zip(points, shares)], corners
    return [replace(light, position=p, radius=0.0, power=light.power * share)
            for p, share in zip(points, shares)], corners


def has_size(light: Light) -> bool:
    """Whether the lamp has a size: a radius, an area, a sun's angle."""
    return light.angle > 0.0 if isinstance(light, SunLight) else reach(light) > 0.0


def _lamp_at(light: Light, uv: np.ndarray, facing: np.ndarray) -> np.ndarray:
    """(n,3) the points `uv (n,2)` of the unit square on a lamp with a size
    (a point or spot lamp's on its disc facing `facing (3,)`), or a sun's
    directions."""
    if isinstance(light, SunLight):
        return cone_directions(light.direction, math.cos(0.5 * light.angle), uv)
    return emitting_points(light, np.tile(facing, (len(uv), 1)), uv)


def lamp_cells(light: Light, per_axis: int, facing: np.ndarray):
    """The m x m cells (m = `per_axis`) of a lamp with a size: (points
    (m^2,3), corners (m^2,4,3), shares (m^2,)), or None for a lamp of size
    0 or for m = 1 (a penumbra under BEAM_SHIFT map cells, which one point,
    its centre, stands for). A cell is the flat quadrilateral of the lamp's
    map of the unit square at its grid's corners (u, v), (u', v), (u', v'), (u, v') (an area lamp's
    surface, a disc facing `facing (3,)` for a point or spot lamp, or a
    sun's unit directions); its point is its centroid (a sun's, normalised),
    `corners` its corners less the point, and its share of the lamp's light
    its area over all the cells' (the maps are equal-area, but the
    concentric map bends along the square's diagonals and about its centre,
    and its flat cells tile a polygon inscribed in the disc). Each point's
    beams spread over their landing's image of its cell (passes/beam.py),
    and the flat cells' images tile as the cells do."""
    if not has_size(light) or per_axis == 1:
        return None
    ticks = np.arange(per_axis + 1) / per_axis
    lattice = np.stack(np.meshgrid(ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 2)
    at = _lamp_at(light, lattice, facing).reshape(per_axis + 1, per_axis + 1, 3)
    corners = np.stack([at[:-1, :-1], at[1:, :-1], at[1:, 1:], at[:-1, 1:]], axis=2).reshape(-1, 4, 3)
    # the quadrilateral as triangles (0, 1, 2) and (0, 2, 3): areas and centroids
    halves = [np.linalg.norm(np.cross(corners[:, a] - corners[:, 0], corners[:, b] - corners[:, 0]), axis=1) / 2.0
              for a, b in ((1, 2), (2, 3))]
    area = halves[0] + halves[1]
    points = ((halves[0][:, None] * (corners[:, 0] + corners[:, 1] + corners[:, 2])
               + halves[1][:, None] * (corners[:, 0] + corners[:, 2] + corners[:, 3]))
              / (3.0 * np.maximum(area, DIVISION_FLOOR)[:, None]))
    if isinstance(light, SunLight):
        points /= np.linalg.norm(points, axis=1)[:, None]
    return points, corners - points[:, None, :], area / area.sum()


def grid_phases(count: int) -> np.ndarray:
    """(count, 2) in [0,1)^2, the phases of the beam grids of a lamp's
    `count` points (beam_sources.BeamSource): the R2 sequence, whose points
    spread evenly over the square in any run of them; 0 for a lamp of one
    point, whose grid stays as it was."""
    if count == 1:
        return np.zeros((1, 2))
    return r2_sequence(np.arange(count), np.zeros(2))


def beam_lamps(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, receivers, cell: float,
               lamp_rays: int) -> tuple[list[Light], np.ndarray, list[Optional[np.ndarray]]]:
    """Every lamp as lamps of size 0 for beam mode, with points enough for
    map cells of `cell` m on receivers within `receivers` (lo, hi), and no
    more than each lamp's share of `lamp_rays` (by its flux toward the
    targets) can give grids of MIN_GRID_POINTS; with the phase (2,) of each
    one's grid (`grid_phases`) and the corners (4,3) of the lamp's cell each
    one stands for, less the point (`lamp_cells`; None for a lamp of size 0).
    A mesh light's points are its pieces' cells, on each side whose light
    leaves it (mesh_lights.point_lamps)."""
    flux = np.array([flux_toward(light, targets, scene_sphere) for light in lights])
    budgets = lamp_rays * flux / flux.sum() if flux.sum() > 0 else np.zeros(len(lights))
    out, phases, cells = [], [], []
    for light, budget in zip(lights, budgets):
        if isinstance(light, MeshLight):
            per_axis = points_per_axis(light, targets, receivers, cell, budget)
            points, corners = mesh_lights.point_lamps(light, per_axis * per_axis, mesh_lights.lift_off(light))
            out += points
            cells += corners
            phases.append(grid_phases(len(points)))
            continue
        if isinstance(light, SunLight) or not targets:
            facing = getattr(light, "direction", np.array([0.0, 0.0, -1.0]))
        else:
            toward = sum(sphere.center - light.position for sphere in targets)
            norm = float(np.linalg.norm(toward))
            facing = toward / norm if norm > 0 else np.array([0.0, 0.0, -1.0])
        points, corners = point_lamps(light, points_per_axis(light, targets, receivers, cell, budget), facing)
        out += points
        cells += corners
        phases.append(grid_phases(len(points)))
    phases = np.concatenate(phases) if phases else np.zeros((0, 2))
    # the sky's regions are points of one lamp
    sky = [k for k, lamp in enumerate(out) if isinstance(lamp, SkyRegion)]
    if sky:
        phases[sky] = grid_phases(len(sky))
    return out, phases, cells
