"""What a surface does to light: glass, diffuse (with a Principled BSDF's specular layer or not), mirror."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Union

import numpy as np

from ..optics.microfacet import alpha_of
from ..optics.layers import Stack
from .color import RGB, rgb
from .textures import Node


@dataclass
class Dielectric:
    """Clear or coloured glass, water, gems: refracts and reflects (Fresnel).

    ior                index of refraction relative to the surrounding medium:
                       1.33 water, 1.5 glass, 1.9 cubic zirconia, 2.41
                       diamond; below 1 for an air bubble in water (1/1.33)
    reflection_tint    (3,) colour of every reflection, total internal ones
                       included: a Glass BSDF's Color, white for a Principled
                       BSDF (Cycles' Fresnel reflection_tint, svm/closure.h)
    transmission_tint  (3,) colour of every refraction: a Glass BSDF's Color,
                       the square root of a Principled BSDF's Base Color, so
                       that a thin shell crossed twice takes the colour once
    absorption         (3,) Beer-Lambert absorption coefficient, per metre,
                       inside (optics.absorption_from_color turns a colour at
                       a distance into one)
    abbe               Abbe number V_d: the IOR follows Cauchy's law through
                       `ior` at 587.6 nm with this dispersion
                       (optics.cauchy_ior); 55 diamond, 58 crown glass, 33
                       cubic zirconia; inf for none
    roughness          Blender's Roughness, 0..1: light scatters about GGX
                       microfacet normals of width alpha = roughness^2
                       (optics.microfacet); 0 is a perfectly smooth interface
    multiscatter       True for Blender's Multiscatter GGX (the default),
                       which gives back the light a single microfacet bounce
                       loses (optics.multiscatter); False for plain GGX
    fresnel            False for a Refraction BSDF, which reflects nothing:
                       every ray refracts whole, and ends under total
                       internal reflection (Cycles' MicrofacetFresnel::NONE)
    """

    ior: float = 1.5
    reflection_tint: RGB = field(default_factory=lambda: np.ones(3))
    transmission_tint: RGB = field(default_factory=lambda: np.ones(3))
    absorption: RGB = field(default_factory=lambda: np.zeros(3))
    abbe: float = math.inf
    roughness: float = 0.0
    multiscatter: bool = True
    fresnel: bool = True

    def __post_init__(self):
        self.reflection_tint = rgb(self.reflection_tint)
        self.transmission_tint = rgb(self.transmission_tint)
        self.absorption = rgb(self.absorption)

    @property
    def smooth(self) -> bool:
        """Rendered as a perfectly smooth interface: Roughness 0, or so low
        that Cycles takes it for one (optics.microfacet.alpha_of)."""
        return bool(alpha_of(self.roughness) == 0.0)


@dataclass
class Coat:
    """The coat of a Principled BSDF: a clear GGX dielectric over the rest
    (optics/layers.py).

    weight        0..1, Coat Weight
    roughness     0..1, Coat Roughness (alpha = roughness^2)
    ior           >= 1, Coat IOR
    tint          (3,) Coat Tint: the colour of what is seen through it, at normal incidence
    """

    weight: float = 1.0
    roughness: float = 0.03
    ior: float = 1.5
    tint: RGB = field(default_factory=lambda: np.ones(3))

    def __post_init__(self):
        self.tint = rgb(self.tint)


@dataclass
class Specular:
    """The layers of a Principled BSDF over a diffuse surface: a GGX
    specular layer with Cycles' Fresnel, energy compensation and layering
    (optics/principled.py), a metal and a coat (optics/layers.py).

    roughness     0..1, the Principled BSDF's Roughness (alpha = roughness^2)
    ior           its IOR; 1 reflects nothing
    level         Specular IOR Level, 0.5 keeps the F0 of `ior`, 1 doubles it
    tint          (3,) Specular Tint, multiplying F0, and the metal's tint at 82 degrees
    multiscatter  the node's Multiscatter GGX (its default); False for GGX
    metallic      0..1, Metallic: that share of the surface is a metal of its Base Color
    coat          the coat over it all, or None
    layering      the Blender whose Cycles layers them: "4.2", "4.5" or "5.3"
                  (optics/layers.py; later ones layer as 5.3)
    """

    roughness: float = 0.5
    ior: float = 1.5
    level: float = 0.5
    tint: RGB = field(default_factory=lambda: np.ones(3))
    multiscatter: bool = True
    metallic: float = 0.0
    coat: Coat | None = None
    layering: str = "5.3"

    def __post_init__(self):
        self.tint = rgb(self.tint)

    def stack(self) -> Stack | None:
        """The layers ready to shade, or None where none reflects anything."""
        return Stack.of(self)

    def diffuse_share(self, cos_v: np.ndarray) -> np.ndarray:
        """(n,3) the share of the diffuse base the layers leave toward view
        cosines `cos_v (n,)` (Stack.toward): what the caustic is times."""
        cos_v = np.asarray(cos_v, dtype=np.float64)
        stack = self.stack()
        return np.ones((len(cos_v), 3)) if stack is None else stack.toward(cos_v, np.zeros((len(cos_v), 3))).diffuse


@dataclass
class Diffuse:
    """An opaque Lambertian surface, with the specular layer of a Principled
    BSDF over it if `specular` is given.

    albedo        (3,) diffuse reflectance (a Principled BSDF's Base Color)
    specular      the specular layer (None: Lambertian only)
    receiver      whether it collects caustics into an illumination map
    emission      (3,) radiance it gives off, W/(m^2 sr), as an Emission
                  shader's Color x Strength, from both sides: seen, and
                  lighting the scene and casting caustics as a lamp
                  (scene.MeshLight)
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
    """A mirror or a metal: every ray reflects, r = d - 2 (d.n) n about the
    shading normal (smooth) or about a GGX microfacet normal (rough), and
    its colour is multiplied by `color`.

    color         (3,) reflectance, the same at every angle (a metal's
                  Schlick/F82 rise toward grazing incidence is ignored)
    roughness     Blender's Roughness, 0..1, as Dielectric's
    multiscatter  Multiscatter GGX (True) or plain GGX, as Dielectric's
    """

    color: RGB = field(default_factory=lambda: np.full(3, 0.9))
    roughness: float = 0.0
    multiscatter: bool = True

    def __post_init__(self):
        self.color = rgb(self.color)

    @property
    def smooth(self) -> bool:
        """Rendered as a perfectly smooth interface: Roughness 0, or so low
        that Cycles takes it for one (optics.microfacet.alpha_of)."""
        return bool(alpha_of(self.roughness) == 0.0)


Material = Union[Dielectric, Diffuse, Reflector]
