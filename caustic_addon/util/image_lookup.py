"""Images looked up at continuous coordinates, as Cycles' image textures
are (`kernel/device/cpu/image.h`): pixel centres at ((i + 0.5) / w,
(j + 0.5) / h), row j = 0 at v = 0; Closest, Linear (bilinear) or Cubic (the
uniform cubic B-spline, which Smart also uses on the CPU) interpolation;
and, along each axis, Repeat (wrap), Extend (the edge pixel), Clip (black
outside the image) or Mirror extension. The scalar cores (`..1`) and the
kernel over rows of coordinates, for float32, float64 and uint8 images."""

from __future__ import annotations

import math

import numpy as np

from .jit import inline, kernel
from .rows import contiguous

EXTENSIONS = ("REPEAT", "EXTEND", "CLIP", "MIRROR")
INTERPOLATIONS = ("Closest", "Linear", "Cubic", "Smart")
_REPEAT, _EXTEND, _CLIP, _MIRROR = range(4)
_CLOSEST, _LINEAR, _CUBIC = range(3)


@inline
def pixel_index1(index, size, extension):
    """(the pixel index that integer `index` reads along an axis of `size`
    pixels, 1.0 where it lies inside the image or 0.0 where Clip puts
    black), as Cycles' wrap_periodic / wrap_clamp / wrap_mirror
    (kernel/device/cpu/image.h): Repeat index mod size; Mirror p = index mod
    2 size, p if p < size else 2 size - 1 - p; Extend and Clip the index
    clamped to 0 .. size - 1."""
    if extension == _REPEAT:
        return index % size, 1.0
    if extension == _MIRROR:
        period = index % (2 * size)
        return (period if period < size else 2 * size - 1 - period), 1.0
    inside = 1.0 if extension != _CLIP or (0 <= index < size) else 0.0
    return min(max(index, 0), size - 1), inside


@inline
def bspline_weights1(t):
    """The weights of the uniform cubic B-spline at fraction `t` for the
    pixels at offsets -1, 0, 1, 2 (Cycles' cubic interpolation,
    kernel/device/cpu/image.h; de Boor, "A Practical Guide to Splines"):
    (1-t)^3/6, (3t^3 - 6t^2 + 4)/6, (-3t^3 + 3t^2 + 3t + 1)/6, t^3/6."""
    t2, t3 = t * t, t * t * t
    return (math.pow(1.0 - t, 3.0) / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0)


@inline
def axis_taps1(coordinate, size, interpolation):
    """(the first pixel offset's integer index, the weights of the 1, 2 or
    4 pixels read along an axis of `size` pixels at `coordinate` in 0..1,
    as a 4-tuple padded with zeros): Closest the pixel floor(coordinate
    size); Linear and Cubic about x = coordinate size - 1/2, fraction
    t = x - floor(x): (1-t, t) from floor(x), the B-spline's from floor(x) - 1."""
    if interpolation == _CLOSEST:
        return math.floor(coordinate * size), (1.0, 0.0, 0.0, 0.0)
    x = coordinate * size - 0.5
    x0 = math.floor(x)
    t = x - x0
    if interpolation == _LINEAR:
        return x0, (1.0 - t, t, 0.0, 0.0)
    return x0 - 1, bspline_weights1(t)


@kernel("void(f8[:, ::1], f4[:, :, ::1], f8[:, ::1], i8, i8, i8)",
        "void(f8[:, ::1], f8[:, :, ::1], f8[:, ::1], i8, i8, i8)",
        "void(f8[:, ::1], u1[:, :, ::1], f8[:, ::1], i8, i8, i8)")
def _lookup_rows(out, image, uv, interpolation, along_u, along_v):
    """out (n,c) = the sum over the taps of pixel x its two axes' weights,
    row taps outer, column taps inner."""
    h, w, channels = image.shape
    taps = 1 if interpolation == _CLOSEST else (2 if interpolation == _LINEAR else 4)
    for n in range(len(uv)):
        x0, wx = axis_taps1(uv[n, 0], w, interpolation)
        y0, wy = axis_taps1(uv[n, 1], h, interpolation)
        for c in range(channels):
            out[n, c] = 0.0
        for j in range(taps):
            row, in_v = pixel_index1(y0 + j, h, along_v)
            weight_v = wy[j] * in_v
            for i in range(taps):
                col, in_u = pixel_index1(x0 + i, w, along_u)
                weight = weight_v * (wx[i] * in_u)
                for c in range(channels):
                    out[n, c] += image[row, col, c] * weight


def lookup(image: np.ndarray, uv: np.ndarray, interpolation: str = "Linear",
           extension: str | tuple[str, str] = "REPEAT") -> np.ndarray:
    """(n,c) float64 values of `image (h,w,c)` (float32, float64 or uint8,
    C-contiguous to be read without a copy) at `uv (n,2)` (u across the
    columns, v along the rows); `extension` one mode, or one for u and one for v."""
    along_u, along_v = (extension, extension) if isinstance(extension, str) else extension
    mode = min(INTERPOLATIONS.index(interpolation), _CUBIC)
    image = np.ascontiguousarray(image)
    out = np.empty((len(uv), image.shape[2]))
    _lookup_rows(out, image, contiguous(uv, np.float64), mode, EXTENSIONS.index(along_u), EXTENSIONS.index(along_v))
    return out
