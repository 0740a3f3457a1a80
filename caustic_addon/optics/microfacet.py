"""The GGX (Trowbridge-Reitz) microfacet model as Cycles samples it: scalar
forms for kernels (the `...1` functions) and array kernels over rays.

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
from ..util.vectors import dot1, float_rows, normalize1, row, scale1, set_row, sum1
from .specular import fresnel_dielectric1


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


@inline
def ggx_d1(cos_h, alpha):
    """GGX distribution of normals D(h) = a^2 / (pi ((1 - c^2) + a^2 c^2)^2),
    c = cos(theta_h) (Walter et al. 2007, eq. 33), per steradian of h; its
    projected area integrates to 1: int D(h) cos(theta_h) dw_h = 1."""
    c2 = min(cos_h * cos_h, 1.0)
    a2 = alpha * alpha
    q = (1.0 - c2) + a2 * c2
    return a2 / (math.pi * (q * q))


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


@inline
def reflection1(cos_nv, cos_nl, cos_nh, alpha):
    """The microfacet BRDF times cos(theta_l), without Fresnel:

        f cos_l = D(h) G2(v, l) / (4 cos_v),  G2 = 1 / (1 + Lambda(v) + Lambda(l))

    (Heitz 2014, eq. 99, height-correlated; Cycles' bsdf_microfacet_eval,
    which returns f cos_l). 0 where either direction is below the surface."""
    if not (cos_nv > 0.0 and cos_nl > 0.0):
        return 0.0
    g2 = 1.0 / (1.0 + ggx_lambda1(cos_nv, alpha) + ggx_lambda1(cos_nl, alpha))
    return ggx_d1(cos_nh, alpha) * g2 / (4.0 * cos_nv)


@inline
def reflection_pdf1(cos_nv, cos_nh, alpha):
    """Solid-angle density of l = reflect(v, h) for h drawn from the visible
    normals: D(h) G1(v) / (4 cos_v), G1 = 1 / (1 + Lambda(v)) (Heitz 2018,
    eq. 17 with the reflection Jacobian 1 / (4 v.h))."""
    g1 = 1.0 / (1.0 + ggx_lambda1(cos_nv, alpha))
    return ggx_d1(cos_nh, alpha) * g1 / (4.0 * max(cos_nv, 1e-300))


@inline
def visible_normal1(wi, alpha, disc_x, disc_y):
    """The microfacet normal (3-tuple, local, unit) of GGX's normals visible
    from `wi` (unit, local, wi.z > 0), of density
    D_wi(h) = G1(wi) max(0, wi.h) D(h) / wi.z, at the point (disc_x,
    disc_y) of the unit disc: Heitz 2018, sec. 3-4, as Cycles'
    `microfacet_ggx_sample_vndf`: stretch wi to the hemisphere
    configuration, squeeze half the disc by (1 + wi_h.z) / 2, lift it onto
    the hemisphere about wi_h, and unstretch."""
    wh = normalize1((alpha * wi[0], alpha * wi[1], wi[2]))
    lensq = wh[0] * wh[0] + wh[1] * wh[1]
    if lensq > 1e-14:
        inv = 1.0 / math.sqrt(lensq)
        t1 = (-wh[1] * inv, wh[0] * inv, 0.0)
    else:
        t1 = (1.0, 0.0, 0.0)
    t2 = (wh[1] * t1[2] - wh[2] * t1[1], wh[2] * t1[0] - wh[0] * t1[2], wh[0] * t1[1] - wh[1] * t1[0])
    s = 0.5 * (1.0 + wh[2])
    p1 = disc_x
    p2 = (1.0 - s) * math.sqrt(max(0.0, 1.0 - p1 * p1)) + s * disc_y
    lift = math.sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2))
    nh = (p1 * t1[0] + p2 * t2[0] + lift * wh[0], p1 * t1[1] + p2 * t2[1] + lift * wh[1],
          p1 * t1[2] + p2 * t2[2] + lift * wh[2])
    return normalize1((alpha * nh[0], alpha * nh[1], max(nh[2], 0.0)))


@inline
def visible_normal_about1(wi, normal, tangent, bitangent, alpha, disc_x, disc_y):
    """visible_normal1 in the frame (tangent, bitangent, normal): the world
    microfacet normal about the macro `normal`, visible from the unit world
    direction `wi` (on the normal's side)."""
    local = normalize1((dot1(wi, tangent), dot1(wi, bitangent), max(dot1(wi, normal), 1e-12)))
    h = visible_normal1(local, alpha, disc_x, disc_y)
    return normalize1(sum1(1.0, sum1(h[0], tangent, h[1], bitangent), h[2], normal))


@inline
def half_vector1(view, light, normal, eta, through):
    """The microfacet normal that turns `view` into `light` (both unit,
    away from the surface), on the side of `normal`: normalize(v + l) by
    reflection, -normalize(eta v + l) by refraction (`through`), eta =
    eta_v / eta_l (Walter et al. 2007, eq. 13 and 16)."""
    if through:
        half = normalize1(scale1(-1.0, sum1(eta, view, 1.0, light)))
    else:
        half = normalize1(sum1(1.0, view, 1.0, light))
    return scale1(-1.0, half) if dot1(half, normal) < 0.0 else half


@inline
def bsdf_cosine1(view, light, normal, alpha, eta, mirror):
    """f(view, light) |cos theta_light| of a rough GGX interface, the
    radiance toward `view` per unit irradiance (at normal incidence)
    arriving along `light` (both unit, away from the surface), about the
    macro `normal` on the view's side: Walter et al. 2007, eq. 20 and 21,
    as Cycles' `bsdf_microfacet_eval` writes them,

        reflection    F D G2 / (4 cos_v),                h = normalize(v + l)
        transmission  (1 - F) D G2 |v.h| |l.h| / (cos_v (eta v.h + l.h)^2),
                                                         h = -normalize(eta v + l)

    with Fresnel F at h for eta = eta_v / eta_l (1 at a `mirror`, which
    transmits nothing) and no radiance factor eta^2 (Cycles has none), so
    that its integral over the light's sphere is what the visible-normal
    sampler keeps, the single-scattering albedo. 0 where the pair has no
    such microfacet normal (and where eta v.h + l.h = 0, h's limit)."""
    cos_v, cos_l = dot1(view, normal), dot1(light, normal)
    through = cos_l < 0.0
    half = half_vector1(view, light, normal, eta, through)
    v_h, l_h = dot1(view, half), dot1(light, half)
    if not (cos_v > 0.0 and v_h > 0.0 and ((l_h < 0.0 and not mirror) if through else l_h > 0.0)):
        return 0.0
    f = 1.0 if mirror else fresnel_dielectric1(v_h, eta)
    a = max(alpha, 1e-12)
    common = ggx_d1(dot1(half, normal), a) / (1.0 + ggx_lambda1(cos_v, a) + ggx_lambda1(abs(cos_l), a)) / max(
        cos_v, 1e-12)
    if not through:
        return 0.25 * f * common
    across = eta * v_h + l_h
    if across == 0.0:
        return 0.0
    return (1.0 - f) * common * abs(v_h * l_h) / (across * across)


@inline
def branch_pdf1(view, light, normal, alpha, eta):
    """Solid-angle density of a rough interface's branch toward `light`
    for a normal h drawn from the normals visible from `view` (both unit,
    away from the surface, about the macro `normal` on the view's side):
    the reflected branch's reflection_pdf1, h = normalize(v + l), and the
    refracted one's D_v(h) |l.h| / (eta v.h + l.h)^2, D_v(h) = G1(v) D(h)
    v.h / cos_v, h = -normalize(eta v + l) for eta = eta_v / eta_l (Heitz
    2018, eq. 3; Walter et al. 2007, eq. 17). Over what bsdf_cosine1
    gives, it is what a branch keeps, F G2 / G1 or (1 - F) G2 / G1. 0 where
    the pair has no such normal."""
    cos_v, cos_l = dot1(view, normal), dot1(light, normal)
    through = cos_l < 0.0
    half = half_vector1(view, light, normal, eta, through)
    v_h, l_h = dot1(view, half), dot1(light, half)
    if not (cos_v > 0.0 and v_h > 0.0 and (l_h < 0.0 if through else l_h > 0.0)):
        return 0.0
    a = max(alpha, 1e-12)
    if not through:
        return reflection_pdf1(cos_v, dot1(half, normal), a)
    across = eta * v_h + l_h
    if across == 0.0:
        return 0.0
    visible = ggx_d1(dot1(half, normal), a) / (1.0 + ggx_lambda1(cos_v, a)) * v_h / cos_v
    return visible * abs(l_h) / (across * across)


@kernel("void(f8[::1], f8[::1], f8[::1])")
def _d_values(cos_h, alpha, out):
    for i in range(len(cos_h)):
        out[i] = ggx_d1(cos_h[i], alpha[i])


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


def ggx_d(cos_h, alpha) -> np.ndarray:
    """ggx_d1 of each element (arguments broadcast), in their shape."""
    cos_h, alpha = float_rows(cos_h, alpha)
    out = np.empty(cos_h.shape)
    _d_values(cos_h.ravel(), alpha.ravel(), out.reshape(-1))
    return out


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1])")
def _visible_normals(wi, alpha, disc, out):
    for i in range(len(wi)):
        set_row(out, i, visible_normal1(row(wi, i), alpha[i], disc[i, 0], disc[i, 1]))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1])")
def _visible_normals_about(wi, normal, tangent, bitangent, alpha, disc, out):
    for i in range(len(wi)):
        set_row(out, i, visible_normal_about1(row(wi, i), row(normal, i), row(tangent, i), row(bitangent, i),
                                              alpha[i], disc[i, 0], disc[i, 1]))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], b1[::1], f8[::1])")
def _bsdf_cosines(view, light, normal, alpha, eta, mirror, out):
    for i in range(len(view)):
        out[i] = bsdf_cosine1(row(view, i), row(light, i), row(normal, i), alpha[i], eta[i], mirror[i])


def visible_normals_of_disc(wi: np.ndarray, alpha: np.ndarray, disc: np.ndarray) -> np.ndarray:
    """(n,3) visible_normal1 of each row: local unit directions `wi (n,3)`,
    widths `alpha (n,)`, points `disc (n,2)` of the unit disc."""
    (wi,), (alpha,), (disc,) = float_rows(wi), float_rows(alpha), float_rows(disc)
    out = np.empty_like(wi)
    _visible_normals(wi, alpha, disc, out)
    return out


def sample_visible_normals_local(wi: np.ndarray, alpha: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) microfacet normals drawn from GGX's distribution of normals
    visible from `wi (n,3)` (unit, local, wi.z > 0) from `uv (n,2)` in
    [0,1)^2 through the concentric disc: visible_normals_of_disc."""
    return visible_normals_of_disc(wi, alpha, concentric_disc(uv))


def sample_visible_normals(wi: np.ndarray, normal: np.ndarray, alpha: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """World microfacet normals (n,3) about the macro normals `normal (n,3)`,
    visible from the unit world directions `wi (n,3)` (on the normal's
    side), from `uv (n,2)` through the concentric disc: visible_normal_about1
    in the frame of each normal (sampling.warps.frames)."""
    wi, normal = float_rows(wi, normal)
    t, b = float_rows(*frames(normal))
    (alpha,) = float_rows(alpha)
    (disc,) = float_rows(concentric_disc(uv))
    out = np.empty_like(wi)
    _visible_normals_about(wi, normal, t, b, alpha, disc, out)
    return out


def bsdf_cosine(view: np.ndarray, light: np.ndarray, normal: np.ndarray, alpha: np.ndarray, eta: np.ndarray,
                mirror: np.ndarray) -> np.ndarray:
    """(n,) bsdf_cosine1 of each row: `view, light, normal (n,3)`, `alpha,
    eta (n,)`, `mirror (n,)` bool."""
    view, light, normal = float_rows(view, light, normal)
    alpha, eta = float_rows(alpha, eta)
    out = np.empty(len(view))
    _bsdf_cosines(view, light, normal, alpha, eta, np.ascontiguousarray(mirror, dtype=bool), out)
    return out


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[::1])")
def _branch_pdfs(view, light, normal, alpha, eta, out):
    for i in range(len(view)):
        out[i] = branch_pdf1(row(view, i), row(light, i), row(normal, i), alpha[i], eta[i])


def branch_pdf(view: np.ndarray, light: np.ndarray, normal: np.ndarray, alpha: np.ndarray,
               eta: np.ndarray) -> np.ndarray:
    """(n,) branch_pdf1 of each row: `view, light, normal (n,3)`, `alpha, eta (n,)`."""
    view, light, normal = float_rows(view, light, normal)
    alpha, eta = float_rows(alpha, eta)
    out = np.empty(len(view))
    _branch_pdfs(view, light, normal, alpha, eta, out)
    return out
