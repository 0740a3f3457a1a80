"""What a surface does to light: glass, diffuse (with a Principled BSDF's specular layer or not), mirror."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Union

import numpy as np

from ..optics.principled import Layer
from .color import RGB, rgb
from .textures import Node


@dataclass
class Dielectric:
    """Clear or coloured glass, water, gems: refracts and reflects (Fresnel).

    ior           index of refraction relative to the surrounding medium: 1.33
                  water, 1.5 glass, 1.9 cubic zirconia, 2.41 diamond; below 1 for
                  an air bubble in water (1/1.33)
    color         tint applied at every reflection and refraction, as the
                  colour of Blender's Glass BSDF
    absorption    (3,) Beer-Lambert absorption coefficient, per metre, inside
                  (optics.absorption_from_color turns a colour at a distance
                  into one)
    abbe          Abbe number V_d: the IOR follows Cauchy's law through `ior`
                  at 587.6 nm with this dispersion (optics.cauchy_ior); 55
                  diamond, 58 crown glass, 33 cubic zirconia; inf for none
    """

    ior: float = 1.5
    color: RGB = field(default_factory=lambda: np.ones(3))
    absorption: RGB = field(default_factory=lambda: np.zeros(3))
    abbe: float = math.inf

    def __post_init__(self):
        self.color = rgb(self.color)
        self.absorption = rgb(self.absorption)


@dataclass
class Specular:
    """The specular layer of a Principled BSDF over a diffuse surface: a
    GGX lobe with Cycles' Fresnel, energy compensation and layering
    (optics/principled.py).

    roughness     0..1, the Principled BSDF's Roughness (alpha = roughness^2)
    ior           its IOR; 1 reflects nothing
    level         Specular IOR Level, 0.5 keeps the F0 of `ior`, 1 doubles it
    tint          (3,) Specular Tint, multiplying F0
    multiscatter  the node's Multiscatter GGX (its default); False for GGX
    """

    roughness: float = 0.5
    ior: float = 1.5
    level: float = 0.5
    tint: RGB = field(default_factory=lambda: np.ones(3))
    multiscatter: bool = True

    def __post_init__(self):
        self.tint = rgb(self.tint)

    def layer(self) -> Layer | None:
        """The layer ready to shade, or None where it reflects nothing."""
        return Layer.of(self.roughness, self.ior, self.level, self.tint, self.multiscatter)

    def diffuse_share(self, cos_v: np.ndarray) -> np.ndarray:
        """(n,) the share of the diffuse base the layer leaves toward view
        cosines `cos_v (n,)` (Layer.toward): what the caustic is times."""
        layer = self.layer()
        return np.ones(len(cos_v)) if layer is None else layer.toward(np.asarray(cos_v, dtype=np.float64))[1]


@dataclass
class Diffuse:
    """An opaque Lambertian surface, with the specular layer of a Principled
    BSDF over it if `specular` is given.

    albedo        (3,) diffuse reflectance (a Principled BSDF's Base Color)
    specular      the specular layer (None: Lambertian only)
    receiver      whether it collects caustics into an illumination map
    emission      (3,) radiance it gives off, W/(m^2 sr), as an Emission
                  shader's Color x Strength: seen, but lighting nothing else
    texture       the albedo from nodes (textures.py) at each shading point,
                  in place of `albedo`
    """

    albedo: RGB = field(default_factory=lambda: np.full(3, 0.8))
    specular: Optional[Specular] = None
    receiver: bool = True
    emission: RGB = field(default_factory=lambda: np.zeros(3))
    texture: Optional[Node] = None

    def __post_init__(self):
        self.albedo = rgb(self.albedo)
        self.emission = rgb(self.emission)


@dataclass
class Reflector:
    """A specular mirror or polished metal: every ray reflects, r = d - 2 (d.n) n
    about the shading normal, and its colour is multiplied by `color`.

    color         (3,) reflectance, the same at every angle (a metal's
                  Schlick/F82 rise toward grazing incidence is ignored)

    It is perfectly smooth: the add-on names glossy materials with a
    roughness above 0 in a warning, as it does rough glass.
    """

    color: RGB = field(default_factory=lambda: np.full(3, 0.9))

    def __post_init__(self):
        self.color = rgb(self.color)


Material = Union[Dielectric, Diffuse, Reflector]
