"""Low-discrepancy point sets in the unit square."""

from __future__ import annotations

import numpy as np

# R2 low-discrepancy sequence (Roberts 2018): x_i = frac(s + i * alpha),
# alpha = (1/g, 1/g^2) with g the plastic number.
_PLASTIC = 1.32471795724474602596
_R2_ALPHA = np.array([1.0 / _PLASTIC, 1.0 / _PLASTIC ** 2])


def r2_sequence(index: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """(n,2) points in [0,1)^2 of the R2 sequence at integer `index (n,)`,
    Cranley-Patterson rotated by `shift`, (2,) for all or (n,2) per point."""
    return np.mod(shift + index[:, None].astype(np.float64) * _R2_ALPHA[None, :], 1.0)
