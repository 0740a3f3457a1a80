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
from .aims import Aim, Sphere, aims, balance_density, disc_points, meets_any, overlapping, share


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

    def balance(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) what the weight of the source's rays `origins, dirs (n,3)`
        is multiplied by: 1 / (cell measure x the summed sample density of
        the aims that hold each ray), 1 where no other aim holds it; 0 for
        a ray that meets a `rough` sphere and no `smooth` one."""
        others, density = zip(*self.overlap)
        factor = (1.0 / self.cell_measure) / balance_density(others, np.array(density), origins, dirs)
        if self.rough:
            factor[meets_any(list(self.rough), origins, dirs) & ~meets_any(list(self.smooth), origins, dirs)] = 0.0
        return factor


class SourceBatch:
    """Grids of one size traced as one batch, `sources (k,)`: the rays of
    the rows of all of them at once, from arrays of the sources' aims,
    where a pass per source would cost its numpy calls again for each (a
    sky is up to 256 suns, each traced once per wavelength band). A sun's
    disc is done in the arrays; a cone's rays, and the balance of rays that
    several aims or a rough caster hold, source by source, for the rows of
    the sources that have them."""

    def __init__(self, sources: list[BeamSource]):
        self.sources, self.grid = sources, sources[0].grid
        aims = [source.aim for source in sources]
        self.disc = np.array([aim.is_disc for aim in aims], dtype=bool)
        self.axis = np.array([aim.axis for aim in aims]).reshape(-1, 3)
        self.center = np.array([aim.center if aim.is_disc else np.zeros(3) for aim in aims]).reshape(-1, 3)
        self.radius = np.array([aim.radius for aim in aims])
        self.tangent = np.array([aim.tangent for aim in aims]).reshape(-1, 3)
        self.bitangent = np.array([aim.bitangent for aim in aims]).reshape(-1, 3)
        self.start = np.array([aim.start_distance for aim in aims])
        # a disc's divisor is never read (np.where)
        self.target = np.array([1.0 if aim.is_disc else aim.target_distance for aim in aims])
        self.emitted = np.array([source.aim.emitted(source.energy, source.aim.axis[None])[0] if source.aim.is_disc
                                 else np.zeros(3) for source in sources]).reshape(-1, 3)
        roll = np.array([source.roll for source in sources])
        self.rolled, self.cos_roll, self.sin_roll = roll != 0.0, np.cos(roll), np.sin(roll)
        self.balanced = np.flatnonzero([len(source.overlap) > 1 or bool(source.rough) for source in sources])
        self.spreading = any(source.cell is not None for source in sources)
        self.cell_axes, self.cell_corners = cell_frames(np.array([np.zeros((4, 3)) if source.cell is None
                                                                  else source.cell for source in sources]))

    def rays(self, which: np.ndarray, rc: np.ndarray):
        """Rays of sources `which (n,)` (ascending) at continuous grid
        positions `rc (n,2)` (row, col) in [0, grid - 1]: (origins (n,3),
        dirs (n,3), weight (n,3) intensity (W/sr) or irradiance (W/m^2)
        times the ray's share of its cell, 1 where no other aim holds it).
        The grid's point of the unit disc, turned by its source's roll, is
        mapped through the aim (Aim.rays): a disc's ray crosses it at
        `disc_points` along the sun's direction, from start_distance
        upstream."""
        disc = concentric_disc(rc / (self.grid - 1))
        turned = np.flatnonzero(self.rolled[which])
        if len(turned):
            c, s = self.cos_roll[which[turned]], self.sin_roll[which[turned]]
            x, y = disc[turned, 0].copy(), disc[turned, 1].copy()
            disc[turned, 0], disc[turned, 1] = x * c - y * s, x * s + y * c
        origins, dirs, weight = np.empty((len(which), 3)), np.empty((len(which), 3)), np.empty((len(which), 3))
        suns = np.flatnonzero(self.disc[which])
        k = which[suns]
        dirs[suns] = self.axis[k]
        origins[suns] = (disc_points(self.center[k], self.radius[k, None], self.tangent[k], self.bitangent[k],
                                     disc[suns]) - self.start[k, None] * dirs[suns])
        weight[suns] = self.emitted[k]
        first = np.searchsorted(which, np.arange(len(self.sources) + 1))
        for k in np.unique(which[~self.disc[which]]):
            rows = slice(first[k], first[k + 1])
            aim = self.sources[k].aim
            origins[rows], dirs[rows] = aim.rays(disc[rows])
            weight[rows] = aim.emitted(self.sources[k].energy, dirs[rows])
        for k in self.balanced:
            rows = slice(first[k], first[k + 1])
            weight[rows] *= self.sources[k].balance(origins[rows], dirs[rows])[:, None]
        return origins, dirs, weight

    def differentials(self, which: np.ndarray, dirs: np.ndarray, first_hit: np.ndarray):
        """(d_origins (n,2,3), d_dirs (n,2,3)): how the rays of sources
        `which (n,)` along `dirs (n,3)` change per metre (a sun's: per
        radian) along each of their lamp's `cell_frames` axes (ray
        differentials, Igehy 1999; passes/differentials.py carries them
        through the bounces). From a point of a lamp moved by e, the ray
        through the point at the target's distance s along it turns by
        -(e - d (d.e)) / s. A sun's direction turns by e, the ray pivoting
        where it first meets the scene, `first_hit (n,)` m along it (where it
        meets nothing, at the aim's disc): every direction of the sun's cell
        lights that point of a caster alike, while a pivot on the disc,
        which crosses a large flat caster far from where the ray meets it,
        would move a landing by that whole lever arm. Zero for a lamp of
        size 0 (its axes are)."""
        edges = self.cell_axes[which]
        across = edges - dirs[:, None, :] * np.einsum("nkc,nc->nk", edges, dirs)[:, :, None]
        sun = self.disc[which][:, None, None]
        met = np.isfinite(first_hit) & (first_hit > 0)
        pivot = np.where(met, first_hit, self.start[which])[:, None, None]
        return (np.where(sun, -pivot * across, edges),
                np.where(sun, across, -across / self.target[which][:, None, None]))


def cell_frames(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(axes (k,2,3), corners (k,4,2)) of lamp cells `cells (k,4,3)`: two
    orthonormal axes in the plane of each cell (along its first edges), and
    its corners in them; zeros for a cell of zeros (a lamp of size 0)."""
    along = cells[:, 1] - cells[:, 0] + cells[:, 2] - cells[:, 3]
    across = cells[:, 3] - cells[:, 0] + cells[:, 2] - cells[:, 1]
    sized = np.linalg.norm(along, axis=1) > 0
    t = np.zeros_like(along)
    t[sized] = along[sized] / np.linalg.norm(along[sized], axis=1)[:, None]
    b = across - t * np.einsum("kc,kc->k", t, across)[:, None]
    b[sized] /= np.linalg.norm(b[sized], axis=1)[:, None]
    axes = np.stack([t, b], axis=1)
    return axes, np.einsum("kic,kjc->kij", cells, axes)


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
