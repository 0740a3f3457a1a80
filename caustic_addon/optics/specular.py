"""Specular optics at a smooth interface: scalar forms for kernels (the
`...1` functions, over 3-tuples) and array kernels over rays for numpy
callers, one implementation.

Conventions for every function: `d (n,3)` is the unit direction the light
travels along; `n (n,3)` is the unit normal on the side the light comes from,
so dot(d, n) <= 0; `eta (n,)` or scalar is eta_i / eta_t, the index of the
medium the light leaves over that of the medium it enters. Work in float64:
the refraction of nearly grazing rays loses about half its digits in float32.
"""

from __future__ import annotations

import math

import numpy as np

from ..util.jit import inline, kernel
from ..util.vectors import dot1, float_rows, row, scale1, set_row, sum1


@inline
def reflect1(d, n):
    """Mirror reflection r = d - 2 (d.n) n (the paper's eq. 3, after De Greve 2006)."""
    return sum1(1.0, d, -2.0 * dot1(d, n), n)


@inline
def valid_reflection_normal1(ng, i, n):
    """The shading normal `n` raised toward the geometric normal `ng` just
    enough that the mirror reflection of `i` (unit, toward where the ray
    came from, i.ng >= 0) about it leaves the surface at least min(0.9
    i.ng, 0.01) above it; `n` itself where it already does. Cycles'
    ensure_valid_specular_reflection (kernel/closure/bsdf_util.h), which it
    applies to a glass's, a mirror's and a metal's normal under the
    material's Bump Map Correction (on by default): in the frame of ng and
    the part of n across it, N' = (x, 0, z) with 2 (N'.i) z - i.z = t gives
    4 a z^4 - 2 b z^2 + c = 0, a = i.x^2 + i.z^2, b = 2 (a + i.z t),
    c = (i.z + t)^2, of which one root solves the unsquared equation."""
    iz = dot1(i, ng)
    threshold = min(0.9 * iz, 0.01)
    if dot1(ng, sum1(2.0 * dot1(n, i), n, -1.0, i)) >= threshold:
        return n
    across = sum1(1.0, n, -dot1(n, ng), ng)
    length = math.sqrt(dot1(across, across))
    x_axis = scale1(1.0 / length, across) if length > 0.0 else n
    ix = dot1(i, x_axis)
    a = ix * ix + iz * iz
    b = 2.0 * (a + iz * threshold)
    c = (threshold + iz) * (threshold + iz)
    root = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    nz2 = 0.25 * (b + root) / a if ix < 0.0 else 0.25 * (b - root) / a
    return sum1(math.sqrt(max(1.0 - nz2, 0.0)), x_axis, math.sqrt(max(nz2, 0.0)), ng)


@inline
def cos2_transmitted1(cos_i, eta):
    """cos^2 of the refraction angle by Snell's law, negative under total
    internal reflection: 1 - eta^2 (1 - cos_i^2), evaluated as
    (1 - eta)(1 + eta) + eta^2 cos_i^2, which keeps its digits at grazing
    incidence when eta is near 1."""
    return (1.0 - eta) * (1.0 + eta) + eta * eta * cos_i * cos_i


@inline
def refract1(d, n, eta):
    """Snell refraction, the paper's eqs. (4)-(6) in De Greve's robust form.

        cos_i = -d.n,  cos_t^2 = cos2_transmitted1(cos_i, eta)
        t = eta d + (eta cos_i - cos_t) n

    Returns (t, tir): `tir` marks total internal reflection (cos_t^2 < 0),
    where t is meaningless and the caller must reflect."""
    cos_i = min(max(-dot1(d, n), 0.0), 1.0)
    cos2_t = cos2_transmitted1(cos_i, eta)
    cos_t = math.sqrt(max(0.0, cos2_t))
    return sum1(eta, d, eta * cos_i - cos_t, n), cos2_t < 0.0


@inline
def fresnel_dielectric1(cos_i, eta):
    """Exact unpolarised Fresnel reflectance F = (Rs + Rp) / 2 (Hecht, Optics, 4.34/4.35).

        Rs = ((eta cos_i - cos_t) / (eta cos_i + cos_t))^2
        Rp = ((cos_i - eta cos_t) / (cos_i + eta cos_t))^2

    with eta = eta_i / eta_t, cos_i clamped to 0..1 and cos_t from Snell's
    law. F = 1 past the critical angle (total internal reflection). At
    exactly grazing incidence both ratios are 0/0; their limit is 1, or 0
    for matched indices (eta = 1)."""
    cos_i = min(max(cos_i, 0.0), 1.0)
    cos2_t = cos2_transmitted1(cos_i, eta)
    if cos2_t < 0.0:
        return 1.0
    cos_t = math.sqrt(cos2_t)
    s_den, p_den = eta * cos_i + cos_t, cos_i + eta * cos_t
    if s_den == 0.0 or p_den == 0.0:
        return 0.0 if eta == 1.0 else 1.0
    rs, rp = (eta * cos_i - cos_t) / s_den, (cos_i - eta * cos_t) / p_den
    return min(max(0.5 * (rs * rs + rp * rp), 0.0), 1.0)


@inline
def radiance_scale1(eta):
    """What radiance keeps of itself, beyond the Fresnel transmittance, where
    a ray of eta = eta_i / eta_t refracts and radiance flows back along it:
    eta^2. Radiance over eta^2 is what a refraction conserves (Veach 1997,
    sec. 5.2, L_i / eta_i^2 = T L_t / eta_t^2), so a floor under water seen
    from the air is 1 / 1.33^2 as bright as under the air. Along a path the
    factors telescope: a closed glass's entry and exit cancel."""
    return eta * eta


def basic_irradiance_scale(ior: np.ndarray) -> np.ndarray:
    """(n,) what a receiver inside a medium of index `ior (n,)` shows of its
    irradiance E to a renderer whose paths take no factor at refractions,
    as Cycles and EEVEE: the basic irradiance E / n^2 (Veach 1997, sec. 5.2),
    the irradiance that radiance over n^2 gives. A baked caustic under water
    holds it, so Cycles shows the floor's caustic as bright as ours."""
    return 1.0 / (ior * ior)


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1])")
def _reflect_rows(d, n, out):
    for i in range(len(d)):
        set_row(out, i, reflect1(row(d, i), row(n, i)))


@kernel("void(f8[:, ::1], f8[:, ::1], f8[::1], f8[:, ::1], b1[::1])")
def _refract_rows(d, n, eta, out, tir):
    for i in range(len(d)):
        t, total = refract1(row(d, i), row(n, i), eta[i])
        set_row(out, i, t)
        tir[i] = total


@kernel("void(f8[::1], f8[::1], f8[::1])")
def _fresnel_values(cos_i, eta, out):
    for i in range(len(cos_i)):
        out[i] = fresnel_dielectric1(cos_i[i], eta[i])


def reflect(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(n,3) reflect1 of each row of `d` about `n` (rows broadcast)."""
    d, n = float_rows(d, n)
    out = np.empty_like(d)
    _reflect_rows(d, n, out)
    return out


def refract(d: np.ndarray, n: np.ndarray, eta) -> tuple[np.ndarray, np.ndarray]:
    """refract1 of each row: (t (n,3), tir (n,) bool)."""
    d, n = float_rows(d, n)
    (eta,) = float_rows(np.broadcast_to(np.asarray(eta, dtype=np.float64), d.shape[:1]))
    out, tir = np.empty_like(d), np.empty(len(d), dtype=bool)
    _refract_rows(d, n, eta, out, tir)
    return out, tir


def fresnel_dielectric(cos_i, eta) -> np.ndarray:
    """fresnel_dielectric1 of each element of `cos_i` and `eta` (broadcast), in their shape."""
    cos_i, eta = float_rows(cos_i, eta)
    out = np.empty(cos_i.shape)
    _fresnel_values(cos_i.ravel(), eta.ravel(), out.reshape(-1))
    return out
