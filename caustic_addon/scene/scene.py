"""Objects, lamps and a camera: the scene a render takes."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .camera import Camera
from .color import RGB, rgb
from .geometry import Copies, Mesh
from .lights import Light, World
from .materials import Dielectric, Diffuse, Material, Reflector
from .visibility import Visibility


@dataclass
class Instances:
    """One mesh under many affine, invertible transforms: `mesh` in object
    space, `transforms (k,4,4)` object to world. Embree keeps one BVH of the
    mesh for all of them (tracing.embree.Instances), and the first copy
    speaks for all where a body is analysed (holes, winding). The object's
    own mesh, the copies in world space, is made only where something reads
    it (geometry.Copies): a render places the copies as it reads them
    (tracing/triangles.py)."""

    mesh: Mesh
    transforms: np.ndarray

    def __post_init__(self):
        self.transforms = np.ascontiguousarray(self.transforms, dtype=np.float64).reshape(-1, 4, 4)


@dataclass
class Object:
    """A mesh with one material. `body` names the closed surface the mesh is
    part of when one surface has several materials: objects with the same
    body are one mesh for inside and outside (whether it is closed, which way
    it faces, which glass a ray is in); None, the object is its own body.
    `instances`, where given, is what the mesh was made of: a mesh in object
    space under its object's transform, or an instancer's instances of one
    mesh (Object.instanced); the accelerator keeps that mesh's BVH between
    renders."""

    name: str
    mesh: Mesh
    material: Material
    visibility: Visibility = field(default_factory=Visibility)
    body: Optional[str] = None
    instances: Optional[Instances] = None

    @classmethod
    def instanced(cls, name: str, local: Mesh, transforms: np.ndarray, material: Material,
                  visibility: Visibility = Visibility(), body: Optional[str] = None) -> "Object":
        """The object whose mesh is `local` (object space) under each of
        `transforms (k,4,4)`: Mesh.instanced for k = 1, else its copies made
        only where they are read (geometry.Copies), which hold no corner
        normals."""
        instances = Instances(local, transforms)
        mesh = (local.instanced(instances.transforms) if len(instances.transforms) == 1
                else Copies(local, instances.transforms))
        return cls(name, mesh, material, visibility, body, instances)

    @property
    def copies(self) -> int:
        """How many equal copies of one mesh its mesh is made of."""
        return 1 if self.instances is None else len(self.instances.transforms)

    @property
    def body_name(self) -> str:
        return self.body if self.body is not None else self.name

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

    @property
    def emitting(self) -> list[Object]:
        """The objects whose material emits light (Diffuse.emission): lamps too (scene.MeshLight)."""
        return [o for o in self.objects if np.any(getattr(o.material, "emission", 0.0) > 0.0)]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (3,), hi (3,)) of all geometry."""
        bounds = [o.mesh.bounds for o in self.objects if o.mesh.triangle_count] or [(np.zeros(3), np.zeros(3))]
        return np.min([lo for lo, _ in bounds], axis=0), np.max([hi for _, hi in bounds], axis=0)

    def extent(self) -> float:
        """Diagonal of the geometry's bounding box: the length the epsilons scale with."""
        lo, hi = self.bounds()
        return float(max(np.linalg.norm(hi - lo), 1e-12))
