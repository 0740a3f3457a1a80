"""A Principled BSDF's layers over an opaque receiver's diffuse base, top
down, as Cycles stacks them (intern/cycles/kernel/svm/closure.h,
CLOSURE_BSDF_PRINCIPLED_ID; the sources each bpy ships, under
scripts/addons_core/cycles/source), each weighed toward the eye:

- the coat: a GGX dielectric of its own Roughness and IOR, its Fresnel the
  real dielectric curve, of weight c = Coat Weight, with Multiscatter GGX's
  gain from Blender 4.5 on (bsdf_microfacet_setup_fresnel_dielectric). Its
  Coat Tint t is seen along the view refracted into a coat of unit
  thickness, t_v = t^(1 / cos_t), cos_t = sqrt(1 - (1 - mu^2) / n_c^2)
  (Beer's law). What it leaves of the layers below, with A_c its Fresnel
  albedo toward the eye (principled.Layer):
    4.2   (1 - c A_c) mix(1, t_v, c), A_c of a smooth coat, F(mu);
    4.5   (1 - c A_c g) mix(1, t_v, c), g the gain's darkening;
    5.3   1 - c + c t_v (1 - A_c) per channel (bsdf_coat_setup, OpenPBR's slab);
- the metal, of weight Metallic m times what the coat leaves: an F82-tint
  conductor of Base Color and Specular Tint (metal.py) with the base's
  Roughness, with Multiscatter GGX's gain 1 + F_ms (1 - E) / E, F_ms of the
  F82 curve's mean (metal.f82_fss); it leaves the rest 1 - m;
- the specular layer (principled.Layer), and the diffuse base under it.

Emission shows under the coat, not under the metal. Every weight depends on
the view alone, as Cycles' do: the light that arrives through the coat,
the caustic's included, is not dimmed by it on its way in."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from ..util.jit import kernel
from ..util.rows import contiguous
from ..util.vectors import DIVISION_FLOOR
from .metal import f82_b, f82_fss
from .principled import MIN_ALPHA, Layer, albedo_curves, curve_at1, curve_node1, multiscatter_gain1
from .specular import fresnel_dielectric

# Cycles' CLOSURE_WEIGHT_CUTOFF: a closure of less weight is not made.
WEIGHT_CUTOFF = 1e-5
# The Blenders whose layering Stack follows (Specular.layering).
LAYERINGS = ("4.2", "4.5", "5.3")


class Seen(NamedTuple):
    """A stack's weights toward the eye at n points, each (n,3).

    layer     the specular layer's (principled.Lobe.gain)
    metal     the metal's (Lobe.metal); base its F0, the Base Color in 0..1
              (Lobe.base); b its F82-tint factor (Lobe.b)
    coat      the coat's lobe's
    diffuse   the diffuse base's share: what its colour, and the caustic, are times
    emission  what the coat leaves of the surface's emission
    """

    layer: np.ndarray
    metal: np.ndarray
    base: np.ndarray
    b: np.ndarray
    coat: np.ndarray
    diffuse: np.ndarray
    emission: np.ndarray


@dataclass
class Stack:
    """One Principled receiver's layers, ready to shade.

    layer         its specular layer, None where it reflects nothing (IOR 1)
    alpha         GGX alpha of the layer and the metal
    metallic      0..1, Metallic;  f82 (3,) the metal's Specular Tint
    multiscatter  Multiscatter GGX: the metal's gain
    e_curve, e_avg  the lobe's albedo without Fresnel (principled.albedo_curves)
    coat          the coat's layer, None without one or at Coat IOR 1
    coat_weight   0..1;  coat_ior >= 1;  coat_tint (3,)
    layering      the Blender whose layering it follows (LAYERINGS)
    """

    layer: Layer | None
    alpha: float
    metallic: float
    f82: np.ndarray
    multiscatter: bool
    e_curve: np.ndarray
    e_avg: float
    coat: Layer | None
    coat_weight: float
    coat_ior: float
    coat_tint: np.ndarray
    layering: str

    @staticmethod
    def of(inputs) -> Stack | None:
        """The stack of a Principled receiver's `inputs` (scene.materials.Specular),
        None where no layer reflects anything."""
        layer = Layer.of(inputs.roughness, inputs.ior, inputs.level, inputs.tint, inputs.multiscatter)
        metallic = float(inputs.metallic) if inputs.metallic > WEIGHT_CUTOFF else 0.0
        coat = inputs.coat if inputs.coat is not None and inputs.coat.weight > WEIGHT_CUTOFF else None
        if layer is None and not metallic and coat is None:
            return None
        e_curve, _, e_avg = albedo_curves(float(inputs.roughness), 1.5)
        coat_layer = None if coat is None else Layer.of(coat.roughness, coat.ior, 0.5, np.ones(3),
                                                         inputs.layering != "4.2")
        return Stack(layer, max(float(inputs.roughness) ** 2, MIN_ALPHA), metallic,
                     np.minimum(np.asarray(inputs.tint, dtype=np.float64), 1.0), bool(inputs.multiscatter), e_curve,
                     e_avg, coat_layer, 0.0 if coat is None else float(coat.weight),
                     1.0 if coat is None else float(coat.ior),
                     np.ones(3) if coat is None else np.asarray(coat.tint, dtype=np.float64), inputs.layering)

    def coat_toward(self, cos_v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the coat lobe's weight (n,3), what the coat leaves of the layers
        under it (n,3)) toward view cosines `cos_v (n,)`: c times its
        multiple-scattering gain, and the module's layering of `layering`."""
        n = len(cos_v)
        if self.coat_weight == 0.0:
            return np.zeros((n, 3)), np.ones((n, 3))
        c, mu = self.coat_weight, np.clip(cos_v, 0.0, 1.0)
        tint = np.ones((n, 3))
        if not np.all(self.coat_tint == 1.0):
            cos_t = np.sqrt(1.0 - (1.0 - mu * mu) / self.coat_ior ** 2)
            tint = self.coat_tint[None, :] ** (1.0 / cos_t[:, None])
        if self.coat is None:
            lobe, albedo = np.zeros((n, 3)), np.zeros(n)
        else:
            gain, left = self.coat.toward(cos_v)
            lobe = c * gain
            if self.layering == "4.2":
                albedo = fresnel_dielectric(mu, 1.0 / self.coat_ior)
            elif self.layering == "4.5":
                albedo = 1.0 - left
            else:
                albedo = 1.0 - replace(self.coat, multiscatter=False).toward(cos_v)[1]
        if self.layering == "5.3":
            return lobe, np.clip(1.0 - c + c * tint * (1.0 - albedo)[:, None], 0.0, 1.0)
        return lobe, (1.0 - c * albedo)[:, None] * (1.0 + c * (tint - 1.0))

    def toward(self, cos_v: np.ndarray, base: np.ndarray) -> Seen:
        """The weights toward view cosines `cos_v (n,)` over Base Colors `base (n,3)`."""
        cos_v = contiguous(cos_v, np.float64)
        n = len(cos_v)
        coat, above = self.coat_toward(cos_v)
        f0 = np.clip(base, 0.0, 1.0)
        b = f82_b(f0, self.f82)
        metal = np.zeros((n, 3))
        if self.metallic:
            metal = np.ones((n, 3))
            if self.multiscatter:
                _metal_gains(cos_v, self.e_curve, self.e_avg, contiguous(f82_fss(f0, b), np.float64), metal)
            metal *= self.metallic * above
        rest = (1.0 - self.metallic) * above
        if self.layer is None:
            layer, diffuse = np.zeros((n, 3)), rest
        else:
            gain, share = self.layer.toward(cos_v)
            layer, diffuse = gain * rest, share[:, None] * rest
        return Seen(layer, metal, f0, b, coat, diffuse, above)


@kernel("void(f8[::1], f8[::1], f8, f8[:, ::1], f8[:, ::1])")
def _metal_gains(cos_v, e_curve, e_avg, fss, gain):
    """gain[i] = multiscatter_gain1 of each channel of `fss (n,3)`, E at
    cos_v[i] from `e_curve` (floored at DIVISION_FLOOR)."""
    k = len(e_curve)
    for i in range(len(cos_v)):
        mu = min(max(cos_v[i], 0.0), 1.0)
        j = curve_node1(k, mu)
        e = curve_at1(e_curve[j], e_curve[j + 1], j, k, mu)
        missing = (1.0 - e) / max(e, DIVISION_FLOOR)
        for c in range(3):
            gain[i, c] = multiscatter_gain1(fss[i, c], e_avg, missing)
