"""The Fresnel term of a Principled BSDF's metal, as Cycles gives it
(intern/cycles/kernel/closure/bsdf_util.h, fresnel_f82 and
fresnel_f82tint_B; bsdf_microfacet.h, bsdf_microfacet_setup_fresnel_f82_tint):
the F82-tint model of Kutz, Hasan and Edmondson 2021, "Novel aspects of the
Adobe Standard Material". Its reflectance at normal incidence F0 is the
Base Color; the Specular Tint scales Schlick's curve at cos = 1/7 (about
82 degrees), where real metals dip below it.

    F(mu) = clamp(F0 + (1 - F0)(1 - mu)^5 - b mu (1 - mu)^6, 0, 1)

with b chosen so that F(1/7) = F_Schlick(1/7) x tint."""

from __future__ import annotations

import numpy as np

from ..util.jit import inline

# 1 - cos at the angle the tint sets, 82.8 degrees (cos = 1/7).
_AT_82 = 6.0 / 7.0


def f82_b(f0: np.ndarray, tint: np.ndarray) -> np.ndarray:
    """(..., 3) the factor b of the F82-tint curve of reflectance `f0 (..., 3)`
    and Specular Tint `tint (3,)` (clamped to 1, as closure.h does):
    b = F_Schlick(1/7) 7 / (6/7)^6 (1 - tint)."""
    schlick = f0 + (1.0 - f0) * _AT_82 ** 5
    return schlick * (7.0 / _AT_82 ** 6) * (1.0 - np.minimum(tint, 1.0))


def f82_fss(f0: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 3) the cosine-weighted hemispherical mean 2 int F(mu) mu dmu of
    the F82-tint curve: F0 + (1 - F0) / 21 - b / 126, exactly (Cycles' F_ss
    for the metal's multiple-scattering gain)."""
    return f0 + (1.0 - f0) / 21.0 - b / 126.0


@inline
def f82_fresnel1(cos_hv, f0, b):
    """(3-tuple) the F82-tint reflectance at cosine `cos_hv` of reflectance
    `f0` and factor `b` (3-tuples; f82_b)."""
    s = min(max(1.0 - cos_hv, 0.0), 1.0)
    s5 = s * s * s * s * s
    dip = cos_hv * s5 * s
    return (min(max(f0[0] + (1.0 - f0[0]) * s5 - b[0] * dip, 0.0), 1.0),
            min(max(f0[1] + (1.0 - f0[1]) * s5 - b[1] * dip, 0.0), 1.0),
            min(max(f0[2] + (1.0 - f0[2]) * s5 - b[2] * dip, 0.0), 1.0))
