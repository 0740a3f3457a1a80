"""Colours: linear Rec.709 RGB as (3,) float64 arrays."""

from __future__ import annotations

import numpy as np

RGB = np.ndarray  # (3,) float64, linear


def rgb(value) -> RGB:
    """A colour from a scalar or a 3-sequence, as a (3,) float64 array."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,):
        raise ValueError(f"a colour has 3 components, got shape {arr.shape}")
    return arr
