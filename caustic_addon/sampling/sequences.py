"""Low-discrepancy point sets in the unit square."""

from __future__ import annotations

import numpy as np

from ..util.jit import inline, kernel

# R2 low-discrepancy sequence (Roberts 2018): x_i = frac(s + i * alpha),
# alpha = (1/g, 1/g^2) with g the plastic number.
_PLASTIC = 1.32471795724474602596
_R2_X, _R2_Y = 1.0 / _PLASTIC, 1.0 / _PLASTIC ** 2


@inline
def r2_point1(index, shift_x, shift_y):
    """(x, y) in [0,1)^2: point `index` of the R2 sequence, Cranley-Patterson
    rotated by (shift_x, shift_y)."""
    return (shift_x + np.float64(index) * _R2_X) % 1.0, (shift_y + np.float64(index) * _R2_Y) % 1.0


def r2_sequence(index: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """(n,2) points in [0,1)^2 of the R2 sequence at integer `index (n,)`,
    Cranley-Patterson rotated by `shift`, (2,) for all or (n,2) per point."""
    out = np.empty((len(index), 2))
    _r2_rows(out, np.ascontiguousarray(index, dtype=np.int64),
             np.array(np.broadcast_to(shift, out.shape), dtype=np.float64, order="C"))
    return out


@kernel("void(f8[:, ::1], i8[::1], f8[:, ::1])")
def _r2_rows(out, index, shift):
    for i in range(len(index)):
        out[i, 0], out[i, 1] = r2_point1(index[i], shift[i, 0], shift[i, 1])
