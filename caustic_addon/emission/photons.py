"""Where photons leave the lamps, which way, and with how much flux.

Each lamp gets an `Emitter` that makes photon i from its index alone, so a
render split into chunks gives the same photons whatever the chunk size.

Two modes:
- 'sphere': the paper's eq. (1), P(u,v) = (cos v cos u, cos v sin u, sin v)
  on a grid of u in [0, 2 pi), v in [-pi/2, pi/2]; a photon carries the
  intensity times the solid angle of its (u,v) cell, so a uniform lamp stays
  uniform.
- 'targeted': only into the cones (point, spot) or over the discs (sun) that
  hold the casters' (transparent and reflecting objects') bounding spheres, on a low-discrepancy
  sequence. Where cones overlap, a photon's flux is divided by the summed
  sample density of all cones that contain it (the balance heuristic), so the
  expected irradiance equals that of full-sphere emission.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling.sequences import r2_sequence
from ..sampling.warps import orthonormal_basis, sample_cone, sample_disc
from ..scene import Light, SunLight
from . import radiometry
from .targets import Sphere, target_cone, visible_targets


def sphere_grid(count: int) -> tuple[int, int]:
    """(nu, nv): the paper's (u, v) grid with about `count` cells, twice as
    many steps in u (0..2 pi) as in v (-pi/2..pi/2), so cells are square at the equator."""
    nv = max(1, int(round(math.sqrt(count / 2.0))))
    return 2 * nv, nv


@dataclass
class Photons:
    """A batch of n photons leaving a lamp: origins (n,3), dirs (n,3) unit,
    flux (n,3) W, ids (n,) int64 unique per render (they seed each photon's
    random choices). Photons with zero flux are already removed."""

    origins: np.ndarray
    dirs: np.ndarray
    flux: np.ndarray
    ids: np.ndarray


class Emitter:
    """Makes photons [start, stop) of one lamp. `count` is how many it makes
    in all; its photons' ids start at `id_base`."""

    count: int
    flux_toward_targets: float
    id_base: int = 0

    def emit(self, start: int, stop: int) -> Photons:
        raise NotImplementedError


def _kept(origins, dirs, flux, ids) -> Photons:
    keep = flux.max(axis=1) > 0.0
    return Photons(origins[keep], dirs[keep], flux[keep], ids[keep])


class PointSphereEmitter(Emitter):
    """The paper's eq. (1): every direction, on the (u, v) grid's cell centres."""

    def __init__(self, light: Light, energy: float, count: int):
        self.light, self.energy = light, energy
        self.nu, self.nv = sphere_grid(count)
        self.count = self.nu * self.nv
        self.flux_toward_targets = float(light.power * energy)

    def emit(self, start: int, stop: int) -> Photons:
        i = np.arange(start, stop)
        du, dv = 2.0 * math.pi / self.nu, math.pi / self.nv
        u = (i % self.nu + 0.5) * du
        v0 = -0.5 * math.pi + (i // self.nu) * dv
        v = v0 + 0.5 * dv
        dirs = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
        cell_solid_angle = du * (np.sin(v0 + dv) - np.sin(v0))
        flux = radiometry.intensity(self.light, self.energy, dirs) * cell_solid_angle[:, None]
        origins = np.broadcast_to(self.light.position, dirs.shape)
        return _kept(origins, dirs, flux, i + self.id_base)


class PointConeEmitter(Emitter):
    """Into the cones from a point or spot lamp that hold the target spheres."""

    def __init__(self, light: Light, energy: float, count: int, targets: list[Sphere], shift: np.ndarray):
        self.light, self.energy, self.shift = light, energy, shift
        axes, cos_max = zip(*(target_cone(light.position, sphere) for sphere in targets))
        self.axes, self.cos_max = np.array(axes), np.array(cos_max)
        solid_angles = 2.0 * math.pi * (1.0 - self.cos_max)
        self.counts = np.maximum(1, np.round(count * solid_angles / solid_angles.sum())).astype(np.int64)
        self.starts = np.concatenate([[0], np.cumsum(self.counts)])
        self.count = int(self.starts[-1])
        # photons per steradian of each cone
        self.density = self.counts / solid_angles
        self.flux_toward_targets = float(light.power * energy * min(solid_angles.sum(), 4.0 * math.pi)
                                         / (4.0 * math.pi))

    def emit(self, start: int, stop: int) -> Photons:
        i = np.arange(start, stop)
        cone = np.searchsorted(self.starts, i, side="right") - 1
        uv = r2_sequence(i - self.starts[cone], self.shift)
        dirs = np.empty((len(i), 3))
        for k in np.unique(cone):
            sel = cone == k
            dirs[sel] = sample_cone(self.axes[k], self.cos_max[k], uv[sel])
        inside = (dirs @ self.axes.T) >= self.cos_max[None, :] - 1e-12
        density = inside.astype(np.float64) @ self.density
        flux = radiometry.intensity(self.light, self.energy, dirs) / density[:, None]
        origins = np.broadcast_to(self.light.position, dirs.shape)
        return _kept(origins, dirs, flux, i + self.id_base)


class SunDiscEmitter(Emitter):
    """Parallel rays over the discs, seen along the sun, of the target spheres.
    Origins start upstream of everything (`start_distance` before each centre)."""

    def __init__(self, light: SunLight, energy: float, count: int, targets: list[Sphere],
                 start_distance: float, shift: np.ndarray):
        self.light, self.energy, self.shift = light, energy, shift
        self.targets, self.start_distance = targets, start_distance
        self.tangent, self.bitangent = orthonormal_basis(light.direction)
        areas = np.array([math.pi * s.radius ** 2 for s in targets])
        self.counts = np.maximum(1, np.round(count * areas / areas.sum())).astype(np.int64)
        self.starts = np.concatenate([[0], np.cumsum(self.counts)])
        self.count = int(self.starts[-1])
        self.density = self.counts / areas
        self.flux_toward_targets = float(light.strength * energy * areas.sum())

    def _plane_coords(self, points: np.ndarray) -> np.ndarray:
        return np.stack([points @ self.tangent, points @ self.bitangent], axis=1)

    def emit(self, start: int, stop: int) -> Photons:
        i = np.arange(start, stop)
        disc = np.searchsorted(self.starts, i, side="right") - 1
        uv = r2_sequence(i - self.starts[disc], self.shift)
        radii = np.array([s.radius for s in self.targets])
        centers = np.array([s.center for s in self.targets])
        xy = sample_disc(1.0, uv) * radii[disc][:, None]
        origins = (centers[disc] + xy[:, :1] * self.tangent + xy[:, 1:] * self.bitangent
                   - self.start_distance * self.light.direction)
        offsets = self._plane_coords(origins)[:, None, :] - self._plane_coords(centers)[None, :, :]
        inside = np.einsum("nkj,nkj->nk", offsets, offsets) <= (radii ** 2)[None, :] * (1.0 + 1e-12)
        density = inside.astype(np.float64) @ self.density
        flux = radiometry.sun_irradiance(self.light, self.energy)[None, :] / density[:, None]
        dirs = np.broadcast_to(self.light.direction, origins.shape)
        return _kept(origins, np.ascontiguousarray(dirs), flux, i + self.id_base)


def make_emitters(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, mode: str,
                  energy: float, photons: int, seed: int) -> list[Emitter]:
    """One emitter per lamp that can light a target, with the photon budget
    shared in proportion to the flux each sends toward its targets."""
    rng = np.random.default_rng(seed)
    start_distance = 2.0 * scene_sphere.radius + 1.0
    candidates = []
    for light in lights:
        aimed = [scene_sphere] if mode == "sphere" else visible_targets(light, targets)
        if not aimed or not targets:
            continue
        candidates.append((light, aimed))

    def build(light, aimed, count):
        shift = rng.random(2)
        if isinstance(light, SunLight):
            return SunDiscEmitter(light, energy, count, aimed, start_distance, shift)
        if mode == "sphere":
            return PointSphereEmitter(light, energy, count)
        return PointConeEmitter(light, energy, count, aimed, shift)

    probes = [build(light, aimed, 1) for light, aimed in candidates]
    weights = np.array([p.flux_toward_targets for p in probes], dtype=np.float64)
    if len(probes) == 0 or weights.sum() <= 0:
        return []
    shares = np.maximum(1, np.round(photons * weights / weights.sum())).astype(int)
    emitters = [build(light, aimed, int(n)) for (light, aimed), n in zip(candidates, shares)]
    for k in range(1, len(emitters)):
        emitters[k].id_base = emitters[k - 1].id_base + emitters[k - 1].count
    return emitters
