"""The GGX (Trowbridge-Reitz) microfacet model as Cycles samples it, vectorised over rays.

Sources: Walter, Marschner, Li and Torrance 2007, "Microfacet models for
refraction through rough surfaces" (the distribution, eq. 33); Heitz 2014,
"Understanding the masking-shadowing function in microfacet-based BRDFs"
(Smith's Lambda, eq. 72, and the height-correlated G2 = 1 / (1 + L(i) + L(o)));
Heitz 2018, "Sampling the GGX distribution of visible normals" (JCGT 7(4)).
Cycles uses the same: `intern/cycles/kernel/closure/bsdf_microfacet.h`
(`bsdf_D`, `bsdf_lambda`, `microfacet_ggx_sample_vndf`,
`bsdf_microfacet_eval`), with alpha = Roughness^2 (`svm/closure.h`). Local frames have the macro normal along +z; directions
point away from the surface.
"""

from __future__ import annotations

import math

import numpy as np

from ..sampling.warps import concentric_disc, frames
from ..util.jit import inline, kernel
from ..util.vectors import cross_rows, dot, float_rows, normalize
from .specular import fresnel_dielectric


# Cycles renders a closure with alpha_x alpha_y at or below this as a
# perfectly specular one (`roughness_is_almost_specular`): Roughness under
# about 0.0038.
SPECULAR_ALPHA2 = 2e-10


def alpha_of(roughness) -> np.ndarray:
    """GGX width alpha = Roughness^2, Roughness clamped to 0..1, as Cycles'
    shader nodes set it (`svm/closure.h`: sqr(saturatef(roughness))); 0,
    the smooth interface, where Cycles takes it for one (SPECULAR_ALPHA2)."""
    alpha = np.clip(np.asarray(roughness, dtype=np.float64), 0.0, 1.0) ** 2
    return np.where(alpha * alpha <= SPECULAR_ALPHA2, 0.0, alpha)


def ggx_d(cos_h: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """GGX distribution of normals D(h) = a^2 / (pi ((1 - c^2) + a^2 c^2)^2),
    c = cos(theta_h) (Walter et al. 2007, eq. 33), per steradian of h; its
    projected area integrates to 1: int D(h) cos(theta_h) dw_h = 1."""
    c2 = np.minimum(cos_h * cos_h, 1.0)
    a2 = alpha * alpha
    return a2 / (math.pi * ((1.0 - c2) + a2 * c2) ** 2)


@inline
def ggx_lambda1(cos_v, alpha):
    """Smith's Lambda(v) = (sqrt(1 + a^2 tan^2(theta_v)) - 1) / 2 (Heitz 2014,
    eq. 72); the masking G1(v) = 1 / (1 + Lambda(v))."""
    c2 = max(cos_v * cos_v, 1e-300)
    return 0.5 * (math.sqrt(1.0 + alpha * alpha * max(1.0 / c2 - 1.0, 0.0)) - 1.0)


@inline
def shadowing_weight1(cos_in, cos_out, alpha):
    """What a path keeps when its microfacet normal was drawn from the
    visible normals of its incoming direction: G2 / G1(in) = (1 + L(in)) /
    (1 + L(in) + L(out)), for reflection and refraction alike (Heitz 2018,
    sec. 2; Cycles' eval / pdf in `bsdf_microfacet_sample`). In particle
    tracing the light's direction is the one sampled from, and no 1/eta^2
    factor applies: flux, not radiance, crosses the interface."""
    lam_in = ggx_lambda1(cos_in, alpha)
    return (1.0 + lam_in) / (1.0 + lam_in + ggx_lambda1(cos_out, alpha))


@kernel("void(f8[::1], f8[::1], f8[::1])")
def _lambda_values(cos_v, alpha, out):
    for i in range(len(cos_v)):
        out[i] = ggx_lambda1(cos_v[i], alpha[i])


@kernel("void(f8[::1], f8[::1], f8[::1], f8[::1])")
def _shadowing_values(cos_in, cos_out, alpha, out):
    for i in range(len(cos_in)):
        out[i] = shadowing_weight1(cos_in[i], cos_out[i], alpha[i])


def ggx_lambda(cos_v, alpha) -> np.ndarray:
    """ggx_lambda1 of each element (arguments broadcast), in their shape."""
    cos_v, alpha = float_rows(cos_v, alpha)
    out = np.empty(cos_v.shape)
    _lambda_values(cos_v.ravel(), alpha.ravel(), out.reshape(-1))
    return out


def shadowing_weight(cos_in, cos_out, alpha) -> np.ndarray:
    """shadowing_weight1 of each element (arguments broadcast), in their shape."""
    cos_in, cos_out, alpha = float_rows(cos_in, cos_out, alpha)
    out = np.empty(cos_in.shape)
    _shadowing_values(cos_in.ravel(), cos_out.ravel(), alpha.ravel(), out.reshape(-1))
    return out


def reflection(cos_nv: np.ndarray, cos_nl: np.ndarray, cos_nh: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The microfacet BRDF times cos(theta_l), without Fresnel:

        f cos_l = D(h) G2(v, l) / (4 cos_v),  G2 = 1 / (1 + Lambda(v) + Lambda(l))

    (Heitz 2014, eq. 99, height-correlated; Cycles' bsdf_microfacet_eval,
    which returns f cos_l). 0 where either direction is below the surface."""
    up = (cos_nv > 0.0) & (cos_nl > 0.0)
    g2 = 1.0 / (1.0 + ggx_lambda(cos_nv, alpha) + ggx_lambda(cos_nl, alpha))
    return np.where(up, ggx_d(cos_nh, alpha) * g2 / (4.0 * np.where(up, cos_nv, 1.0)), 0.0)


def reflection_pdf(cos_nv: np.ndarray, cos_nh: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Solid-angle density of l = reflect(v, h) for h drawn from the visible
    normals: D(h) G1(v) / (4 cos_v), G1 = 1 / (1 + Lambda(v)) (Heitz 2018,
    eq. 17 with the reflection Jacobian 1 / (4 v.h))."""
    g1 = 1.0 / (1.0 + ggx_lambda(cos_nv, alpha))
    return ggx_d(cos_nh, alpha) * g1 / (4.0 * np.maximum(cos_nv, 1e-300))


def sample_visible_normals_local(wi: np.ndarray, alpha: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) microfacet normals drawn from GGX's distribution of normals
    visible from `wi (n,3)` (unit, local, wi.z > 0), of density
    D_wi(h) = G1(wi) max(0, wi.h) D(h) / wi.z, from `uv (n,2)` in [0,1)^2
    through the concentric disc: visible_normals_of_disc."""
    return visible_normals_of_disc(wi, alpha, concentric_disc(uv))


def visible_normals_of_disc(wi: np.ndarray, alpha: np.ndarray, disc: np.ndarray) -> np.ndarray:
    """(n,3) the visible normals (sample_visible_normals_local) of points
    `disc (n,2)` of the unit disc: Heitz 2018, sec. 3-4, as Cycles'
    `microfacet_ggx_sample_vndf`: stretch wi to the hemisphere
    configuration, squeeze half the disc by (1 + wi_h.z) / 2, lift it onto
    the hemisphere about wi_h, and unstretch."""
    a = alpha[:, None]
    wh = normalize(np.concatenate([a * wi[:, :2], wi[:, 2:]], axis=1))
    lensq = wh[:, 0] ** 2 + wh[:, 1] ** 2
    tilted = lensq > 1e-14
    inv = np.where(tilted, 1.0 / np.sqrt(np.where(tilted, lensq, 1.0)), 0.0)
    t1 = np.stack([np.where(tilted, -wh[:, 1] * inv, 1.0), np.where(tilted, wh[:, 0] * inv, 0.0),
                   np.zeros(len(wh))], axis=1)
    t2 = cross_rows(wh, t1)
    s = 0.5 * (1.0 + wh[:, 2])
    p1 = disc[:, 0]
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * disc[:, 1]
    lift = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    nh = p1[:, None] * t1 + p2[:, None] * t2 + lift[:, None] * wh
    return normalize(np.concatenate([a * nh[:, :2], np.maximum(nh[:, 2:], 0.0)], axis=1))


def sample_visible_normals(wi: np.ndarray, normal: np.ndarray, alpha: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """World microfacet normals (n,3) about the macro normals `normal (n,3)`,
    visible from the unit world directions `wi (n,3)` (on the normal's
    side), from `uv (n,2)`: sample_visible_normals_local in the frame of
    each normal."""
    t, b = frames(normal)
    local = np.stack([dot(wi, t), dot(wi, b), np.maximum(dot(wi, normal), 1e-12)], axis=1)
    h = sample_visible_normals_local(normalize(local), alpha, uv)
    return normalize(h[:, :1] * t + h[:, 1:2] * b + h[:, 2:] * normal)


def bsdf_cosine(view: np.ndarray, light: np.ndarray, normal: np.ndarray, alpha: np.ndarray, eta: np.ndarray,
                mirror: np.ndarray) -> np.ndarray:
    """(n,) f(view, light) |cos theta_light| of a rough GGX interface, the
    radiance toward `view (n,3)` per unit irradiance (at normal incidence)
    arriving along `light (n,3)` (both unit, away from the surface), about
    the macro normal `normal (n,3)` on the view's side: Walter et al. 2007,
    eq. 20 and 21, as Cycles' `bsdf_microfacet_eval` writes them,

        reflection    F D G2 / (4 cos_v),                h = normalize(v + l)
        transmission  (1 - F) D G2 |v.h| |l.h| / (cos_v (eta v.h + l.h)^2),
                                                         h = -normalize(eta v + l)

    with Fresnel F at h for eta = eta_v / eta_l (1 at a mirror, `mirror (n,)`,
    which transmits nothing) and no radiance factor eta^2 (Cycles has none),
    so that its integral over the light's sphere is what the visible-normal
    sampler keeps, the single-scattering albedo."""
    cos_v, cos_l = dot(view, normal), dot(light, normal)
    through = cos_l < 0.0
    half = normalize(np.where(through[:, None], -(eta[:, None] * view + light), view + light))
    half = np.where((dot(half, normal) < 0.0)[:, None], -half, half)
    v_h, l_h = dot(view, half), dot(light, half)
    f = np.where(mirror, 1.0, fresnel_dielectric(v_h, eta))
    a = np.maximum(alpha, 1e-12)
    common = ggx_d(dot(half, normal), a) / (1.0 + ggx_lambda(cos_v, a) + ggx_lambda(np.abs(cos_l), a)) / np.maximum(
        cos_v, 1e-12)
    with np.errstate(divide="ignore", invalid="ignore"):
        transmitted = (1.0 - f) * common * np.abs(v_h * l_h) / (eta * v_h + l_h) ** 2
    reflected = 0.25 * f * common
    valid = (cos_v > 0.0) & (v_h > 0.0) & np.where(through, (l_h < 0.0) & ~mirror, l_h > 0.0)
    return np.where(valid, np.where(through, transmitted, reflected), 0.0)
