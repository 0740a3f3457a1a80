"""The specular layer of Cycles' Principled BSDF (Blender 4.x and 5.x,
"Principled v2") over its diffuse base, as intern/cycles/kernel/svm/closure.h
builds it and kernel/closure/bsdf_microfacet.h evaluates it:

- a GGX lobe of alpha = Roughness^2 (microfacet.py);
- F0 = ((n - 1) / (n + 1))^2 of the IOR n, times 2 x Specular IOR Level
  (0.5 keeps it), and the IOR that F0 belongs to, eta = (1 + sqrt F0) /
  (1 - sqrt F0), is the one the Fresnel curve follows; Specular Tint
  multiplies F0 (clamped to 1), not the grazing reflectance, which stays 1;
- Fresnel: the real dielectric curve F_d(eta, h.v) remapped from
  [F0(eta), 1] onto [F0 tint, 1] (generalized_schlick_fresnel, exponent < 0);
- Multiscatter GGX (the node's default) scales the lobe by 1 + F_ms (1 - E) / E
  (Kulla and Conty 2017, "Revisiting Physically Based Shading at
  Imageworks"; microfacet_ggx_preserve_energy), with E(mu) the lobe's
  directional albedo without Fresnel, E_avg its cosine-weighted mean,
  F_ms = F_ss E_avg / (1 - F_ss (1 - E_avg)) and F_ss the hemispherical
  mean of the Fresnel term (Kulla and Conty's fit of the dielectric one);
- the diffuse base under it keeps 1 - max over channels of the layer's
  albedo toward the eye, F0 tint + (1 - F0 tint) s(mu), times the multiple
  scattering's darkening (1 + F_ms (1 - E) / E) / (1 + (1 - E) / E)
  (closure_layering_weight), with s(mu) the mean Fresnel interpolant over
  the visible normals.

Cycles reads E, E_avg and s from tables it made by Monte Carlo
(intern/cycles/app/cycles_precompute.cpp: E and E_avg over 32 roughnesses
and 32 cosines, s over 16 roughnesses, cosines and IORs) and interpolates
them linearly. This module integrates the same definitions by a midpoint
rule at the same nodes and interpolates them the same way, so it inherits
the tables' interpolation, not their noise. At the nodes it is within
8e-4 of Cycles' tables for E and E_avg (3e-4 RMS) and 7e-4 for s, but for
the corner of roughness 0, IOR 1 and grazing view (0.15), where the layer
reflects next to nothing."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import microfacet
from .metal import f82_fresnel1
from ..sampling.warps import concentric_disc
from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import DIVISION_FLOOR, dot, dot1, float_rows, normalize1, row, set_row, sum1
from .specular import fresnel_dielectric1

E_NODES = 32
S_NODES = 16
# Strata per axis of the square the visible normals are drawn from; the
# radial one is graded toward the disc's rim, where the reflected direction
# leaves the hemisphere.
QUADRATURE = 48
# The smallest alpha the lobe takes: 1e-10 for alpha^2, a mirror to
# Cycles (microfacet.SPECULAR_ALPHA2), which lamps do not light.
MIN_ALPHA = 1e-5


@inline
def f0_from_ior(ior):
    """Reflectance at normal incidence ((n - 1) / (n + 1))^2 (Cycles' F0_from_ior)."""
    r = (ior - 1.0) / (ior + 1.0)
    return r * r


def ior_from_f0(f0):
    """The IOR (1 + sqrt F0) / (1 - sqrt F0) of reflectance F0, F0 clamped to
    0..0.99 (Cycles' ior_from_F0)."""
    root = np.sqrt(np.clip(f0, 0.0, 0.99))
    return (1.0 + root) / (1.0 - root)


def specular_f0(ior: float, level: float) -> tuple[float, float]:
    """(F0, eta): F0 of `ior` times 2 `level` (Specular IOR Level; 0.5 keeps
    it) and the IOR whose Fresnel curve the lobe follows (closure.h, "Apply
    IOR adjustment"). eta = 1 means no specular layer at all."""
    f0 = f0_from_ior(ior)
    if level == 0.5:
        return f0, ior
    f0 *= 2.0 * level
    eta = float(ior_from_f0(f0))
    return f0, (1.0 / eta if ior < 1.0 else eta)


def dielectric_fss(eta: float) -> float:
    """Hemispherical mean 2 int F_d(mu) mu dmu of the dielectric Fresnel
    term, Kulla and Conty's fit (as Cycles' fresnel_dielectric_Fss)."""
    if eta < 1.0:
        return 0.997118 + eta * (0.1014 - eta * (0.965241 + eta * 0.130607))
    return (eta - 1.0) / (4.08567 + 1.00071 * eta)


@inline
def fresnel_interpolant1(cos_hv, eta):
    """s = (F_d(cos_hv) - F0(eta)) / (1 - F0(eta)) clamped to 0..1: where the
    dielectric Fresnel curve of IOR `eta` stands between its value at normal
    incidence and 1 (generalized_schlick_fresnel's interpolant)."""
    real = f0_from_ior(eta)
    return min(max((fresnel_dielectric1(cos_hv, 1.0 / eta) - real) / (1.0 - real), 0.0), 1.0)


@inline
def fresnel1(cos_hv, eta, f0):
    """(3-tuple) F0 tint + (1 - F0 tint) s, s = fresnel_interpolant1: the
    dielectric Fresnel curve of IOR `eta` remapped onto `f0` (3-tuple) .. 1
    (generalized_schlick_fresnel, exponent < 0)."""
    s = fresnel_interpolant1(cos_hv, eta)
    return (f0[0] + (1.0 - f0[0]) * s, f0[1] + (1.0 - f0[1]) * s, f0[2] + (1.0 - f0[2]) * s)


@inline
def lobe_weight1(normal, view, light, f0, eta, alpha, gain, metal, base, b):
    """(3-tuple) f cos(theta_l) of a Principled BSDF's GGX lobe: its BRDF
    toward the eye `view` for light from the unit direction `light`, times
    the cosine at `normal`: (gain F(h.v) + metal F_82(h.v)) D G2 / (4 cos_v),
    h = normalize(v + l), the specular layer's Fresnel (fresnel1) and the
    metal's (metal.f82_fresnel1 of reflectance `base` and factor `b`), each
    times its weight toward the eye (bsdf_microfacet_eval x energy_scale x
    the darkening in the closure's weight; microfacet.reflection1). The
    metal and the layer share the Roughness, so one lobe serves both."""
    half = normalize1(sum1(1.0, view, 1.0, light))
    lobe = microfacet.reflection1(dot1(normal, view), dot1(normal, light), dot1(normal, half), alpha)
    cos_hv = dot1(half, view)
    f, m = fresnel1(cos_hv, eta, f0), f82_fresnel1(cos_hv, base, b)
    return ((f[0] * gain[0] + m[0] * metal[0]) * lobe, (f[1] * gain[1] + m[1] * metal[1]) * lobe,
            (f[2] * gain[2] + m[2] * metal[2]) * lobe)


@inline
def lobe_pdf1(normal, view, light, alpha):
    """Solid-angle density of lobe_sample1 drawing `light`:
    microfacet.reflection_pdf1 at h = normalize(v + l), 0 where h is below
    the surface."""
    cos_h = dot1(normal, normalize1(sum1(1.0, view, 1.0, light)))
    return microfacet.reflection_pdf1(dot1(normal, view), cos_h, alpha) if cos_h > 0.0 else 0.0


@inline
def lobe_sample1(normal, tangent, bitangent, view, alpha, disc_x, disc_y):
    """The unit direction reflect(v, h) = 2 (v.h) h - v about the microfacet
    normal h that microfacet.visible_normal1 draws from the view's visible
    normals in the frame (tangent, bitangent, normal) at the disc point
    (disc_x, disc_y); it may fall below the surface."""
    local = normalize1((dot1(tangent, view), dot1(bitangent, view), max(dot1(normal, view), 1e-9)))
    m = microfacet.visible_normal1(local, alpha, disc_x, disc_y)
    h = sum1(1.0, sum1(m[0], tangent, m[1], bitangent), m[2], normal)
    return sum1(2.0 * dot1(view, h), h, -1.0, view)


@inline
def curve_node1(k, x):
    """The node j of a table of k values at nodes i / (k - 1) that
    `curve_at1` interpolates from at 0 <= x <= 1: x_j <= x < x_j+1, j <= k - 2."""
    j = min(max(int(x * (k - 1)), 0), k - 2)
    while j > 0 and j / (k - 1) > x:
        j -= 1
    while j < k - 2 and (j + 1) / (k - 1) <= x:
        j += 1
    return j


@inline
def curve_at1(y0, y1, j, k, x):
    """np.interp(x, nodes, curve) over the nodes i / (k - 1) of a table of
    k values, 0 <= x <= 1 (Cycles' lookup_table_read), from the values y0,
    y1 at its nodes j, j + 1 (curve_node1), the same arithmetic as numpy's:
    slope (x - x_j) + y_j between the nodes. The caller reads the table: a
    helper that reads an array under a branch or a loop costs its kernel an
    atomic reference count a call (tracing.accelerator.inside1)."""
    lo = j / (k - 1)
    if x >= 1.0:
        return y1
    if x <= lo:
        return y0
    return (y1 - y0) / ((j + 1) / (k - 1) - lo) * (x - lo) + y0


def _node(value: float, count: int) -> tuple[int, float]:
    """(i, t): `value` in 0..1 lies between table nodes i and i + 1 of
    `count`, a fraction t of the way (Cycles' lookup_table_read)."""
    x = min(max(value, 0.0), 1.0) * (count - 1)
    i = min(int(x), count - 2)
    return i, x - i


def _nodes(count: int, lo: float, hi: float) -> np.ndarray:
    """A table axis as cycles_precompute.cpp spans it: i / (count - 1), clamped to lo..hi."""
    return np.clip(np.arange(count) / (count - 1), lo, hi)


@kernel("void(f8[::1], f8, f8[::1])")
def _interpolants(cos_hv, eta, out):
    for i in range(len(cos_hv)):
        out[i] = fresnel_interpolant1(cos_hv[i], eta)


def directional(rough: float, mu: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """(E (k,), s (k,)) at cosines `mu (k,)` of a lobe of Roughness `rough`:
    E = the mean of G2 / G1 and s = the mean of the Fresnel interpolant
    (F_d(eta, h.v) - F0) / (1 - F0) over normals h drawn from the visible
    normals, counting 0 where reflect(v, h) goes below the surface (what
    cycles_precompute.cpp averages), by a QUADRATURE^2 midpoint rule over
    the square Heitz's map takes, u = 1 - (1 - w)^4 across the disc's
    radius (its rim, the last alpha^2 of u, holds the cut)."""
    g = (np.arange(QUADRATURE) + 0.5) / QUADRATURE
    radial, azimuth = (a.ravel() for a in np.meshgrid(g, g))
    uv = np.stack([1.0 - (1.0 - radial) ** 4, azimuth], axis=1)
    weight = 4.0 * (1.0 - radial) ** 3
    q, k = len(uv), len(mu)
    mu_rows = np.repeat(mu, q)
    view = np.stack([np.sqrt(1.0 - mu_rows ** 2), np.zeros(q * k), mu_rows], axis=1)
    alpha = rough * rough
    r, phi = np.sqrt(uv[:, 0]), 2.0 * math.pi * uv[:, 1]
    disc = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    h = microfacet.visible_normals_of_disc(view, np.full(q * k, alpha), np.tile(disc, (k, 1)))
    cos_hv = dot(view, h)
    cos_l = 2.0 * cos_hv * h[:, 2] - mu_rows
    up = cos_l > 0.0
    g2_over_g1 = np.where(up, microfacet.shadowing_weight(mu_rows, cos_l, alpha), 0.0)
    s = np.empty(len(cos_hv))
    _interpolants(cos_hv, eta, s)
    s = np.where(up, s, 0.0)
    weights = np.tile(weight, k)
    return (g2_over_g1 * weights).reshape(k, q).mean(axis=1), (s * weights).reshape(k, q).mean(axis=1)


@lru_cache(maxsize=64)
def albedo_curves(roughness: float, eta: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(E (E_NODES,), s (S_NODES,), E_avg) of a lobe of `roughness` and IOR
    `eta`, at the cosines of Cycles' tables, interpolated between the
    tables' roughness (and, for s, IOR) nodes as Cycles does."""
    rough_e = _nodes(E_NODES, 1e-4, 1.0)
    i, t = _node(roughness, E_NODES)
    mu_e = _nodes(E_NODES, 1e-4, 1.0)
    gauss, weights = np.polynomial.legendre.leggauss(E_NODES)
    mu_avg = 0.5 * (gauss + 1.0)
    curves, means = [], []
    for rough in rough_e[i:i + 2]:
        curves.append(directional(rough, mu_e, 1.5)[0])
        means.append(float(np.sum(weights * mu_avg * directional(rough, mu_avg, 1.5)[0])))
    e_curve = (1.0 - t) * curves[0] + t * curves[1]
    e_avg = (1.0 - t) * means[0] + t * means[1]

    rough_s, mu_s = _nodes(S_NODES, 1e-4, 1.0), _nodes(S_NODES, 1e-4, 1.0)
    z_nodes = _nodes(S_NODES, 1e-4, 0.99)
    i, t = _node(roughness, S_NODES)
    j, u = _node(math.sqrt(abs((eta - 1.0) / (eta + 1.0))), S_NODES)
    s_curve = np.zeros(S_NODES)
    for rough, w_rough in zip(rough_s[i:i + 2], (1.0 - t, t)):
        for z, w_z in zip(z_nodes[j:j + 2], (1.0 - u, u)):
            if w_rough * w_z > 0.0:
                s_curve += w_rough * w_z * directional(rough, mu_s, float(ior_from_f0(z ** 4)))[1]
    return e_curve, np.clip(s_curve, 0.0, 1.0), e_avg


@dataclass
class Layer:
    """One material's specular layer, ready to shade: F0 tint `f0 (3,)`, the
    IOR `eta` of its Fresnel curve, `alpha`, and, with `multiscatter`, its
    F_ss (3,); its albedo curves (albedo_curves)."""

    f0: np.ndarray
    eta: float
    alpha: float
    multiscatter: bool
    fss: np.ndarray
    e_curve: np.ndarray
    s_curve: np.ndarray
    e_avg: float

    @staticmethod
    def of(roughness: float, ior: float, level: float, tint: np.ndarray, multiscatter: bool) -> "Layer | None":
        """The layer of a Principled BSDF's Roughness, IOR, Specular IOR Level
        and Specular Tint (3,); None where it reflects nothing (eta = 1, as
        Cycles skips it)."""
        f0, eta = specular_f0(ior, level)
        if eta == 1.0:
            return None
        f0_tint = np.clip(f0 * np.asarray(tint, dtype=np.float64), 0.0, 1.0)
        real = f0_from_ior(eta)
        s = min(max((dielectric_fss(eta) - real) / (1.0 - real), 0.0), 1.0)
        e_curve, s_curve, e_avg = albedo_curves(float(roughness), float(eta))
        return Layer(f0_tint, float(eta), max(float(roughness) ** 2, MIN_ALPHA), bool(multiscatter),
                     f0_tint + (1.0 - f0_tint) * s, e_curve, s_curve, e_avg)

    def toward(self, cos_v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(gain (n,3), diffuse (n,)) seen from cosines `cos_v (n,)`: toward1
        of each, and the share of the diffuse base the layer leaves, 1 - the
        max over channels of its albedo, clamped to 0..1."""
        n = len(cos_v)
        gain, shared = np.empty((n, 3)), np.empty((n, 3))
        _toward(contiguous(cos_v, np.float64), self.s_curve, self.e_curve, self.f0, self.fss, self.e_avg,
                self.multiscatter, gain, shared)
        return gain, np.clip(1.0 - shared.max(axis=1), 0.0, 1.0)


@inline
def multiscatter_gain1(fss, e_avg, missing):
    """1 + F_ms missing, F_ms = F_ss E_avg / (1 - F_ss (1 - E_avg)), of one channel."""
    return 1.0 + fss * e_avg / (1.0 - fss * (1.0 - e_avg)) * missing


@inline
def toward1(mu, s, e, f0, fss, e_avg, multiscatter):
    """(gain, shared) (3-tuples) of a layer seen at `mu`, the cosine of its
    view clamped to 0..1, where its curves read `s` and `e`: the
    multiple-scattering gain 1 + F_ms (1 - E) / E of the lobe,
    F_ms = F_ss E_avg / (1 - F_ss (1 - E_avg)), (1 without `multiscatter`)
    and the albedo the layer takes from the diffuse base, F0 + (1 - F0) s
    times its darkening gain / (1 + (1 - E) / E) (closure_layering_weight's
    layer albedo over the weight), E floored at DIVISION_FLOOR. `f0`, `fss` 3-tuples."""
    albedo = (f0[0] + (1.0 - f0[0]) * s, f0[1] + (1.0 - f0[1]) * s, f0[2] + (1.0 - f0[2]) * s)
    if not multiscatter:
        return (1.0, 1.0, 1.0), albedo
    missing = (1.0 - e) / max(e, DIVISION_FLOOR)
    gain = (multiscatter_gain1(fss[0], e_avg, missing), multiscatter_gain1(fss[1], e_avg, missing),
            multiscatter_gain1(fss[2], e_avg, missing))
    darkening = 1.0 + missing
    return gain, (gain[0] / darkening * albedo[0], gain[1] / darkening * albedo[1], gain[2] / darkening * albedo[2])


@kernel("void(f8[::1], f8[::1], f8[::1], f8[::1], f8[::1], f8, b1, f8[:, ::1], f8[:, ::1])")
def _toward(cos_v, s_curve, e_curve, f0, fss, e_avg, multiscatter, gain, shared):
    f0_t, fss_t = (f0[0], f0[1], f0[2]), (fss[0], fss[1], fss[2])
    ks, ke = len(s_curve), len(e_curve)
    for i in range(len(cos_v)):
        mu = min(max(cos_v[i], 0.0), 1.0)
        js, je = curve_node1(ks, mu), curve_node1(ke, mu)
        s = curve_at1(s_curve[js], s_curve[js + 1], js, ks, mu)
        e = curve_at1(e_curve[je], e_curve[je + 1], je, ke, mu)
        g, a = toward1(mu, s, e, f0_t, fss_t, e_avg, multiscatter)
        gain[i, 0], gain[i, 1], gain[i, 2] = g
        shared[i, 0], shared[i, 1], shared[i, 2] = a


@dataclass
class Lobe:
    """The GGX lobes at n shading points, seen from their eye rays: a
    Principled BSDF's specular layer and metal, which share its Roughness,
    or its coat (layers.Stack).

    active (n,) bool   the point's surface has the lobe; the others reflect nothing
    f0 (n,3)           the layer's F0 tint;  eta (n,) the IOR of its Fresnel curve
    alpha (n,)         GGX alpha
    gain (n,3)         the layer's weight toward the eye: its multiple-scattering
                       gain (Layer.toward) times what the layers above leave; 0 where inactive
    metal (n,3)        the metal's weight toward the eye, likewise (0: no metal)
    base (n,3)         the metal's F0, its Base Color;  b (n,3) its F82-tint factor (metal.f82_b)
    """

    active: np.ndarray
    f0: np.ndarray
    eta: np.ndarray
    alpha: np.ndarray
    gain: np.ndarray
    metal: np.ndarray | None = None
    base: np.ndarray | None = None
    b: np.ndarray | None = None

    def __post_init__(self):
        self.active = contiguous(self.active, bool)
        self.metal, self.base, self.b = (np.zeros((len(self.active), 3)) if a is None else a
                                         for a in (self.metal, self.base, self.b))
        self.f0, self.eta, self.alpha, self.gain, self.metal, self.base, self.b = (
            contiguous(a, np.float64) for a in (self.f0, self.eta, self.alpha, self.gain, self.metal, self.base,
                                                self.b))

    @property
    def fields(self) -> tuple:
        """(f0, eta, alpha, gain, metal, base, b), as kernels take them."""
        return self.f0, self.eta, self.alpha, self.gain, self.metal, self.base, self.b

    @property
    def lamp_lit(self) -> np.ndarray:
        """(n,) the points whose lobe lamps light: not a mirror (Cycles evaluates no mirror)."""
        return self.active & (self.alpha * self.alpha > microfacet.SPECULAR_ALPHA2)

    def take(self, rows: np.ndarray) -> Lobe:
        """The layers at the points `rows (m,)`."""
        return Lobe(*(np.take(a, rows, axis=0) for a in (self.active, *self.fields)))

    def weight(self, normal: np.ndarray, view: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,3) lobe_weight1 of each point: f cos(theta_l) toward the eye
        `view (n,3)` for light from unit `dirs (n,3)`, at `normal (n,3)`."""
        out = np.empty((len(normal), 3))
        _lobe_weights(*float_rows(normal, view, dirs), *self.fields, out)
        return out

    def pdf(self, normal: np.ndarray, view: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) lobe_pdf1 of each point, the density of `sample` drawing `dirs (n,3)`; 0 where inactive."""
        out = np.empty(len(normal))
        _lobe_pdfs(*float_rows(normal, view, dirs), self.active, self.alpha, out)
        return out

    def sample(self, normal: np.ndarray, tangent: np.ndarray, bitangent: np.ndarray, view: np.ndarray,
               uv: np.ndarray) -> np.ndarray:
        """(n,3) lobe_sample1 of each point in the frame (tangent, bitangent,
        normal), at the concentric disc's points of `uv (n,2)`; some fall
        below the surface."""
        out = np.empty((len(normal), 3))
        _lobe_samples(*float_rows(normal, tangent, bitangent, view), self.alpha,
                      *float_rows(concentric_disc(uv)), out)
        return out


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], "
        "f8[:, ::1], f8[:, ::1])")
def _lobe_weights(normal, view, dirs, f0, eta, alpha, gain, metal, base, b, out):
    for i in range(len(normal)):
        set_row(out, i, lobe_weight1(row(normal, i), row(view, i), row(dirs, i), row(f0, i), eta[i], alpha[i],
                                     row(gain, i), row(metal, i), row(base, i), row(b, i)))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], b1[::1], f8[::1], f8[::1])")
def _lobe_pdfs(normal, view, dirs, active, alpha, out):
    for i in range(len(normal)):
        out[i] = lobe_pdf1(row(normal, i), row(view, i), row(dirs, i), alpha[i]) if active[i] else 0.0


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1])")
def _lobe_samples(normal, tangent, bitangent, view, alpha, disc, out):
    for i in range(len(normal)):
        set_row(out, i, lobe_sample1(row(normal, i), row(tangent, i), row(bitangent, i), row(view, i), alpha[i],
                                     disc[i, 0], disc[i, 1]))
