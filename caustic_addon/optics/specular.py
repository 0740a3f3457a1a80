"""Specular optics at a smooth interface, vectorised over rays.

Conventions for every function: `d (n,3)` is the unit direction the light
travels along; `n (n,3)` is the unit normal on the side the light comes from,
so dot(d, n) <= 0; `eta (n,)` or scalar is eta_i / eta_t, the index of the
medium the light leaves over that of the medium it enters. Work in float64:
the refraction of nearly grazing rays loses about half its digits in float32.
"""

from __future__ import annotations

import numpy as np

from ..util.vectors import dot


def reflect(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Mirror reflection r = d - 2 (d.n) n (the paper's eq. 3, after De Greve 2006)."""
    return d - 2.0 * dot(d, n)[:, None] * n


def refract(d: np.ndarray, n: np.ndarray, eta) -> tuple[np.ndarray, np.ndarray]:
    """Snell refraction, the paper's eqs. (4)-(6) in De Greve's robust form.

        cos_i = -d.n,  sin2_t = eta^2 (1 - cos_i^2)
        t = eta d + (eta cos_i - sqrt(1 - sin2_t)) n

    Returns (t (n,3), tir (n,)): `tir` marks total internal reflection
    (cos_t^2 < 0), where t is meaningless and the caller must reflect.
    cos_t^2 = 1 - eta^2 (1 - cos_i^2) is evaluated as
    (1 - eta)(1 + eta) + eta^2 cos_i^2, which keeps its digits at grazing
    incidence when eta is near 1.
    """
    eta = np.broadcast_to(np.asarray(eta, dtype=np.float64), d.shape[:1])
    cos_i = np.clip(-dot(d, n), 0.0, 1.0)
    cos2_t = cos2_transmitted(cos_i, eta)
    tir = cos2_t < 0.0
    cos_t = np.sqrt(np.maximum(0.0, cos2_t))
    t = eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n
    return t, tir


def cos2_transmitted(cos_i: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """cos^2 of the refraction angle by Snell's law, negative under total
    internal reflection: (1 - eta)(1 + eta) + eta^2 cos_i^2."""
    return (1.0 - eta) * (1.0 + eta) + eta * eta * cos_i * cos_i


def fresnel_dielectric(cos_i: np.ndarray, eta) -> np.ndarray:
    """Exact unpolarised Fresnel reflectance F = (Rs + Rp) / 2 (Hecht, Optics, 4.34/4.35).

        Rs = ((eta cos_i - cos_t) / (eta cos_i + cos_t))^2
        Rp = ((cos_i - eta cos_t) / (cos_i + eta cos_t))^2

    with eta = eta_i / eta_t and cos_t from Snell's law. F = 1 past the
    critical angle (total internal reflection). At exactly grazing incidence
    both ratios are 0/0; their limit is 1, or 0 for matched indices (eta = 1).
    """
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    eta = np.broadcast_to(np.asarray(eta, dtype=np.float64), cos_i.shape)
    cos2_t = cos2_transmitted(cos_i, eta)
    cos_t = np.sqrt(np.maximum(0.0, cos2_t))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
        rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    f = 0.5 * (rs * rs + rp * rp)
    f = np.where(np.isfinite(f), f, np.where(eta == 1.0, 0.0, 1.0))
    return np.where(cos2_t < 0.0, 1.0, np.clip(f, 0.0, 1.0))
