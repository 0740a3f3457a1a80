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
from ..util.vectors import dot, max_channel, normalize
from .specular import fresnel_dielectric

E_NODES = 32
S_NODES = 16
# Strata per axis of the square the visible normals are drawn from; the
# radial one is graded toward the disc's rim, where the reflected direction
# leaves the hemisphere.
QUADRATURE = 48
# The smallest alpha the lobe takes: 1e-10 for alpha^2, a mirror to
# Cycles (microfacet.SPECULAR_ALPHA2), which lamps do not light.
MIN_ALPHA = 1e-5


def f0_from_ior(ior):
    """Reflectance at normal incidence ((n - 1) / (n + 1))^2 (Cycles' F0_from_ior)."""
    return ((ior - 1.0) / (ior + 1.0)) ** 2


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


def fresnel(cos_hv: np.ndarray, eta: np.ndarray, f0: np.ndarray) -> np.ndarray:
    """(n,3) F0 tint + (1 - F0 tint) s with s = (F_d - F0(eta)) / (1 - F0(eta))
    clamped to 0..1: the dielectric Fresnel curve of IOR `eta (n,)`
    remapped onto `f0 (n,3)` .. 1 (generalized_schlick_fresnel)."""
    real = f0_from_ior(eta)
    s = np.clip((fresnel_dielectric(cos_hv, 1.0 / eta) - real) / (1.0 - real), 0.0, 1.0)
    return f0 + (1.0 - f0) * s[:, None]


def _node(value: float, count: int) -> tuple[int, float]:
    """(i, t): `value` in 0..1 lies between table nodes i and i + 1 of
    `count`, a fraction t of the way (Cycles' lookup_table_read)."""
    x = min(max(value, 0.0), 1.0) * (count - 1)
    i = min(int(x), count - 2)
    return i, x - i


def _nodes(count: int, lo: float, hi: float) -> np.ndarray:
    """A table axis as cycles_precompute.cpp spans it: i / (count - 1), clamped to lo..hi."""
    return np.clip(np.arange(count) / (count - 1), lo, hi)


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
    lambda_v = microfacet.ggx_lambda(mu_rows, alpha)
    up = cos_l > 0.0
    g2_over_g1 = np.where(up, (1.0 + lambda_v) / (1.0 + lambda_v + microfacet.ggx_lambda(cos_l, alpha)), 0.0)
    real = f0_from_ior(eta)
    s = np.where(up, np.clip((fresnel_dielectric(cos_hv, 1.0 / eta) - real) / (1.0 - real), 0.0, 1.0), 0.0)
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
        """(gain (n,3), diffuse (n,)) seen from cosines `cos_v (n,)`: the
        multiple-scattering gain 1 + F_ms (1 - E) / E of the lobe (1 without
        multiscatter) and the share of the diffuse base the layer leaves."""
        mu = np.clip(cos_v, 0.0, 1.0)
        s = np.interp(mu, _nodes(S_NODES, 0.0, 1.0), self.s_curve)
        albedo = self.f0[None, :] + (1.0 - self.f0[None, :]) * s[:, None]
        if not self.multiscatter:
            return np.ones((len(mu), 3)), np.clip(1.0 - max_channel(albedo), 0.0, 1.0)
        e = np.interp(mu, _nodes(E_NODES, 0.0, 1.0), self.e_curve)
        missing = (1.0 - e) / e
        fms = self.fss * self.e_avg / (1.0 - self.fss * (1.0 - self.e_avg))
        gain = 1.0 + fms[None, :] * missing[:, None]
        darkening = gain / (1.0 + missing)[:, None]
        return gain, np.clip(1.0 - max_channel(darkening * albedo), 0.0, 1.0)


@dataclass
class Lobe:
    """The specular layers at n shading points, seen from their eye rays.

    active (n,) bool   the point's surface has a layer; the others reflect nothing
    f0 (n,3)           F0 tint;  eta (n,) the IOR of the Fresnel curve
    alpha (n,)         GGX alpha
    gain (n,3)         multiple-scattering gain toward the eye (Layer.toward), 0 where inactive
    """

    active: np.ndarray
    f0: np.ndarray
    eta: np.ndarray
    alpha: np.ndarray
    gain: np.ndarray

    def take(self, idx: np.ndarray) -> "Lobe":
        return Lobe(self.active[idx], np.take(self.f0, idx, axis=0), self.eta[idx], self.alpha[idx],
                    np.take(self.gain, idx, axis=0))

    @property
    def lamp_lit(self) -> np.ndarray:
        """(n,) the points whose lobe lamps light: not a mirror (Cycles evaluates no mirror)."""
        return self.active & (self.alpha * self.alpha > microfacet.SPECULAR_ALPHA2)

    def weight(self, normal: np.ndarray, view: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,3) f cos(theta_l): the lobe's BRDF toward the eye `view (n,3)`
        for light from unit `dirs (n,3)`, times the cosine at `normal (n,3)`:
        F(h.v) D G2 / (4 cos_v) x gain (bsdf_microfacet_eval x energy_scale
        x the darkening in the closure's weight)."""
        half = normalize(view + dirs)
        lobe = microfacet.reflection(dot(normal, view), dot(normal, dirs), dot(normal, half), self.alpha)
        return fresnel(dot(half, view), self.eta, self.f0) * self.gain * lobe[:, None]

    def pdf(self, normal: np.ndarray, view: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) solid-angle density of `sample` drawing `dirs (n,3)`; 0 where inactive."""
        cos_h = dot(normal, normalize(view + dirs))
        pdf = microfacet.reflection_pdf(dot(normal, view), cos_h, self.alpha)
        return np.where(self.active & (cos_h > 0.0), pdf, 0.0)

    def sample(self, normal: np.ndarray, tangent: np.ndarray, bitangent: np.ndarray, view: np.ndarray,
               uv: np.ndarray) -> np.ndarray:
        """(n,3) unit directions reflect(v, h) about microfacet normals h drawn
        from the visible normals (microfacet.sample_visible_normals_local) of the frame
        (tangent, bitangent, normal), from `uv (n,2)`; some fall below the surface."""
        local = normalize(np.stack([dot(tangent, view), dot(bitangent, view), np.maximum(dot(normal, view), 1e-9)],
                                   axis=1))
        h = microfacet.sample_visible_normals_local(local, self.alpha, uv)
        h = h[:, 0:1] * tangent + h[:, 1:2] * bitangent + h[:, 2:3] * normal
        return 2.0 * dot(view, h)[:, None] * h - view
