"""Where the lamps send their rays: one aim per lamp and caster, a cone of
directions from a point or spot lamp that holds the caster's bounding
sphere, or the disc of it that a sun's parallel rays cross. Photons sample
an aim on a low-discrepancy sequence and beams on a grid, both through
`Aim.rays`, a map of the unit disc onto the aim that is uniform in its
measure (solid angle or area). Where one lamp's aims overlap, a ray stands
for every aim that holds it: its weight is divided by the summed sample
density of those aims (the balance heuristic, Veach 1997), so the expected
light is that of a lamp that sends rays everywhere."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling.warps import orthonormal_basis
from ..scene import Light, Scene, SpotLight, SunLight
from . import radiometry

# Rays at an aim's edge count as inside it: cos(theta) this far below the
# cone's cos_max, or radius^2 this fraction beyond the disc's.
_EDGE_TOLERANCE = 1e-12


@dataclass
class Sphere:
    """A bounding sphere: centre (3,), radius."""

    center: np.ndarray
    radius: float

    @staticmethod
    def around(points: np.ndarray) -> "Sphere":
        center = 0.5 * (points.min(axis=0) + points.max(axis=0))
        return Sphere(center, float(np.linalg.norm(points - center, axis=1).max()))


def casters_and_bounds(scene: Scene) -> tuple[list[Sphere], Sphere]:
    """The casters' (transparent and reflecting objects') bounding spheres,
    which lamps aim at, and the sphere around the whole scene."""
    lo, hi = scene.bounds()
    return ([Sphere.around(o.mesh.vertices) for o in scene.casters],
            Sphere(0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))))


def upstream_distance(scene_sphere: Sphere) -> float:
    """How far before a target's centre a sun's rays start: beyond
    everything in the scene."""
    return 2.0 * scene_sphere.radius + 1.0


def target_cone(position: np.ndarray, sphere: Sphere) -> tuple[np.ndarray, float]:
    """(axis (3,) unit, cos_max) of the cone from `position` that holds
    `sphere`: cos_max = sqrt(1 - (r/d)^2) at distance d; the whole sphere of
    directions (cos_max = -1, any axis) from inside it."""
    to_center = sphere.center - position
    dist = float(np.linalg.norm(to_center))
    if dist <= sphere.radius:
        return np.array([0.0, 0.0, -1.0]), -1.0
    return to_center / dist, math.sqrt(1.0 - (sphere.radius / dist) ** 2)


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


@dataclass
class Aim:
    """One lamp's rays toward one target.

    A cone (point and spot lamps): `axis (3,)` unit and `cos_max`, from the
    lamp's position. A disc (suns): `axis` is the sun's direction, `center
    (3,)` and `radius` the disc's, and its rays start `start_distance`
    upstream of it. `tangent`, `bitangent` (3,) complete the axis to a frame.
    """

    light: Light
    axis: np.ndarray
    cos_max: float = 1.0
    center: np.ndarray = None
    radius: float = 0.0
    start_distance: float = 0.0

    def __post_init__(self):
        self.tangent, self.bitangent = orthonormal_basis(self.axis)

    @property
    def is_disc(self) -> bool:
        return isinstance(self.light, SunLight)

    @property
    def measure(self) -> float:
        """The aim's solid angle (sr) or area (m^2)."""
        if self.is_disc:
            return math.pi * self.radius ** 2
        return 2.0 * math.pi * (1.0 - self.cos_max)

    def flux(self, energy: float) -> float:
        """The lamp's flux toward the aim, W, the spot's mask aside: what the
        lamp rays are shared by."""
        if self.is_disc:
            return float(self.light.strength * energy * self.measure)
        return float(self.light.power * energy * self.measure / (4.0 * math.pi))

    def contains(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) bool: which rays `origins, dirs (n,3)` the aim holds."""
        if self.is_disc:
            rel = origins - self.center
            perp = rel - (rel @ self.axis)[:, None] * self.axis
            return np.einsum("ij,ij->i", perp, perp) <= self.radius ** 2 * (1.0 + _EDGE_TOLERANCE)
        return dirs @ self.axis >= self.cos_max - _EDGE_TOLERANCE

    def rays(self, disc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(origins (n,3), dirs (n,3)) at points `disc (n,2)` of the unit
        disc, mapped so that a uniform density on the disc is uniform in the
        aim's measure. A cone: cos(theta) = 1 - rho^2 (1 - cos_max) at
        radius rho, the disc's azimuth about the axis (Archimedes' hat-box
        theorem); a disc: center + radius (x t + y b)."""
        if self.is_disc:
            origins = (self.center + self.radius * (disc[:, :1] * self.tangent + disc[:, 1:] * self.bitangent)
                       - self.start_distance * self.axis)
            return origins, np.broadcast_to(self.axis, origins.shape).copy()
        rho2 = np.einsum("ij,ij->i", disc, disc)
        cos_t = 1.0 - rho2 * (1.0 - self.cos_max)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
        rho = np.sqrt(rho2)
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.where(rho > 0, disc[:, 0] / rho, 1.0)
            s = np.where(rho > 0, disc[:, 1] / rho, 0.0)
        dirs = (sin_t * c)[:, None] * self.tangent + (sin_t * s)[:, None] * self.bitangent + cos_t[:, None] * self.axis
        return np.broadcast_to(self.light.position, dirs.shape).copy(), dirs

    def emitted(self, energy: float, dirs: np.ndarray) -> np.ndarray:
        """(n,3) what the lamp sends along `dirs (n,3)`: radiant intensity,
        W/sr, from a cone's lamp; irradiance, W/m^2, across a disc."""
        if self.is_disc:
            return np.broadcast_to(radiometry.sun_irradiance(self.light, energy), dirs.shape).copy()
        return radiometry.intensity(self.light, energy, dirs).copy()


def aims(light: Light, targets: list[Sphere], scene_sphere: Sphere) -> list[Aim]:
    """A lamp's aims at the targets it can light. A lamp inside a target
    gets two hemispheres: one cone over the whole sphere of directions would
    fold a grid's edge onto a single direction."""
    out = []
    for sphere in visible_targets(light, targets):
        if isinstance(light, SunLight):
            out.append(Aim(light, light.direction, center=sphere.center, radius=sphere.radius,
                           start_distance=upstream_distance(scene_sphere)))
            continue
        axis, cos_max = target_cone(light.position, sphere)
        if cos_max <= -1.0:
            out += [Aim(light, a, cos_max=0.0) for a in (axis, -axis)]
        else:
            out.append(Aim(light, axis, cos_max=cos_max))
    return out


def balance_density(aims: list[Aim], density: np.ndarray, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(n,) samples per unit measure at rays `origins, dirs (n,3)` of one
    lamp whose aims take `density (k,)` samples per unit measure each: the
    sum over the aims that hold each ray."""
    total = np.zeros(len(origins))
    for aim, rate in zip(aims, density):
        total += rate * aim.contains(origins, dirs)
    return total


def share(total: int, weights: np.ndarray, minimum: int = 1) -> np.ndarray:
    """(k,) int64 parts of `total` in proportion to `weights (k,)`, each at
    least `minimum`."""
    weights = np.asarray(weights, dtype=np.float64)
    return np.maximum(minimum, np.round(total * weights / weights.sum())).astype(np.int64)
