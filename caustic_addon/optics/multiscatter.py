"""The light a single-scattering GGX surface loses, and Cycles' Multiscatter
GGX factor that gives it back.

A path scattered about one sampled microfacet normal keeps G2 / G1 of its
weight, and dies if it leaves on the wrong side: light that real
microfacets would bounce again. Multiscatter GGX, the default of Blender's
Glass, Glossy and Principled BSDFs, restores it as Cycles does
(`bsdf_microfacet.h`, `microfacet_ggx_preserve_energy`, after Kulla and
Conty 2017, "Revisiting physically based shading at Imageworks"): the
directional albedo E(mu) of the single-scattering lobe (reflection, or
reflection plus refraction for glass), and its cosine-weighted mean E_avg,
give the factor

    1 + F_ms (1 - E) / E,   F_ms = F E_avg / (1 - F (1 - E_avg))

with F the surface's colour (1/E for white), E at the cosine of the
direction toward the eye and from the table of the eye's side of the
surface (passes.bounce.multiscatter). Cycles reads E from tables it ships
(`ggx_E`, and `ggx_glass_E` over roughness, cosine and IOR for glass);
here E is integrated for each roughness and IOR a scene uses, by
stratified quadrature over the same visible-normal sampler the passes use,
so the factor makes a white surface as bright as a white world around it
(the white furnace).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..util.jit import inline, kernel
from ..util.vectors import DIVISION_FLOOR, float_rows, row, set_row
from .microfacet import sample_visible_normals_local, shadowing_weight
from .specular import fresnel_dielectric, reflect, refract

# Cosines of incidence at which E is tabulated, the midpoints of equal steps.
ALBEDO_COSINES = 32
# Jittered microfacet samples per tabulated cosine: a side of this many
# strata. The integrand steps to 0 where reflections leave below the
# horizon, a sliver near the disc's rim that a grid of midpoints misses
# (64 x 64 midpoints overestimate E by 1.2% at alpha 0.16, mu 0.95); jittered
# strata are unbiased: 64 x 64 give E within 1e-3 on average (the spread of
# five seeds, 2e-3 at worst) in 0.04 s a table, 128 x 128 within 3e-4 in 0.15 s.
ALBEDO_SIDE = 64


def albedo_cosines() -> np.ndarray:
    """(k,) the cosines of incidence E is tabulated at."""
    return (np.arange(ALBEDO_COSINES) + 0.5) / ALBEDO_COSINES


def _jittered_square(side: int, count: int) -> np.ndarray:
    """(count * side^2, 2): `count` sets of one point in each cell of a
    side x side grid over the unit square, at random within it (a fixed
    seed, so the tables are the same every time)."""
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)
    jitter = np.random.default_rng(0).random((count * side * side, 2))
    return (np.tile(cells, (count, 1)) + jitter) / side


@lru_cache(maxsize=256)
def single_scatter_albedo(alpha: float, eta: float | None, side: int = ALBEDO_SIDE) -> np.ndarray:
    """(k,) directional albedo E(mu) at `albedo_cosines()` of a single-
    scattering GGX surface of width `alpha`: a mirror (`eta` None) or an
    interface of eta = eta_i / eta_t, both branches weighted by their Fresnel
    at the sampled normal (Cycles' glass table, `ggx_glass_E`, is the same
    integral). E(mu) = mean over visible normals h of
    [F G2/G1 where the reflection leaves above] + [(1 - F) G2/G1 where the
    refraction leaves below], side^2 jittered strata of normals per cosine."""
    mu = albedo_cosines()
    n = side * side
    wi = np.repeat(np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), mu], axis=1), n, axis=0)
    a = np.full(len(wi), alpha)
    h = sample_visible_normals_local(wi, a, _jittered_square(side, len(mu)))
    d = -wi
    cos_in = wi[:, 2]
    out = reflect(d, h)
    kept = np.where(out[:, 2] > 0.0, shadowing_weight(cos_in, out[:, 2], a), 0.0)
    if eta is not None:
        f = fresnel_dielectric(np.einsum("ij,ij->i", wi, h), eta)
        through, tir = refract(d, h, eta)
        crossed = np.where(~tir & (through[:, 2] < 0.0), shadowing_weight(cos_in, -through[:, 2], a), 0.0)
        kept = f * kept + (1.0 - f) * crossed
    return kept.reshape(len(mu), n).mean(axis=1)


def average_albedo(albedo: np.ndarray) -> np.ndarray:
    """E_avg = 2 int_0^1 E(mu) mu dmu over the tabulated cosines (midpoint
    rule), for `albedo (..., k)`."""
    mu = albedo_cosines()
    return 2.0 * (albedo * mu).mean(axis=-1)


@inline
def albedo_at1(table, mu):
    """E at the cosine `mu` from `table (k,)` (E at albedo_cosines()),
    linear between the tabulated cosines, clamped at the ends."""
    k = len(table)
    x = min(max(mu * k - 0.5, 0.0), k - 1.0)
    lo = min(int(x), k - 2)
    frac = x - lo
    return table[lo] * (1.0 - frac) + table[lo + 1] * frac


@inline
def multiscatter_factor1(albedo, albedo_avg, color):
    """(3-tuple) Cycles' Multiscatter GGX weight 1 + F_ms (1 - E) / E with
    F_ms = F E_avg / (1 - F (1 - E_avg)), for `albedo` E at the incoming
    cosine, `albedo_avg` E_avg and `color` (3-tuple) F, the surface's
    colour (Kulla and Conty 2017; Cycles' `microfacet_ggx_preserve_energy`);
    both divisors floored at DIVISION_FLOOR."""
    return (_factor1(albedo, albedo_avg, color[0]), _factor1(albedo, albedo_avg, color[1]),
            _factor1(albedo, albedo_avg, color[2]))


@inline
def _factor1(e, e_avg, f):
    """multiscatter_factor1 of one channel of colour `f`."""
    f_ms = f * e_avg / max(1.0 - f * (1.0 - e_avg), DIVISION_FLOOR)
    return 1.0 + f_ms * (1.0 - e) / max(e, DIVISION_FLOOR)


@kernel("void(f8[:, ::1], f8[::1], f8[::1])")
def _albedos(table, mu, out):
    for i in range(len(mu)):
        out[i] = albedo_at1(table[i], mu[i])


@kernel("void(f8[::1], f8[::1], f8[:, ::1], f8[:, ::1])")
def _factors(albedo, albedo_avg, color, out):
    for i in range(len(albedo)):
        set_row(out, i, multiscatter_factor1(albedo[i], albedo_avg[i], row(color, i)))


def albedo_at(table: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """(n,) albedo_at1 at cosines `mu (n,)` of the rows of `table (n,k)`
    (each row its own surface)."""
    (table,), (mu,) = float_rows(table), float_rows(mu)
    out = np.empty(len(mu))
    _albedos(table, mu, out)
    return out


def multiscatter_factor(albedo: np.ndarray, albedo_avg: np.ndarray, color: np.ndarray) -> np.ndarray:
    """(n,3) multiscatter_factor1 of each row: `albedo, albedo_avg (n,)`, `color (n,3)`."""
    albedo, albedo_avg = float_rows(albedo, albedo_avg)
    out = np.empty((len(albedo), 3))
    _factors(albedo, albedo_avg, *float_rows(color), out)
    return out
