"""A lamp with a size as lamps of size 0, for beam mode, whose grids need
rays from one point: `m` x `m` points of a stratified grid over the lamp
(over its disc facing the casters, its sphere's near side, its area, or a
sun's disc of directions), each with 1/m^2 of its light. Their caustics,
each sharp, sum to the soft one; `m` grows with the penumbra the lamp's size
throws onto the receivers, so that neighbouring points' caustics land less
than BEAM_SHIFT map cells apart, up to MAX_PER_AXIS, and while each point's
grid keeps MIN_GRID_POINTS of the lamp's rays.

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

import numpy as np

from ..sampling.sequences import r2_sequence
from ..sampling.warps import cone_directions
from ..scene import AreaLight, Light, SunLight
from .aims import Sphere, aims, emitting_points, reach

# Map cells between the caustics of neighbouring points of a lamp.
BEAM_SHIFT = 2.0
# Points per side of a lamp's grid, at most (MAX_PER_AXIS^2 beam grids).
MAX_PER_AXIS = 16
# Lamp rays each point's beam grid keeps, at least.
MIN_GRID_POINTS = 200


def grid_points(per_axis: int) -> np.ndarray:
    """(m^2, 2) centres of an m x m grid of cells over the unit square."""
    ticks = (np.arange(per_axis) + 0.5) / per_axis
    return np.stack(np.meshgrid(ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 2)


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


def point_lamps(light: Light, per_axis: int, facing: np.ndarray) -> list[Light]:
    """`per_axis`^2 lamps of size 0 that stand for `light`; a point or spot
    lamp's disc faces `facing (3,)`, the direction of its casters."""
    grid = grid_points(per_axis)
    share = 1.0 / len(grid)
    if isinstance(light, SunLight):
        if light.angle <= 0.0:
            return [light]
        half = 0.5 * light.angle
        dirs = cone_directions(light.direction, math.cos(half), grid)
        # each carries L x the disc's solid angle / m^2, L = S / (pi sin^2 h)
        strength = light.strength * 2.0 * (1.0 - math.cos(half)) / math.sin(half) ** 2 * share
        return [replace(light, direction=d, strength=strength, angle=0.0) for d in dirs]
    if reach(light) <= 0.0:
        return [light]
    if isinstance(light, AreaLight):
        points = emitting_points(light, np.zeros((len(grid), 3)), grid)
        zero = np.zeros(3)
        return [replace(light, center=p, axis_x=zero, axis_y=zero, power=light.power * share) for p in points]
    points = emitting_points(light, np.tile(facing, (len(grid), 1)), grid)
    return [replace(light, position=p, radius=0.0, power=light.power * share) for p in points]


def grid_phases(count: int) -> np.ndarray:
    """(count, 2) in [0,1)^2, the phases of the beam grids of a lamp's
    `count` points (beam_sources.BeamSource): the R2 sequence, whose points
    spread evenly over the square in any run of them; 0 for a lamp of one
    point, whose grid stays as it was."""
    if count == 1:
        return np.zeros((1, 2))
    return r2_sequence(np.arange(count), np.zeros(2))


def beam_lamps(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, receivers, cell: float,
               lamp_rays: int) -> tuple[list[Light], np.ndarray]:
    """Every lamp as lamps of size 0 for beam mode, with points enough for
    map cells of `cell` m on receivers within `receivers` (lo, hi), and no
    more than each lamp's share of `lamp_rays` (by its flux toward the
    targets) can give grids of MIN_GRID_POINTS; with the phase (2,) of each
    one's grid (`grid_phases`)."""
    flux = np.array([sum(aim.flux(1.0) for aim in aims(light, targets, scene_sphere)) for light in lights])
    budgets = lamp_rays * flux / flux.sum() if flux.sum() > 0 else np.zeros(len(lights))
    out, phases = [], []
    for light, budget in zip(lights, budgets):
        if isinstance(light, SunLight) or not targets:
            facing = getattr(light, "direction", np.array([0.0, 0.0, -1.0]))
        else:
            toward = sum(sphere.center - light.position for sphere in targets)
            norm = float(np.linalg.norm(toward))
            facing = toward / norm if norm > 0 else np.array([0.0, 0.0, -1.0])
        points = point_lamps(light, points_per_axis(light, targets, receivers, cell, budget), facing)
        out += points
        phases.append(grid_phases(len(points)))
    return out, np.concatenate(phases) if phases else np.zeros((0, 2))
