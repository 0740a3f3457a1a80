"""Where beam mode's lamp rays start: a G x G grid laid over each lamp's
target cone (equal-area: Shirley and Chiu's concentric square-to-disc map,
then the cone's cos(theta) = 1 - rho^2 (1 - cos_max)), or over a sun's
target disc."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..sampling.warps import concentric_disc, orthonormal_basis
from ..scene import Light, SunLight
from . import radiometry
from .targets import Sphere, target_cone, visible_targets


@dataclass
class BeamSource:
    """One gridded cone (point or spot lamp) or disc (sun) of a lamp.

    For a cone: `axis`, `cos_max`; for a disc: `center`, `radius` of the
    target, crossed by parallel light from `start_distance` upstream.
    `cell_measure` is the solid angle (sr) or area (m^2) of one grid cell.
    `overlap` lists every source of the same lamp, to share directions or
    positions that several cones or discs cover (the balance heuristic).
    """

    light: Light
    energy: float
    grid: int
    axis: np.ndarray = None
    cos_max: float = 0.0
    center: np.ndarray = None
    radius: float = 0.0
    start_distance: float = 0.0
    overlap: list = field(default_factory=list)

    @property
    def is_disc(self) -> bool:
        return isinstance(self.light, SunLight)

    @property
    def measure(self) -> float:
        if self.is_disc:
            return math.pi * self.radius ** 2
        return 2.0 * math.pi * (1.0 - self.cos_max)

    @property
    def cell_measure(self) -> float:
        return self.measure / (self.grid - 1) ** 2

    def contains(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        if self.is_disc:
            rel = origins - self.center
            along = rel @ self.light.direction
            perp = rel - along[:, None] * self.light.direction
            return np.einsum("ij,ij->i", perp, perp) <= self.radius ** 2 * (1 + 1e-9)
        return dirs @ self.axis >= self.cos_max - 1e-12

    def rays_at(self, rc: np.ndarray):
        """Rays at continuous grid positions `rc (n,2)` (row, col) in [0,
        grid - 1]: (origins (n,3), dirs (n,3), weight (n,3) intensity (W/sr)
        or irradiance (W/m^2) times the overlap share)."""
        disc = concentric_disc(rc / (self.grid - 1))
        if self.is_disc:
            t, b = orthonormal_basis(self.light.direction)
            origins = (self.center + self.radius * (disc[:, :1] * t + disc[:, 1:] * b)
                       - self.start_distance * self.light.direction)
            dirs = np.broadcast_to(self.light.direction, origins.shape).copy()
            weight = np.broadcast_to(radiometry.sun_irradiance(self.light, self.energy), origins.shape).copy()
        else:
            rho2 = np.einsum("ij,ij->i", disc, disc)
            cos_t = 1.0 - rho2 * (1.0 - self.cos_max)
            sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
            rho = np.sqrt(rho2)
            with np.errstate(invalid="ignore", divide="ignore"):
                c = np.where(rho > 0, disc[:, 0] / rho, 1.0)
                s = np.where(rho > 0, disc[:, 1] / rho, 0.0)
            t, b = orthonormal_basis(self.axis)
            dirs = (sin_t * c)[:, None] * t + (sin_t * s)[:, None] * b + cos_t[:, None] * self.axis
            origins = np.broadcast_to(self.light.position, dirs.shape).copy()
            weight = radiometry.intensity(self.light, self.energy, dirs).copy()
        density = sum(src.contains(origins, dirs) / src.cell_measure for src in self.overlap)
        weight *= ((1.0 / self.cell_measure) / density)[:, None]
        return origins, dirs, weight


def beam_sources(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, energy: float,
                 vertices: int) -> list[BeamSource]:
    """Grids over every lamp's targets, about `vertices` grid points in all,
    shared in proportion to the flux each cone or disc receives."""
    start_distance = 2.0 * scene_sphere.radius + 1.0
    sources = []
    for light in lights:
        per_light = []
        for sphere in visible_targets(light, targets):
            if isinstance(light, SunLight):
                per_light.append(BeamSource(light, energy, 2, center=sphere.center, radius=sphere.radius,
                                            start_distance=start_distance))
                continue
            axis, cos_max = target_cone(light.position, sphere)
            if cos_max <= -1.0:
                # a lamp inside the target: two hemispheres, since one grid over
                # the whole sphere folds its edge onto a single direction
                per_light += [BeamSource(light, energy, 2, axis=a, cos_max=0.0) for a in (axis, -axis)]
                continue
            per_light.append(BeamSource(light, energy, 2, axis=axis, cos_max=cos_max))
        for src in per_light:
            src.overlap = per_light
        sources += per_light
    if not sources:
        return []
    flux = np.array([s.measure * (s.light.strength if s.is_disc else s.light.power) for s in sources])
    for src, share in zip(sources, vertices * flux / flux.sum()):
        src.grid = max(3, int(round(math.sqrt(share))))
    return sources
