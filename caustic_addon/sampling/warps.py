"""Maps of the unit square onto discs, cones of directions and frames around an axis."""

from __future__ import annotations

import math

import numpy as np


def orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) that make a right-handed frame with unit `axis (3,)`
    (Duff et al. 2017, "Building an orthonormal basis, revisited")."""
    sign = math.copysign(1.0, axis[2])
    a = -1.0 / (sign + axis[2])
    b = axis[0] * axis[1] * a
    return (np.array([1.0 + sign * axis[0] ** 2 * a, sign * b, -sign * axis[0]]),
            np.array([b, sign + axis[1] ** 2 * a, -axis[1]]))


def sample_disc(radius: float, uv: np.ndarray) -> np.ndarray:
    """(n,2) points uniform over a disc: r = R sqrt(u), phi = 2 pi v."""
    r = radius * np.sqrt(uv[:, 0])
    phi = 2.0 * math.pi * uv[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def concentric_disc(uv: np.ndarray) -> np.ndarray:
    """Shirley and Chiu's equal-area map of the unit square `uv (n,2)` onto
    the unit disc, (n,2)."""
    a, b = 2.0 * uv[:, 0] - 1.0, 2.0 * uv[:, 1] - 1.0
    first = np.abs(a) > np.abs(b)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(first, a, b)
        phi = np.where(first, 0.25 * math.pi * b / a, 0.5 * math.pi - 0.25 * math.pi * a / b)
    phi = np.where((a == 0) & (b == 0), 0.0, phi)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def frames(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """orthonormal_basis for each of `axes (n,3)` (unit): (t (n,3), b (n,3))."""
    sign = np.where(axes[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + axes[:, 2])
    b = axes[:, 0] * axes[:, 1] * a
    t = np.stack([1.0 + sign * axes[:, 0] ** 2 * a, sign * b, -sign * axes[:, 0]], axis=1)
    return t, np.stack([b, sign + axes[:, 1] ** 2 * a, -axes[:, 1]], axis=1)


def cone_directions(axes: np.ndarray, cos_max: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) unit directions uniform in solid angle within acos(cos_max (n,))
    of `axes (n,3)`: the concentric disc point of `uv (n,2)` at radius rho
    goes to cos(theta) = 1 - rho^2 (1 - cos_max), its azimuth kept
    (Archimedes' hat-box theorem)."""
    disc = concentric_disc(uv)
    rho2 = disc[:, 0] ** 2 + disc[:, 1] ** 2
    cos_t = 1.0 - rho2 * (1.0 - cos_max)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    rho = np.sqrt(rho2)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(rho > 0, disc[:, 0] / rho, 1.0)
        s = np.where(rho > 0, disc[:, 1] / rho, 0.0)
    t, b = frames(axes)
    return (sin_t * c)[:, None] * t + (sin_t * s)[:, None] * b + cos_t[:, None] * axes


def cosine_hemisphere(normals: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(n,3) unit directions about `normals (n,3)` with density cos(theta) / pi
    (Malley's method: the concentric disc point lifted onto the hemisphere)."""
    disc = concentric_disc(uv)
    z = np.sqrt(np.maximum(0.0, 1.0 - disc[:, 0] ** 2 - disc[:, 1] ** 2))
    t, b = frames(normals)
    return disc[:, :1] * t + disc[:, 1:] * b + z[:, None] * normals
