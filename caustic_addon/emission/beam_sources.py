"""Where beam mode's lamp rays start: a G x G grid laid over each of a
lamp's aims (aims.py) through Shirley and Chiu's concentric map of the
square onto the disc, which keeps grid cells of equal measure."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..sampling.warps import concentric_disc
from ..scene import Light
from .aims import Aim, Sphere, aims, balance_density, meets_any, overlapping, share


@dataclass
class BeamSource:
    """A grid of `grid` x `grid` points over one aim of a lamp, the disc
    turned by `roll` radians about the aim's axis. `overlap` lists every
    aim of the same lamp that may hold its rays (aims.overlapping) with its
    grid's sample density (points per unit measure), to share the rays
    that several aims hold. `cell (4,3)`: the
    corners, less the lamp's position (a sun's: its direction), of the cell
    of a lamp with a size that the lamp (one of its points,
    lamp_points.lamp_cells) stands for (None: a lamp of size 0). A ray
    that meets one of the spheres `rough` and none of `smooth`
    (aims.meets_any) carries nothing: photons carry that light
    (passes.beam.photon_lamps)."""

    aim: Aim
    energy: float
    grid: int
    overlap: list[tuple[Aim, float]] = field(default_factory=list)
    roll: float = 0.0
    cell: Optional[np.ndarray] = None
    rough: tuple = ()
    smooth: tuple = ()

    @property
    def light(self) -> Light:
        return self.aim.light

    @property
    def cell_measure(self) -> float:
        """Solid angle (sr) or area (m^2) of one grid cell."""
        return self.aim.measure / (self.grid - 1) ** 2

    def rays_at(self, rc: np.ndarray):
        """Rays at continuous grid positions `rc (n,2)` (row, col) in [0,
        grid - 1]: (origins (n,3), dirs (n,3), weight (n,3) intensity (W/sr)
        or irradiance (W/m^2) times the ray's share of its cell, 1 where no
        other aim holds it)."""
        disc = concentric_disc(rc / (self.grid - 1))
        if self.roll:
            c, s = math.cos(self.roll), math.sin(self.roll)
            disc = disc @ np.array([[c, s], [-s, c]])
        origins, dirs = self.aim.rays(disc)
        others, density = zip(*self.overlap)
        weight = self.aim.emitted(self.energy, dirs)
        weight *= ((1.0 / self.cell_measure) / balance_density(others, np.array(density), origins, dirs))[:, None]
        if self.rough:
            weight[meets_any(list(self.rough), origins, dirs) & ~meets_any(list(self.smooth), origins, dirs)] = 0.0
        return origins, dirs, weight

    def cell_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """(axes (2,3), corners (4,2)): two orthonormal axes in the plane of
        the lamp's `cell` (along its first edges), and its corners in them;
        zeros for a lamp of size 0."""
        if self.cell is None:
            return np.zeros((2, 3)), np.zeros((4, 2))
        c = self.cell
        along = c[1] - c[0] + c[2] - c[3]
        across = c[3] - c[0] + c[2] - c[1]
        t = along / np.linalg.norm(along)
        b = across - t * (t @ across)
        axes = np.stack([t, b / np.linalg.norm(b)])
        return axes, c @ axes.T

    def differentials(self, dirs: np.ndarray, first_hit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(d_origins (n,2,3), d_dirs (n,2,3)): how rays along `dirs (n,3)`
        change per metre (a sun's: per radian) along each of the lamp's
        `cell_frame` axes (ray differentials, Igehy 1999;
        passes/differentials.py carries them through the bounces). From a
        point of a lamp moved by e, the ray through the point at the
        target's distance s along it turns by -(e - d (d.e)) / s. A sun's
        direction turns by e, the ray pivoting where it first meets the
        scene, `first_hit (n,)` m along it (where it meets nothing, at the
        aim's disc): every direction of the sun's cell lights that point
        of a caster alike, while a pivot on the disc, which crosses a
        large flat caster far from where the ray meets it, would move a
        landing by that whole lever arm. Zero for a lamp of size 0."""
        n = len(dirs)
        if self.cell is None:
            return np.zeros((n, 2, 3)), np.zeros((n, 2, 3))
        edges = np.broadcast_to(self.cell_frame()[0], (n, 2, 3))
        across = edges - dirs[:, None, :] * np.einsum("nkc,nc->nk", edges, dirs)[:, :, None]
        if self.aim.is_disc:
            met = np.isfinite(first_hit) & (first_hit > 0)
            pivot = np.where(met, first_hit, self.aim.start_distance)
            return -pivot[:, None, None] * across, across
        return edges.copy(), -across / self.aim.target_distance


def disc_shares(rc: np.ndarray, grid: int) -> np.ndarray:
    """(k,) the share of the unit disc that the flat triangle of the
    concentric_disc points of grid positions `rc (k,3,2)` (row, col) on a
    grid of `grid` x `grid` points covers: times an aim's measure, the
    measure of the grid triangle's beam. The map is equal-area, but it
    bends along the square's diagonals and about its centre: the cell about
    the centre of a grid of an even number of points has its corners on a
    circle, and the square they span covers 2/pi of its disc, so with the
    cell's measure its beams are pi/2 times too bright (a patch one cell
    wide at the aim's centre, a sun's through a flat pane). The flat
    triangles tile the disc but for slivers at its rim."""
    disc = concentric_disc(rc.reshape(-1, 2) / (grid - 1)).reshape(-1, 3, 2)
    (ax, ay), (bx, by) = (disc[:, 1] - disc[:, 0]).T, (disc[:, 2] - disc[:, 0]).T
    return np.abs(ax * by - ay * bx) / (2.0 * math.pi)


def beam_sources(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, energy: float,
                 lamp_rays: int, phases: np.ndarray, cells: list[Optional[np.ndarray]]) -> list[BeamSource]:
    """Grids over every lamp's aims, about `lamp_rays` grid points in all,
    shared in proportion to the flux each aim receives; none over an aim
    that receives none (a lamp of power 0). `cells` (by lamp): the corners
    (4,3) of the cell of a lamp with a size that each lamp stands for, less
    its point (lamp_points.point_lamps), or None.

    `phases (lights, 2)` in [0,1)^2 shift each lamp's grids
    against its casters: the aim widened so that its rings of grid points
    move out by phase[0] of the step between rings at the edge (which puts
    the outer ring's neighbour, the last one on the caster, anywhere
    across the step), and the grid turned by phase[1] of a turn (which
    moves the concentric map's bent diagonals). Neighbouring points of a
    lamp with a size, whose grids would land alike, then sample what lies
    between one grid's points (the light of a glass's rim, say) between
    them."""
    every = [(aim, phase, cell) for light, phase, cell in zip(lights, phases, cells)
             for aim in aims(light, targets, scene_sphere) if aim.flux(energy) > 0]
    if not every:
        return []
    points = share(lamp_rays, [aim.flux(energy) for aim, _, _ in every], minimum=9)
    sources = []
    for (aim, phase, cell), n in zip(every, points):
        grid = int(round(math.sqrt(n)))
        # rings of the concentric map 2 / (grid - 1) apart in rho
        sources.append(BeamSource(aim.widened(1.0 + 2.0 * phase[0] / (grid - 1)), energy, grid,
                                  roll=2.0 * math.pi * phase[1], cell=cell))
    by_light: dict[int, list[BeamSource]] = {}
    for source in sources:
        by_light.setdefault(id(source.aim.light), []).append(source)
    for same in by_light.values():
        for source, near in zip(same, overlapping([other.aim for other in same])):
            source.overlap = [(same[j].aim, 1.0 / same[j].cell_measure) for j in near]
    return sources
