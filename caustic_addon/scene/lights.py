"""Blender's lamps, in Blender's units (emission/radiometry.py turns them into radiometry)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Union

import numpy as np

from .color import RGB, rgb


@dataclass
class PointLight:
    """Blender's point lamp of radius 0: power in W, radiant intensity
    I = color * power / (4 pi) W/sr in every direction (see units.py)."""

    position: np.ndarray
    power: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Point"

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        self.color = rgb(self.color)


@dataclass
class SpotLight:
    """Blender's spot lamp: a point lamp masked to a cone.

    direction     unit axis of the cone, pointing where the light goes
    spot_size     full cone angle, radians (Blender's Spot Size)
    blend         softness of the cone's edge, 0..1 (Blender's Blend)
    """

    position: np.ndarray
    direction: np.ndarray
    power: float
    spot_size: float = math.radians(45.0)
    blend: float = 0.15
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Spot"

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        d = np.asarray(self.direction, dtype=np.float64).reshape(3)
        self.direction = d / np.linalg.norm(d)
        self.color = rgb(self.color)


@dataclass
class SunLight:
    """Blender's sun: parallel light of irradiance `strength` W/m^2 on a
    surface facing it.

    direction     unit vector the light travels along (Blender's -Z of the lamp)
    """

    direction: np.ndarray
    strength: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Sun"

    def __post_init__(self):
        d = np.asarray(self.direction, dtype=np.float64).reshape(3)
        self.direction = d / np.linalg.norm(d)
        self.color = rgb(self.color)


Light = Union[PointLight, SpotLight, SunLight]
