"""The casters that lamps aim at, as bounding spheres, and the cones that hold them."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene import Light, SpotLight


@dataclass
class Sphere:
    """A bounding sphere: centre (3,), radius."""

    center: np.ndarray
    radius: float

    @staticmethod
    def around(points: np.ndarray) -> "Sphere":
        center = 0.5 * (points.min(axis=0) + points.max(axis=0))
        return Sphere(center, float(np.linalg.norm(points - center, axis=1).max()))


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
