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
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

from ..sampling.warps import cone_directions, cone_of_disc, orthonormal_basis
from ..scene import AreaLight, Light, Mesh, MeshLight, Object, Scene, SpotLight, SunLight
from ..util.jit import kernel
from ..util.rows import contiguous
from ..util.vectors import row, set_row
from . import mesh_lights, radiometry
from .lamp_samples import area_point1, facing_disc_point1

# Rays at an aim's edge count as inside it: cos(theta) this far below the
# cone's cos_max, or radius^2 this fraction beyond the disc's.
_EDGE_TOLERANCE = 1e-12
# A sun's disc aim widens by 1 / cos of the half angle, so that its tilted rays still cover the target; a
# sun of 180 degrees (a hemisphere) would widen it without end. Directions past acos(0.1), 84 degrees
# off its axis, carry 1% of a hemisphere's light (cos^2), and they still reach part of the target.
_SUN_WIDEN_COS = 0.1
# Pieces a mesh light's flux toward the casters is estimated from.
FLUX_PIECES = 16


@dataclass
class Sphere:
    """A bounding sphere: centre (3,), radius."""

    center: np.ndarray
    radius: float

    @staticmethod
    def around(points: np.ndarray) -> "Sphere":
        center = 0.5 * (points.min(axis=0) + points.max(axis=0))
        return Sphere(center, float(np.linalg.norm(points - center, axis=1).max()))

    @staticmethod
    def around_meshes(meshes: list[Mesh]) -> "Sphere":
        """Sphere.around all the vertices of `meshes`, with no copy of them."""
        center = 0.5 * (np.min([m.bounds[0] for m in meshes], axis=0) + np.max([m.bounds[1] for m in meshes], axis=0))
        return Sphere(center, max(m.farthest_from(center) for m in meshes))


def casters_and_bounds(scene: Scene) -> tuple[list[Sphere], Sphere]:
    """The casters' (transparent and reflecting objects') bounding spheres,
    one around the casters of each body, which lamps aim at, and the sphere
    around the whole scene."""
    lo, hi = scene.bounds()
    return ([Sphere.around_meshes([caster.mesh for caster in body]) for body in _bodies(scene)],
            Sphere(0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))))


def smooth_and_rough(scene: Scene, targets: list[Sphere]) -> tuple[list[Sphere], list[Sphere]]:
    """casters_and_bounds' `targets`, one per body, parted into those of
    the bodies with no rough part and those of the bodies with one."""
    rough = [any(not caster.material.smooth for caster in body) for body in _bodies(scene)]
    return ([sphere for sphere, r in zip(targets, rough) if not r],
            [sphere for sphere, r in zip(targets, rough) if r])


def _bodies(scene: Scene) -> list[list[Object]]:
    """The casters of each body, bodies in the scene's order."""
    bodies: dict[str, list[Object]] = {}
    for caster in scene.casters:
        bodies.setdefault(caster.body_name, []).append(caster)
    return list(bodies.values())


def meets_any(spheres: list[Sphere], origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(n,) bool: the rays `origins, dirs (n,3)` (unit) that meet one of the
    `spheres` ahead of their origin, or start inside one: with oc the
    centre less the origin, the ray's closest approach |oc|^2 - (oc.d)^2
    is within the radius squared, and oc.d >= 0 or |oc| <= r."""
    met = np.zeros(len(dirs), dtype=bool)
    for sphere in spheres:
        oc = sphere.center - origins
        along = np.einsum("ij,ij->i", oc, dirs)
        square = np.einsum("ij,ij->i", oc, oc)
        r2 = sphere.radius ** 2
        met |= (square - along ** 2 <= r2) & ((along >= 0.0) | (square <= r2))
    return met


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
    outside a spot lamp's cone from every point of the lamp."""
    if not isinstance(light, SpotLight):
        return list(targets)
    half = 0.5 * light.spot_size
    kept = []
    for sphere in targets:
        to_center = sphere.center - light.position
        dist = float(np.linalg.norm(to_center))
        radius = sphere.radius + light.radius
        if dist <= radius:
            kept.append(sphere)
            continue
        angle = math.acos(np.clip(to_center @ light.direction / dist, -1.0, 1.0))
        if angle - math.asin(radius / dist) < half:
            kept.append(sphere)
    return kept


def reach(light: Light) -> float:
    """How far a lamp's emitting points lie from its centre, m: a point or
    spot lamp's radius, an area lamp's half-diagonal, a mesh light's reach
    from its centroid; 0 for a sun."""
    if isinstance(light, AreaLight):
        return float(np.linalg.norm(light.axis_x) + np.linalg.norm(light.axis_y))
    if isinstance(light, SunLight):
        return 0.0
    return float(light.radius)


@dataclass
class Aim:
    """One lamp's rays toward one target.

    A cone (point, spot and area lamps): `axis (3,)` unit and `cos_max`,
    from the lamp's centre, wide enough that rays from any point of the lamp
    toward the target lie in it, and `target_distance` from the lamp to the
    target's centre (its radius from a lamp inside it). A disc (suns):
    `axis` is the sun's direction, `center (3,)` and `radius` the disc's,
    and its rays start `start_distance` upstream of it. `tangent`,
    `bitangent` (3,) complete the axis to a frame.
    """

    light: Light
    axis: np.ndarray
    cos_max: float = 1.0
    center: np.ndarray = None
    radius: float = 0.0
    start_distance: float = 0.0
    target_distance: float = 0.0

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
        """The lamp's flux toward the aim, W, a spot's mask aside: what the
        lamp rays are shared by."""
        light = self.light
        if self.is_disc:
            return float(light.strength * radiometry.sun_energy(light, energy) * self.measure)
        if isinstance(light, AreaLight):
            facing = max(float(self.axis @ light.direction), 0.0)
            return float(light.power * energy * self.measure * facing / math.pi)
        return float(light.power * energy * self.measure / (4.0 * math.pi))

    def widened(self, scale: float) -> "Aim":
        """This aim with its disc's radius `scale` times as large: a disc's in
        metres, a cone's in the map's rho (1 - cos_max times scale^2); this
        very aim at scale 1, whose rays then stay bit for bit."""
        if scale == 1.0:
            return self
        if self.is_disc:
            return replace(self, radius=self.radius * scale)
        return replace(self, cos_max=max(1.0 - (1.0 - self.cos_max) * scale ** 2, -1.0))

    def contains(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) bool: which rays `origins, dirs (n,3)` the aim holds: a
        cone's by their direction, a disc's by where they cross its plane."""
        if self.is_disc:
            rel = origins - self.center
            along = dirs @ self.axis
            with np.errstate(divide="ignore", invalid="ignore"):
                crossing = rel - ((rel @ self.axis) / along)[:, None] * dirs
            return np.einsum("ij,ij->i", crossing, crossing) <= self.radius ** 2 * (1.0 + _EDGE_TOLERANCE)
        return dirs @ self.axis >= self.cos_max - _EDGE_TOLERANCE

    def crossing(self, disc: np.ndarray) -> np.ndarray:
        """(n,3) where a sun's rays cross its disc at points `disc (n,2)` of
        the unit disc (`disc_points`)."""
        return disc_points(self.center, self.radius, self.tangent, self.bitangent, disc)

    def rays(self, disc: np.ndarray, lamp: Optional[np.ndarray] = None) -> tuple[np.ndarray, np.ndarray]:
        """(origins (n,3), dirs (n,3)) at points `disc (n,2)` of the unit
        disc, mapped so that a uniform density on the disc is uniform in the
        aim's measure, from points `lamp (n,2)` of the unit square on the
        lamp (None: its centre, for a lamp of size 0). A cone: directions
        with cos(theta) = 1 - rho^2 (1 - cos_max) at radius rho, the disc's
        azimuth about the axis (Archimedes' hat-box theorem); a disc: through
        center + radius (x t + y b), along a direction of the sun's disc."""
        if self.is_disc:
            through = self.crossing(disc)
            if lamp is not None and self.light.angle > 0.0:
                dirs = cone_directions(self.axis, math.cos(0.5 * self.light.angle), lamp)
            else:
                dirs = np.broadcast_to(self.axis, through.shape).copy()
            return through - self.start_distance * dirs, dirs
        dirs = cone_of_disc(self.axis, self.cos_max, disc)
        if lamp is None or reach(self.light) <= 0.0:
            return np.broadcast_to(self.light.position, dirs.shape).copy(), dirs
        return emitting_points(self.light, dirs, lamp), dirs

    def emitted(self, energy: float, dirs: np.ndarray) -> np.ndarray:
        """(n,3) what the lamp sends along `dirs (n,3)`: radiant intensity,
        W/sr, from a cone's lamp; irradiance, W/m^2, across a disc (a sun
        with an angle: L x its disc's solid angle x cos of the tilt)."""
        light = self.light
        if not self.is_disc:
            return radiometry.intensity(light, energy, dirs).copy()
        if light.angle <= 0.0:
            return np.broadcast_to(radiometry.sun_irradiance(light, energy), dirs.shape).copy()
        solid_angle = 2.0 * math.pi * (1.0 - math.cos(0.5 * light.angle))
        tilt = np.maximum(dirs @ self.axis, 0.0)
        return (radiometry.sun_radiance(light, energy) * solid_angle)[None, :] * tilt[:, None]


def disc_points(center, radius, tangent, bitangent, disc: np.ndarray) -> np.ndarray:
    """center + radius (x t + y b) at points `disc (..., 2)` of the unit
    disc: where a sun's rays cross its aim's disc of `center`, `radius` and
    frame `tangent`, `bitangent` (3-vectors, or arrays that broadcast
    against the points: many aims' at once)."""
    return center + radius * (disc[..., :1] * tangent + disc[..., 1:] * bitangent)


def emitting_points(light: Light, dirs: np.ndarray, lamp: np.ndarray) -> np.ndarray:
    """(n,3) points `lamp (n,2)` of the unit square on a lamp with a size,
    where rays along `dirs (n,3)` cross it: an area lamp's points uniform
    over its surface; a point or spot lamp's on the disc through its centre
    that faces each direction, the lines that a sphere of its radius sends
    that way (its Soft Falloff disc, which Cycles turns toward each point it
    lights, has that far field too)."""
    out = np.empty((len(lamp), 3))
    lamp = contiguous(lamp, np.float64)
    if isinstance(light, AreaLight):
        _area_points(lamp, light.shape == "ELLIPSE", contiguous(light.center, np.float64),
                     contiguous(light.axis_x, np.float64), contiguous(light.axis_y, np.float64), out)
    else:
        _facing_disc_points(lamp, contiguous(dirs, np.float64), contiguous(light.position, np.float64),
                            float(light.radius), out)
    return out


@kernel("void(f8[:, ::1], b1, f8[::1], f8[::1], f8[::1], f8[:, ::1])")
def _area_points(lamp, ellipse, center, axis_x, axis_y, out):
    """out (n,3): lamp_samples.area_point1 of each of `lamp (n,2)`."""
    for i in range(len(lamp)):
        set_row(out, i, area_point1(lamp[i, 0], lamp[i, 1], ellipse, center, axis_x, axis_y))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[::1], f8, f8[:, ::1])")
def _facing_disc_points(lamp, dirs, position, radius, out):
    """out (n,3): lamp_samples.facing_disc_point1 of each of `lamp (n,2)`,
    on the disc square to `dirs (n,3)`."""
    at = (position[0], position[1], position[2])
    for i in range(len(lamp)):
        set_row(out, i, facing_disc_point1(lamp[i, 0], lamp[i, 1], at, radius, row(dirs, i)))


def aims(light: Light, targets: list[Sphere], scene_sphere: Sphere) -> list[Aim]:
    """A lamp's aims at the targets it can light: cones from its centre
    widened by its reach, or a sun's discs widened by its angle. A lamp
    inside a target gets two hemispheres: one cone over the whole sphere of
    directions would fold a grid's edge onto a single direction."""
    out = []
    for sphere in visible_targets(light, targets):
        if isinstance(light, SunLight):
            out.append(Aim(light, light.direction, center=sphere.center,
                           radius=sphere.radius * float(sun_widening(light.angle)),
                           start_distance=upstream_distance(scene_sphere)))
            continue
        axis, cos_max = target_cone(light.position, Sphere(sphere.center, sphere.radius + reach(light)))
        distance = max(float(np.linalg.norm(sphere.center - light.position)), sphere.radius)
        if cos_max <= -1.0:
            out += [Aim(light, a, cos_max=0.0, target_distance=distance) for a in (axis, -axis)]
        else:
            out.append(Aim(light, axis, cos_max=cos_max, target_distance=distance))
    return out


def flux_toward(light: Light, targets: list[Sphere], scene_sphere: Sphere) -> float:
    """W (at energy 1) that `light`'s aims hold: a mesh light's from FLUX_PIECES of its pieces."""
    if isinstance(light, MeshLight):
        parts = mesh_lights.point_lamps(light, FLUX_PIECES, mesh_lights.lift_off(light))[0]
        return sum(flux_toward(part, targets, scene_sphere) for part in parts)
    return sum(aim.flux(1.0) for aim in aims(light, targets, scene_sphere))


def sun_widening(angle):
    """How many times wider than its target a sun's disc aim is, for a sun
    of `angle` radians (or an array of them): 1 / cos of its half angle, so
    that its tilted rays still cover the target, at most 1 / _SUN_WIDEN_COS."""
    return 1.0 / np.maximum(np.cos(0.5 * np.asarray(angle)), _SUN_WIDEN_COS)


def overlapping(aims: list[Aim]) -> list[np.ndarray]:
    """For each of one lamp's `aims`, the indices (ascending) of the aims
    that may hold a ray it holds, itself among them, conservatively: cones
    whose half-angles (widened by contains' tolerance) reach across the
    angle between their axes; a sun's discs whose radii reach across the
    distance between their centres, across the sun's direction. The other
    aims hold none of its rays."""
    axes = np.array([aim.axis for aim in aims]).reshape(-1, 3)
    if aims and aims[0].is_disc:
        centers = np.array([aim.center for aim in aims]).reshape(-1, 3)
        reach = np.array([aim.radius for aim in aims]) * (1.0 + 1e-9) + 1e-12
        out = []
        for i, aim in enumerate(aims):
            apart = centers - centers[i]
            apart -= (apart @ aim.axis)[:, None] * aim.axis
            out.append(np.flatnonzero(np.linalg.norm(apart, axis=1) <= reach + reach[i]))
        return out
    half = np.arccos(np.clip(np.array([aim.cos_max for aim in aims]) - _EDGE_TOLERANCE, -1.0, 1.0)) + 1e-9
    return [np.flatnonzero(np.arccos(np.clip(axes @ axes[i], -1.0, 1.0)) <= half + half[i])
            for i in range(len(aims))]


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
