"""Specular optics at a smooth interface, vectorised over rays.

Conventions for every function: `d (n,3)` is the unit direction the light
travels along; `n (n,3)` is the unit normal on the side the light comes from,
so dot(d, n) <= 0; `eta (n,)` or scalar is eta_i / eta_t, the index of the
medium the light leaves over that of the medium it enters. Work in float64:
the refraction of nearly grazing rays loses about half its digits in float32.
"""

from __future__ import annotations

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of (n,3) arrays -> (n,)."""
    return np.einsum("ij,ij->i", a, b)


# Row-wise reductions over 3 values are spelt out below: numpy's reductions
# along a short last axis (norm, max or sum with axis=1) run 3 to 8 times
# slower than einsum or two elementwise calls (numpy 2.x, measured on
# (20000,3) arrays).


def length(v: np.ndarray) -> np.ndarray:
    """(n,) Euclidean lengths of the rows of `v (n,3)`."""
    return np.sqrt(dot(v, v))


def normalize(v: np.ndarray) -> np.ndarray:
    """Rows of `v (n,3)` scaled to unit length; zero rows stay zero."""
    size = length(v)[:, None]
    return v / np.where(size > 0, size, 1.0)


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,3) row-wise cross products of `a (n,3)` and `b (n,3)`."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def max_channel(c: np.ndarray) -> np.ndarray:
    """(n,) the largest of the three channels of `c (n,3)`."""
    return np.maximum(np.maximum(c[:, 0], c[:, 1]), c[:, 2])


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


def beer_lambert(absorption: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """Transmittance exp(-sigma_a * s) of a path of length `distance (n,)`
    through a medium with absorption coefficient `absorption (n,3)` per metre."""
    return np.exp(-absorption * distance[:, None])


# Fraunhofer lines that define the Abbe number (nm): helium d, hydrogen F and C.
LAMBDA_D, LAMBDA_F, LAMBDA_C = 587.6, 486.1, 656.3


def cauchy_ior(ior_d, abbe, wavelength_nm):
    """Index of refraction at `wavelength_nm` of a glass given by its index
    n_d at 587.6 nm and its Abbe number V_d, by Cauchy's two-term law
    (Hecht, Optics, 3.5; Abbe number as in ISO 7944):

        n(lambda) = A + B / lambda^2
        V_d = (n_d - 1) / (n_F - n_C)   =>   B = (n_d - 1) / (V_d (1/lambda_F^2 - 1/lambda_C^2)),
                                             A = n_d - B / lambda_d^2

    An infinite Abbe number gives n_d at every wavelength. Broadcasts."""
    ior_d = np.asarray(ior_d, dtype=np.float64)
    b = (ior_d - 1.0) / (np.asarray(abbe, dtype=np.float64) * (LAMBDA_F ** -2 - LAMBDA_C ** -2))
    return ior_d + b * (np.asarray(wavelength_nm, dtype=np.float64) ** -2 - LAMBDA_D ** -2)


def absorption_from_color(color, distance: float) -> np.ndarray:
    """Absorption coefficient sigma_a (3,) per metre of a medium whose
    transmittance after `distance` metres is `color` (3,) in (0, 1]:
    exp(-sigma_a d) = color, so sigma_a = -ln(color) / d (Beer-Lambert; the
    "transmission colour at depth" of other renderers)."""
    return -np.log(np.asarray(color, dtype=np.float64)) / distance


def volume_absorption(color, density: float) -> np.ndarray:
    """Absorption coefficient (3,) per metre of Blender's Volume Absorption
    node: sigma_a = density * (1 - color), colour and density clamped at 0
    (Cycles `svm_node_closure_volume` in kernel/svm/closure.h; EEVEE's
    gpu_shader_material_volume_absorption.glsl)."""
    return max(float(density), 0.0) * (1.0 - np.maximum(np.asarray(color, dtype=np.float64), 0.0))
