"""Where beam mode's lamp rays start: a G x G grid laid over each of a
lamp's aims (aims.py) through Shirley and Chiu's concentric map of the
square onto the disc, which keeps grid cells of equal measure."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..sampling.warps import concentric_disc
from ..scene import Light
from .aims import Aim, Sphere, aims, balance_density, share


@dataclass
class BeamSource:
    """A grid of `grid` x `grid` points over one aim of a lamp, the disc
    turned by `roll` radians about the aim's axis. `overlap` lists every
    aim of the same lamp with its grid's sample density (points per unit
    measure), to share the rays that several aims hold."""

    aim: Aim
    energy: float
    grid: int
    overlap: list[tuple[Aim, float]] = field(default_factory=list)
    roll: float = 0.0

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
        return origins, dirs, weight


def beam_sources(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, energy: float,
                 lamp_rays: int, phases: np.ndarray) -> list[BeamSource]:
    """Grids over every lamp's aims, about `lamp_rays` grid points in all,
    shared in proportion to the flux each aim receives; none over an aim
    that receives none (a lamp of power 0).

    `phases (lights, 2)` in [0,1)^2 shift each lamp's grids
    against its casters: the aim widened so that its rings of grid points
    move out by phase[0] of the step between rings at the edge (which puts
    the outer ring's neighbour, the last one on the caster, anywhere
    across the step), and the grid turned by phase[1] of a turn (which
    moves the concentric map's bent diagonals). Neighbouring points of a
    lamp with a size, whose grids would land alike, then sample what lies
    between one grid's points (the light of a glass's rim, say) between
    them."""
    every = [(aim, phase) for light, phase in zip(lights, phases) for aim in aims(light, targets, scene_sphere)
             if aim.flux(energy) > 0]
    if not every:
        return []
    points = share(lamp_rays, [aim.flux(energy) for aim, _ in every], minimum=9)
    sources = []
    for (aim, phase), n in zip(every, points):
        grid = int(round(math.sqrt(n)))
        # rings of the concentric map 2 / (grid - 1) apart in rho
        sources.append(BeamSource(aim.widened(1.0 + 2.0 * phase[0] / (grid - 1)), energy, grid,
                                  roll=2.0 * math.pi * phase[1]))
    for source in sources:
        source.overlap = [(other.aim, 1.0 / other.cell_measure) for other in sources
                          if other.aim.light is source.aim.light]
    return sources
