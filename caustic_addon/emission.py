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

from . import units
from .scene import Light, SpotLight, SunLight

# R2 low-discrepancy sequence (Roberts 2018): x_i = frac(s + i * alpha),
# alpha = (1/g, 1/g^2) with g the plastic number.
_PLASTIC = 1.32471795724474602596
_R2_ALPHA = np.array([1.0 / _PLASTIC, 1.0 / _PLASTIC ** 2])


def hash_uniform(ids: np.ndarray, stream: int, seed: int) -> np.ndarray:
    """(n,) uniform floats in (0,1) that depend only on (id, stream, seed):
    the splitmix64 finaliser (Steele et al. 2014) of their combination. A
    photon's random choices are then the same however the work is chunked."""
    with np.errstate(over="ignore"):
        x = (ids.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
             + np.uint64((stream * 0x632BE59BD9B4E019 + seed * 0xD6E8FEB86659FD93) % (1 << 64)))
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
    return ((x >> np.uint64(11)).astype(np.float64) + 0.5) * (1.0 / (1 << 53))


def r2_sequence(index: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """(n,2) points in [0,1)^2 of the R2 sequence at integer `index (n,)`,
    Cranley-Patterson rotated by `shift (2,)`."""
    return np.mod(shift[None, :] + index[:, None].astype(np.float64) * _R2_ALPHA[None, :], 1.0)


def orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) that make a right-handed frame with unit `axis (3,)`
    (Duff et al. 2017, "Building an orthonormal basis, revisited")."""
    sign = math.copysign(1.0, axis[2])
    a = -1.0 / (sign + axis[2])
    b = axis[0] * axis[1] * a
    return (np.array([1.0 + sign * axis[0] ** 2 * a, sign * b, -sign * axis[0]]),
            np.array([b, sign + axis[1] ** 2 * a, -axis[1]]))


def sample_cone(axis: np.ndarray, cos_max: float, uv: np.ndarray) -> np.ndarray:
    """Unit directions (n,3) uniform in solid angle within `acos(cos_max)` of
    `axis`: cos(theta) = 1 - u (1 - cos_max), phi = 2 pi v."""
    cos_t = 1.0 - uv[:, 0] * (1.0 - cos_max)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * math.pi * uv[:, 1]
    t, b = orthonormal_basis(axis)
    return (sin_t * np.cos(phi))[:, None] * t + (sin_t * np.sin(phi))[:, None] * b + cos_t[:, None] * axis


def sample_disc(radius: float, uv: np.ndarray) -> np.ndarray:
    """(n,2) points uniform over a disc: r = R sqrt(u), phi = 2 pi v."""
    r = radius * np.sqrt(uv[:, 0])
    phi = 2.0 * math.pi * uv[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def sphere_grid(count: int) -> tuple[int, int]:
    """(nu, nv): the paper's (u, v) grid with about `count` cells, twice as
    many steps in u (0..2 pi) as in v (-pi/2..pi/2), so cells are square at the equator."""
    nv = max(1, int(round(math.sqrt(count / 2.0))))
    return 2 * nv, nv


@dataclass
class Sphere:
    """A bounding sphere: centre (3,), radius."""

    center: np.ndarray
    radius: float

    @staticmethod
    def around(points: np.ndarray) -> "Sphere":
        center = 0.5 * (points.min(axis=0) + points.max(axis=0))
        return Sphere(center, float(np.linalg.norm(points - center, axis=1).max()))


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
        flux = units.intensity(self.light, self.energy, dirs) * cell_solid_angle[:, None]
        origins = np.broadcast_to(self.light.position, dirs.shape)
        return _kept(origins, dirs, flux, i + self.id_base)


def target_cone(position: np.ndarray, sphere: Sphere) -> tuple[np.ndarray, float]:
    """(axis (3,) unit, cos_max) of the cone from `position` that holds
    `sphere`: cos_max = sqrt(1 - (r/d)^2) at distance d; the whole sphere of
    directions (cos_max = -1, any axis) from inside it."""
    to_center = sphere.center - position
    dist = float(np.linalg.norm(to_center))
    if dist <= sphere.radius:
        return np.array([0.0, 0.0, -1.0]), -1.0
    return to_center / dist, math.sqrt(1.0 - (sphere.radius / dist) ** 2)


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
        flux = units.intensity(self.light, self.energy, dirs) / density[:, None]
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
        flux = units.sun_irradiance(self.light, self.energy)[None, :] / density[:, None]
        dirs = np.broadcast_to(self.light.direction, origins.shape)
        return _kept(origins, np.ascontiguousarray(dirs), flux, i + self.id_base)


def visible_targets(light: Light, targets: list[Sphere]) -> list[Sphere]:
    """The target spheres a lamp can light: all of them, except those wholly
    outside a spot lamp's cone."""
    if not isinstance(light, SpotLight):
        return list(targets)
    half = 0.5 * light.spot_size
    kept = []
    for sphere in targets:
        to_center = sphere.center - light.position
        dist = float(np.linalg.norm(to_center))
        if dist <= sphere.radius:
            kept.append(sphere)
            continue
        angle = math.acos(np.clip(to_center @ light.direction / dist, -1.0, 1.0))
        if angle - math.asin(sphere.radius / dist) < half:
            kept.append(sphere)
    return kept


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
