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
