"""Per-object material tables, so both passes look materials up by object
index in one numpy gather instead of a Python loop per hit."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..optics.dispersion import cauchy_ior
from ..optics.microfacet import alpha_of
from ..optics.multiscatter import ALBEDO_COSINES, average_albedo, single_scatter_albedo
from ..optics.layers import Stack
from ..optics.principled import Lobe
from ..optics.spectrum import bands
from .materials import Diffuse
from .scene import Object
from .textures import Node, SurfacePoints, as_color


@dataclass
class Materials:
    """Indexed by object index (m objects).

    dielectric (m,) bool        reflector (m,) bool        receiver (m,) bool
    specular_surface (m,) bool  dielectric or reflector: rays scatter there
    ior (m,)
    reflection_tint (m,3)       each reflection's colour: glass's, or a reflector's reflectance
    transmission_tint (m,3)     each refraction's colour (0 at reflectors)
    energy_tint (m,3)           the colour F_ss that Multiscatter GGX gives back
                                energy in: glass's transmission tint, a
                                reflector's reflectance (Cycles' bsdf_microfacet.h)
    fresnel (m,) bool           False where every ray refracts whole (Refraction BSDF)
    absorption (m,3) per metre
    albedo (m,3)
    emission (m,3) radiance a surface gives off
    ior_bands (m,K)             IOR in each of the K wavelength bands
    band_weights (K,3)          each band's RGB share (spectrum.Bands)
    stacks                      object index -> its Principled layers (optics.layers.Stack)
    alpha (m,)                  GGX width, roughness^2; 0 where smooth
    facet_albedo (m,2,k)        single-scattering albedo E at the k cosines
                                of multiscatter.albedo_cosines, entering
                                ([:, 0]) and leaving ([:, 1]); 1 where no
                                energy is given back (smooth, or plain GGX)
    facet_albedo_avg (m,2)      its cosine-weighted mean E_avg
    textures                    object index -> the nodes of its albedo

    K is 1, with ior_bands = ior, unless a dielectric disperses.
    """

    dielectric: np.ndarray
    reflector: np.ndarray
    receiver: np.ndarray
    ior: np.ndarray
    reflection_tint: np.ndarray
    transmission_tint: np.ndarray
    energy_tint: np.ndarray
    fresnel: np.ndarray
    absorption: np.ndarray
    albedo: np.ndarray
    emission: np.ndarray
    ior_bands: np.ndarray
    band_weights: np.ndarray
    alpha: np.ndarray
    facet_albedo: np.ndarray
    facet_albedo_avg: np.ndarray
    stacks: dict[int, Stack] = field(default_factory=dict)
    textures: dict[int, Node] = field(default_factory=dict)

    @property
    def band_count(self) -> int:
        return len(self.band_weights)

    @staticmethod
    def of(objects: list[Object], band_count: int = 1) -> "Materials":
        """The tables for `objects`, with `band_count` wavelength bands if
        any of them disperses."""
        def column(name, default):
            return np.array([getattr(o.material, name, default) for o in objects], dtype=np.float64)

        def rgb_column(name, default):
            return column(name, np.full(3, default)).reshape(-1, 3)

        ior, abbe = column("ior", 1.0), column("abbe", np.inf)
        spectral = bands(band_count if np.isfinite(abbe).any() else 1)
        alpha = alpha_of(column("roughness", 0.0))
        facet_albedo = np.array([_facet_albedo(o, a) for o, a in zip(objects, alpha)]).reshape(-1, 2, ALBEDO_COSINES)
        dielectric = np.array([o.is_transparent for o in objects], dtype=bool)
        reflectance = rgb_column("color", 1.0)
        reflection_tint = np.where(dielectric[:, None], rgb_column("reflection_tint", 1.0), reflectance)
        transmission_tint = rgb_column("transmission_tint", 0.0)
        return Materials(
            dielectric=dielectric,
            reflector=np.array([o.is_reflector for o in objects], dtype=bool),
            receiver=np.array([o.is_receiver for o in objects], dtype=bool),
            ior=ior,
            reflection_tint=reflection_tint,
            transmission_tint=transmission_tint,
            energy_tint=np.where(dielectric[:, None], transmission_tint, reflection_tint),
            fresnel=np.array([getattr(o.material, "fresnel", True) for o in objects], dtype=bool),
            absorption=rgb_column("absorption", 0.0),
            albedo=rgb_column("albedo", 0.0),
            emission=rgb_column("emission", 0.0),
            ior_bands=cauchy_ior(ior[:, None], abbe[:, None], spectral.wavelengths[None, :]),
            band_weights=spectral.weights,
            alpha=alpha,
            facet_albedo=facet_albedo,
            facet_albedo_avg=average_albedo(facet_albedo),
            textures={index: o.material.texture for index, o in enumerate(objects)
                      if getattr(o.material, "texture", None) is not None},
            stacks=_stacks(objects),
        )

    def albedo_at(self, obj: np.ndarray, triangle: np.ndarray, u: np.ndarray, v: np.ndarray,
                  points: np.ndarray) -> np.ndarray:
        """(n,3) albedo at surface points of objects `obj (n,)`: a textured
        object's nodes at its `triangle (n,)` (index in its own mesh),
        barycentrics `u, v (n,)` and world `points (n,3)`; else its colour."""
        albedo = np.take(self.albedo, obj, axis=0)
        for index, texture in self.textures.items():
            rows = np.flatnonzero(obj == index)
            if len(rows):
                at = SurfacePoints(np.take(points, rows, axis=0), np.take(triangle, rows), np.take(u, rows),
                                   np.take(v, rows))
                albedo[rows] = as_color(texture.evaluate(at))
        return albedo

    def layers_at(self, obj: np.ndarray, cos_v: np.ndarray, base: np.ndarray) -> tuple[list[Lobe], np.ndarray,
                                                                                       np.ndarray]:
        """(lobes, diffuse (n,3), emission (n,3)) at points of objects
        `obj (n,)` seen at cosines `cos_v (n,)` from their normals, over
        their Base Colors `base (n,3)`: the GGX lobes of their Principled
        layers there (the specular layer with the metal, and the coat where
        a point has one; none without layers), the share of the diffuse
        base they leave, and of the emission (layers.Stack.toward; 1 without)."""
        n = len(obj)
        diffuse, emission = np.ones((n, 3)), np.ones((n, 3))
        here = {index: rows for index in self.stacks if len(rows := np.flatnonzero(obj == index))}
        if not here:
            return [], diffuse, emission
        lobe, coat = (Lobe(np.zeros(n, dtype=bool), np.zeros((n, 3)), np.full(n, 1.5), np.ones(n), np.zeros((n, 3)))
                      for _ in range(2))
        for index, rows in here.items():
            stack = self.stacks[index]
            seen = stack.toward(cos_v[rows], np.take(base, rows, axis=0))
            lobe.active[rows] = stack.layer is not None or stack.metallic > 0.0
            lobe.alpha[rows], lobe.gain[rows] = stack.alpha, seen.layer
            lobe.metal[rows], lobe.base[rows], lobe.b[rows] = seen.metal, seen.base, seen.b
            if stack.layer is not None:
                lobe.f0[rows], lobe.eta[rows] = stack.layer.f0, stack.layer.eta
            if stack.coat is not None:
                coat.active[rows], coat.alpha[rows], coat.gain[rows] = True, stack.coat.alpha, seen.coat
                coat.f0[rows], coat.eta[rows] = stack.coat.f0, stack.coat.eta
            diffuse[rows], emission[rows] = seen.diffuse, seen.emission
        return [part for part in (lobe, coat) if part.active.any()], diffuse, emission

    @property
    def specular_surface(self) -> np.ndarray:
        return self.dielectric | self.reflector

    def medium_ior(self, medium: np.ndarray) -> np.ndarray:
        """(n,) the index of refraction of the media `medium (n,)` (object
        indices; MISS, -1, the air): 1 in the air."""
        return np.where(medium < 0, 1.0, np.take(self.ior, np.maximum(medium, 0)))


# The numba type of the Materials fields kernels take by name
# (util.jit.named_kernel).
MATERIAL_TYPES = {"dielectric": "b1[::1]", "reflector": "b1[::1]", "reflection_tint": "f8[:, ::1]",
                  "transmission_tint": "f8[:, ::1]"}


def _stacks(objects: list[Object]) -> dict[int, Stack]:
    """Object index -> the Principled layers of each diffuse object whose layers reflect."""
    stacks = {}
    for index, o in enumerate(objects):
        inputs = o.material.specular if isinstance(o.material, Diffuse) else None
        stack = None if inputs is None else inputs.stack()
        if stack is not None:
            stacks[index] = stack
    return stacks


def _facet_albedo(obj: Object, alpha: float) -> np.ndarray:
    """(2,k) the single-scattering albedo of `obj`'s rough surface entering
    and leaving it (multiscatter.single_scatter_albedo, at its IOR at
    587.6 nm); ones where nothing is given back: smooth, plain GGX or not a
    caster."""
    if alpha <= 0.0 or not obj.is_caster or not obj.material.multiscatter:
        return np.ones((2, ALBEDO_COSINES))
    if obj.is_reflector:
        return np.tile(single_scatter_albedo(float(alpha), None), (2, 1))
    ior = float(obj.material.ior)
    return np.stack([single_scatter_albedo(float(alpha), 1.0 / ior), single_scatter_albedo(float(alpha), ior)])
