"""The GGX (Trowbridge-Reitz) microfacet distribution, isotropic, as Cycles
evaluates and samples it (intern/cycles/kernel/closure/bsdf_microfacet.h):
its normal distribution D, Smith's height-correlated masking-shadowing, and
the distribution of visible normals. Cosines are with the macro normal;
`alpha` is Cycles' alpha, Roughness^2."""

from __future__ import annotations

import math

import numpy as np

from ..util.vectors import cross_rows, normalize

# Cycles' roughness_is_almost_specular: alpha_x alpha_y at or below this is a
# mirror, which lamps cannot light (no evaluation, only sampling).
SMOOTH_ALPHA2 = 2e-10


def distribution(cos_nh: np.ndarray, alpha2: np.ndarray) -> np.ndarray:
    """D(h) = alpha^2 / (pi ((1 - c^2) + alpha^2 c^2)^2), c = n.h
    (Walter et al. 2007, eq. 33; Cycles' bsdf_D), per steradian of h."""
    c2 = np.minimum(cos_nh * cos_nh, 1.0)
    return alpha2 / (math.pi * ((1.0 - c2) + alpha2 * c2) ** 2)


def smith_lambda(cos_n: np.ndarray, alpha2: np.ndarray) -> np.ndarray:
    """Lambda(w) = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2 (Heitz 2014, eq. 72)."""
    c2 = np.maximum(cos_n * cos_n, 1e-300)
    return 0.5 * (np.sqrt(1.0 + alpha2 * np.maximum(1.0 / c2 - 1.0, 0.0)) - 1.0)


def reflection(cos_nv: np.ndarray, cos_nl: np.ndarray, cos_nh: np.ndarray, alpha2: np.ndarray) -> np.ndarray:
    """The microfacet BRDF times cos(theta_l), without Fresnel:

        f cos_l = D(h) G2(v, l) / (4 cos_v),  G2 = 1 / (1 + Lambda(v) + Lambda(l))

    (Heitz 2014, eq. 99, height-correlated; Cycles' bsdf_microfacet_eval,
    which returns f cos_l). 0 where either direction is below the surface."""
    up = (cos_nv > 0.0) & (cos_nl > 0.0)
    g2 = 1.0 / (1.0 + smith_lambda(cos_nv, alpha2) + smith_lambda(cos_nl, alpha2))
    return np.where(up, distribution(cos_nh, alpha2) * g2 / (4.0 * np.where(up, cos_nv, 1.0)), 0.0)


def reflection_pdf(cos_nv: np.ndarray, cos_nh: np.ndarray, alpha2: np.ndarray) -> np.ndarray:
    """Solid-angle density of l = reflect(v, h) for h drawn from the visible
    normals: D(h) G1(v) / (4 cos_v), G1 = 1 / (1 + Lambda(v)) (Heitz 2018,
    eq. 17 with the reflection Jacobian 1 / (4 v.h))."""
    g1 = 1.0 / (1.0 + smith_lambda(cos_nv, alpha2))
    return distribution(cos_nh, alpha2) * g1 / (4.0 * np.maximum(cos_nv, 1e-300))


def sample_visible_normals(view_local: np.ndarray, alpha: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) microfacet normals in the local frame (z the macro normal),
    drawn by the distribution of normals visible from `view_local (n,3)`
    (unit, z > 0), from `uv (n,2)` in the unit square: Heitz 2018,
    "Sampling the GGX Distribution of Visible Normals", sections 3-4, as
    Cycles' microfacet_ggx_sample_vndf."""
    a = alpha[:, None]
    stretched = view_local * np.concatenate([a, a, np.ones_like(a)], axis=1)
    stretched = normalize(stretched)
    lensq = stretched[:, 0] ** 2 + stretched[:, 1] ** 2
    tilted = lensq > 1e-14
    inv = np.where(tilted, 1.0 / np.sqrt(np.where(tilted, lensq, 1.0)), 0.0)
    t1 = np.stack([np.where(tilted, -stretched[:, 1] * inv, 1.0), np.where(tilted, stretched[:, 0] * inv, 0.0),
                   np.zeros(len(uv))], axis=1)
    t2 = cross_rows(stretched, t1)
    r, phi = np.sqrt(uv[:, 0]), 2.0 * math.pi * uv[:, 1]
    x, y = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + stretched[:, 2])
    y = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - x * x)) + s * y
    z = np.sqrt(np.maximum(0.0, 1.0 - x * x - y * y))
    h = x[:, None] * t1 + y[:, None] * t2 + z[:, None] * stretched
    h = np.stack([alpha * h[:, 0], alpha * h[:, 1], np.maximum(h[:, 2], 0.0)], axis=1)
    return normalize(h)
