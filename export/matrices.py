"""Blender's matrices as numpy."""

import numpy as np


def numpy_matrix(matrix) -> np.ndarray:
    """(4,4) float64 of a mathutils Matrix."""
    return np.array(matrix, dtype=np.float64).reshape(4, 4)
