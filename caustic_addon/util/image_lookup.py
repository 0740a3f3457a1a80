"""Images looked up at continuous coordinates, as Cycles' image textures
are (`kernel/device/cpu/image.h`): pixel centres at ((i + 0.5) / w,
(j + 0.5) / h), row j = 0 at v = 0; Closest, Linear (bilinear) or Cubic (the
uniform cubic B-spline, which Smart also uses on the CPU) interpolation;
and, along each axis, Repeat (wrap), Extend (the edge pixel), Clip (black
outside the image) or Mirror extension."""

from __future__ import annotations

import numpy as np

EXTENSIONS = ("REPEAT", "EXTEND", "CLIP", "MIRROR")
INTERPOLATIONS = ("Closest", "Linear", "Cubic", "Smart")


def _indices(index: np.ndarray, size: int, extension: str) -> tuple[np.ndarray, np.ndarray]:
    """(the pixel indices (...) that integer `index` reads, whether each
    lies inside the image: False only where Clip puts black)."""
    if extension == "REPEAT":
        return np.mod(index, size), np.ones(index.shape, dtype=bool)
    if extension == "MIRROR":
        period = np.mod(index, 2 * size)
        return np.where(period < size, period, 2 * size - 1 - period), np.ones(index.shape, dtype=bool)
    inside = (index >= 0) & (index < size)
    return np.clip(index, 0, size - 1), inside if extension == "CLIP" else np.ones(index.shape, dtype=bool)


def _bspline_weights(t: np.ndarray) -> np.ndarray:
    """(n,4) weights of the uniform cubic B-spline at fraction `t (n,)` for
    the pixels at offsets -1, 0, 1, 2: (1-t)^3/6, (3t^3 - 6t^2 + 4)/6,
    (-3t^3 + 3t^2 + 3t + 1)/6, t^3/6."""
    t2, t3 = t * t, t * t * t
    return np.stack([(1 - t) ** 3, 3 * t3 - 6 * t2 + 4, -3 * t3 + 3 * t2 + 3 * t + 1, t3], axis=1) / 6.0


def lookup(image: np.ndarray, uv: np.ndarray, interpolation: str = "Linear",
           extension: str | tuple[str, str] = "REPEAT") -> np.ndarray:
    """(n,c) values of `image (h,w,c)` at `uv (n,2)` (u across the columns,
    v along the rows); `extension` one mode, or one for u and one for v."""
    h, w = image.shape[:2]
    along_u, along_v = (extension, extension) if isinstance(extension, str) else extension
    if interpolation == "Closest":
        x, y = np.floor(uv[:, 0] * w).astype(np.int64), np.floor(uv[:, 1] * h).astype(np.int64)
        (col, in_u), (row, in_v) = _indices(x, w, along_u), _indices(y, h, along_v)
        return image[row, col] * (in_u & in_v)[:, None]
    x, y = uv[:, 0] * w - 0.5, uv[:, 1] * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = x - x0, y - y0
    if interpolation == "Linear":
        offsets = np.arange(2)
        wx, wy = np.stack([1 - fx, fx], axis=1), np.stack([1 - fy, fy], axis=1)
    else:
        offsets = np.arange(-1, 3)
        wx, wy = _bspline_weights(fx), _bspline_weights(fy)
    cols, in_u = _indices(x0[:, None] + offsets, w, along_u)
    rows, in_v = _indices(y0[:, None] + offsets, h, along_v)
    wx, wy = wx * in_u, wy * in_v
    out = np.zeros((len(uv), image.shape[2]))
    for j in range(len(offsets)):
        row = rows[:, j]
        for i in range(len(offsets)):
            out += image[row, cols[:, i]] * (wy[:, j] * wx[:, i])[:, None]
    return out
