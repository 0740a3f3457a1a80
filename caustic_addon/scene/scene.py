"""Objects, lamps and a camera: the scene a render takes."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .camera import Camera
from .color import RGB, rgb
from .geometry import Mesh
from .lights import Light, World
from .materials import Dielectric, Diffuse, Material, Reflector


@dataclass
class Object:
    name: str
    mesh: Mesh
    material: Material

    @property
    def is_transparent(self) -> bool:
        return isinstance(self.material, Dielectric)

    @property
    def is_reflector(self) -> bool:
        return isinstance(self.material, Reflector)

    @property
    def is_caster(self) -> bool:
        """Casts caustics: a specular surface, transparent or reflecting."""
        return isinstance(self.material, (Dielectric, Reflector))

    @property
    def is_receiver(self) -> bool:
        return isinstance(self.material, Diffuse) and self.material.receiver


@dataclass
class Scene:
    """objects, lamps and a camera; `ambient` (3,) the paper's ambient term,
    radiance times albedo that every opaque surface adds; `world` the light
    from every direction, seen where eye rays leave and lighting surfaces,
    as Cycles' world."""

    objects: list[Object]
    lights: list[Light]
    camera: Camera
    ambient: RGB = field(default_factory=lambda: np.zeros(3))
    world: World = field(default_factory=World)

    def __post_init__(self):
        self.ambient = rgb(self.ambient)

    @property
    def casters(self) -> list[Object]:
        """The objects that cast caustics: dielectrics and reflectors."""
        return [o for o in self.objects if o.is_caster]

    @property
    def receivers(self) -> list[Object]:
        return [o for o in self.objects if o.is_receiver]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (3,), hi (3,)) of all geometry."""
        pts = np.concatenate([o.mesh.vertices for o in self.objects]) if self.objects else np.zeros((1, 3))
        return pts.min(axis=0), pts.max(axis=0)

    def extent(self) -> float:
        """Diagonal of the geometry's bounding box: the length the epsilons scale with."""
        lo, hi = self.bounds()
        return float(max(np.linalg.norm(hi - lo), 1e-12))
