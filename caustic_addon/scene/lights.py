"""Blender's lamps and world, in Blender's units (emission/radiometry.py
turns them into radiometry).

Every lamp has a `visibility`: the eye rays that see the lamp itself
(passes/seen_lamps.py), by Blender's Ray Visibility of the light object:
camera, glossy and transmission (LAMP_VISIBILITY, Blender's default, hides
it from the camera)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal, Optional, Union

import numpy as np

from .color import RGB, rgb
from .visibility import LAMP_VISIBILITY, Visibility


def _unit(vector) -> np.ndarray:
    v = np.asarray(vector, dtype=np.float64).reshape(3)
    return v / np.linalg.norm(v)


@dataclass
class PointLight:
    """Blender's point lamp: `power` W, so radiant intensity
    I = color * power / (4 pi) W/sr in every direction.

    radius        Blender's Radius (shadow_soft_size), m; 0 for a point
    soft_falloff  Blender's Soft Falloff (on by default): the lamp is a disc
                  of `radius` that faces each point it lights; off, a sphere
    """

    position: np.ndarray
    power: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Point"
    radius: float = 0.0
    soft_falloff: bool = True
    visibility: Visibility = LAMP_VISIBILITY

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        self.color = rgb(self.color)


@dataclass
class SpotLight:
    """Blender's spot lamp: a point lamp masked to a cone.

    direction     unit axis of the cone, pointing where the light goes
    spot_size     full cone angle, radians (Blender's Spot Size)
    blend         softness of the cone's edge, 0..1 (Blender's Blend)
    radius, soft_falloff   as a point lamp's
    """

    position: np.ndarray
    direction: np.ndarray
    power: float
    spot_size: float = math.radians(45.0)
    blend: float = 0.15
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Spot"
    radius: float = 0.0
    soft_falloff: bool = True
    visibility: Visibility = LAMP_VISIBILITY

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        self.direction = _unit(self.direction)
        self.color = rgb(self.color)


@dataclass
class SunLight:
    """Blender's sun: parallel light of irradiance `strength` W/m^2 on a
    surface facing it.

    direction     unit vector the light travels along (Blender's -Z of the lamp)
    angle         Blender's Angle: the full angle the sun's disc spans, radians
    of_world      the sun stands for part of the world's light (its sun, a
                  region of its sky), which the render's Energy does not scale
    """

    direction: np.ndarray
    strength: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Sun"
    angle: float = 0.0
    visibility: Visibility = LAMP_VISIBILITY
    of_world: bool = False

    def __post_init__(self):
        self.direction = _unit(self.direction)
        self.color = rgb(self.color)


@dataclass
class AreaLight:
    """Blender's area lamp: a one-sided Lambertian emitter of `power` W.

    center        (3,) world
    axis_x/axis_y (3,) world half-extents along the lamp's local x and y,
                  the object's scale applied: Size / 2 and Size Y / 2
    direction     unit normal it emits along (Blender's -Z of the lamp)
    shape         'RECTANGLE' (Square, Rectangle) or 'ELLIPSE' (Disk,
                  Ellipse), inscribed in the rectangle
    spread        Blender's Spread: the full angle of the cone it emits into,
                  radians; pi is Lambertian, 0 a parallel beam
    """

    center: np.ndarray
    axis_x: np.ndarray
    axis_y: np.ndarray
    direction: np.ndarray
    power: float
    shape: Literal["RECTANGLE", "ELLIPSE"] = "RECTANGLE"
    spread: float = math.pi
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Area"
    visibility: Visibility = LAMP_VISIBILITY

    def __post_init__(self):
        self.center = np.asarray(self.center, dtype=np.float64).reshape(3)
        self.axis_x = np.asarray(self.axis_x, dtype=np.float64).reshape(3)
        self.axis_y = np.asarray(self.axis_y, dtype=np.float64).reshape(3)
        self.direction = _unit(self.direction)
        self.color = rgb(self.color)

    @property
    def area(self) -> float:
        """m^2 of the emitting surface."""
        rectangle = 4.0 * float(np.linalg.norm(np.cross(self.axis_x, self.axis_y)))
        return rectangle * (math.pi / 4.0 if self.shape == "ELLIPSE" else 1.0)

    @property
    def position(self) -> np.ndarray:
        return self.center


@dataclass
class MeshLight:
    """A mesh's faces with an Emission shader (or a Principled BSDF's
    emission): each triangle a Lambertian emitter of radiance `radiance`
    from both sides, as Cycles' emission closure (kernel/closure/emissive.h,
    |cos|), so a side of area A sends pi A L. The renderer makes one of each
    emissive object (emission/mesh_lights.py); the object itself stays in the
    scene, seen and casting shadows.

    triangles     (n,3,3) world corners of the emitting faces
    radiance      (3,) W/(m^2 sr): the shader's Color x Strength
    sides         (along, against) each face's winding normal: whether
                  that side's light leaves the mesh; a closed mesh's inner
                  side lights only what it holds, and the pass from the
                  lamps leaves it out (emission/mesh_lights.py)
    """

    triangles: np.ndarray
    radiance: RGB
    name: str = "Emission"
    visibility: Visibility = LAMP_VISIBILITY
    sides: tuple[bool, bool] = (True, True)

    def __post_init__(self):
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.float64).reshape(-1, 3, 3)
        self.radiance = rgb(self.radiance)

    @cached_property
    def areas(self) -> np.ndarray:
        """(n,) m^2 of each triangle."""
        t = self.triangles
        return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)

    @cached_property
    def area_cdf(self) -> np.ndarray:
        """(n,) the triangles' running share of the light's area, for sampling by area."""
        return np.cumsum(self.areas) / max(float(self.areas.sum()), 1e-300)

    @cached_property
    def position(self) -> np.ndarray:
        """(3,) the emitting area's centroid."""
        weights = self.areas
        return (weights @ self.triangles.mean(axis=1)) / max(float(weights.sum()), 1e-300)

    @cached_property
    def radius(self) -> float:
        """How far the faces reach from `position`, m."""
        return float(np.linalg.norm(self.triangles.reshape(-1, 3) - self.position, axis=1).max())


Light = Union[PointLight, SpotLight, SunLight, AreaLight, MeshLight]


@dataclass
class World:
    """The light from every direction that meets nothing, what Cycles'
    world shader gives, W/(m^2 sr): `color (3,)` everywhere, or times an
    `environment (h, w, 3)` lat-long image in Cycles' equirectangular
    mapping (row 0 at the top, +Z; column u = 0.5 - atan2(y, x) / (2 pi),
    +X at the middle). A render keeps what it derives from the world while
    the same environment array comes back (emission/kept_worlds.py), so an
    environment once rendered is not written into: a changed one is a new
    array."""

    color: RGB = field(default_factory=lambda: np.zeros(3))
    environment: Optional[np.ndarray] = None

    def __post_init__(self):
        self.color = rgb(self.color)
        if self.environment is not None:
            self.environment = np.ascontiguousarray(self.environment, dtype=np.float64)

    @property
    def is_black(self) -> bool:
        return not np.any(self.color > 0) or (self.environment is not None and not np.any(self.environment > 0))
