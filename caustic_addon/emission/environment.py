"""The world's light as directions: its radiance in any direction, and
directions sampled in proportion to it (a piecewise-constant 2D
distribution over the lat-long image, rows weighted by sin(theta): pbrt-v4's
ImageInfiniteLight, Cycles' background map), with their solid-angle
density, so the eye pass can importance-sample a bright sky, and the pass
from the lamps find an HDRI's sun (world_sun.py).

What the camera sees is the image looked up bilinearly, as Cycles' Linear
interpolation; what lights the scene is each pixel's own value
(`Environment.light`), as pbrt-v4's ImageLe does, so that a sample's
radiance over its density is the same everywhere in a pixel: a sun a few
pixels wide, looked up bilinearly under a density constant per pixel,
would make every sample of it a different weight, and the floor grainy.

The mapping is Cycles' equirectangular one (`direction_to_equirectangular`):
u = 0.5 - atan2(y, x) / (2 pi), v = acos(z) / pi from the top row, so +Z is
row 0 and +X the image's middle column."""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..scene import World
from ..util.image_lookup import lookup
from ..util.jit import inline, kernel
from ..util.rows import contiguous
from ..util.vectors import DIVISION_FLOOR, row, set_row
from .kept_worlds import per_world


@inline
def direction_to_uv1(d):
    """(u, v) in [0,1)^2 of the unit 3-tuple `d`, Cycles'
    direction_to_equirectangular: u = (0.5 - atan2(y, x) / (2 pi)) mod 1,
    v = acos(z) / pi, from the top row."""
    u = (0.5 - math.atan2(d[1], d[0]) / (2.0 * math.pi)) % 1.0
    return u, math.acos(min(max(d[2], -1.0), 1.0)) / math.pi


@inline
def uv_to_direction1(u, v):
    """The unit 3-tuple of image coordinates (u, v): phi = (0.5 - u) 2 pi,
    theta = v pi, (sin theta cos phi, sin theta sin phi, cos theta)."""
    phi, theta = (0.5 - u) * 2.0 * math.pi, v * math.pi
    sin_t = math.sin(theta)
    return sin_t * math.cos(phi), sin_t * math.sin(phi), math.cos(theta)


@inline
def pixel_of1(d, h, w):
    """(row, col) of the pixel of an h x w lat-long image that the unit
    3-tuple `d` falls in."""
    u, v = direction_to_uv1(d)
    return min(max(int(v * h), 0), h - 1), min(max(int(u * w), 0), w - 1)


@inline
def image_density1(d, row_pdf, col_pdf):
    """The solid-angle density at which an image is sampled toward the
    unit 3-tuple `d`: p_pixel w h / (2 pi^2 sin(theta)), p_pixel =
    row_pdf[row] col_pdf[row, col] (each pixel's solid angle is
    2 pi^2 sin(theta) / (w h))."""
    h, w = col_pdf.shape
    r, c = pixel_of1(d, h, w)
    sin_t = math.sqrt(max(0.0, 1.0 - d[2] * d[2]))
    return row_pdf[r] * col_pdf[r, c] * w * h / (2.0 * math.pi ** 2 * max(sin_t, DIVISION_FLOOR))


@inline
def last_at_or_below1(cdf, x):
    """The last index i of the ascending `cdf` with cdf[i] <= x, -1 if none
    (np.searchsorted(cdf, x, side="right") - 1)."""
    lo, hi = 0, len(cdf)
    while lo < hi:
        mid = (lo + hi) // 2
        if cdf[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo - 1


@kernel("void(f8[:, ::1], f8[:, ::1])")
def _uv_rows(dirs, out):
    for i in range(len(dirs)):
        out[i, 0], out[i, 1] = direction_to_uv1(row(dirs, i))


@kernel("void(f8[:, ::1], f8[:, ::1])")
def _direction_rows(uv, out):
    for i in range(len(uv)):
        set_row(out, i, uv_to_direction1(uv[i, 0], uv[i, 1]))


@kernel("void(f8[:, ::1], f8[:, :, ::1], f8[::1], f8[:, ::1])")
def _light_rows(dirs, image, color, out):
    h, w = image.shape[0], image.shape[1]
    for i in range(len(dirs)):
        r, c = pixel_of1(row(dirs, i), h, w)
        for k in range(3):
            out[i, k] = image[r, c, k] * color[k]


@kernel("void(f8[:, ::1], f8[::1], f8[:, ::1], f8[::1])")
def _densities(dirs, row_pdf, col_pdf, out):
    for i in range(len(dirs)):
        out[i] = image_density1(row(dirs, i), row_pdf, col_pdf)


@kernel("void(f8[:, ::1], f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1])")
def _image_samples(uv, cdf_rows, row_pdf, cdf_cols, col_pdf, dirs, density):
    """Environment.sample of an image: a row by its CDF at uv[:, 1], a
    column by that row's at uv[:, 0], uniform within the pixel."""
    h, w = col_pdf.shape
    for i in range(len(uv)):
        r = min(max(last_at_or_below1(cdf_rows, uv[i, 1]), 0), h - 1)
        v = (r + (uv[i, 1] - cdf_rows[r]) / max(row_pdf[r], DIVISION_FLOOR)) / h
        c = min(max(last_at_or_below1(cdf_cols[r], uv[i, 0]), 0), w - 1)
        u = (c + (uv[i, 0] - cdf_cols[r, c]) / max(col_pdf[r, c], DIVISION_FLOOR)) / w
        d = uv_to_direction1(u, min(max(v, 0.0), 1.0))
        set_row(dirs, i, d)
        density[i] = image_density1(d, row_pdf, col_pdf)


def directions_to_uv(dirs: np.ndarray) -> np.ndarray:
    """(n,2) direction_to_uv1 of each of the unit `dirs (n,3)`."""
    out = np.empty((len(dirs), 2))
    _uv_rows(contiguous(dirs, np.float64), out)
    return out


def uv_to_directions(uv: np.ndarray) -> np.ndarray:
    """(n,3) uv_to_direction1 of each of `uv (n,2)`."""
    out = np.empty((len(uv), 3))
    _direction_rows(contiguous(uv, np.float64), out)
    return out


def row_solid_angles(h: int, w: int) -> np.ndarray:
    """(h,) the solid angle (sr) of a pixel in each row of an h x w lat-long
    image: (2 pi / w) (pi / h) sin(theta) at the row's centre."""
    theta = (np.arange(h) + 0.5) / h * math.pi
    return (2.0 * math.pi / w) * (math.pi / h) * np.sin(theta)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """(...) Rec.709 luminance of linear `rgb (..., 3)`."""
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


class Environment:
    """A world, ready to evaluate and, if it has an image, to sample by its
    pixels' luminance times sin(theta) (each pixel's solid angle), with a
    density of p_pixel w h / (2 pi^2 sin(theta)) per steradian."""

    def __init__(self, world: World):
        self.world = world
        image = world.environment
        if image is None:
            return
        h, w = image.shape[:2]
        theta = (np.arange(h) + 0.5) / h * math.pi
        weight = np.maximum(luminance(image * world.color), 0.0) * np.sin(theta)[:, None]
        if not weight.sum() > 0:
            weight = np.sin(theta)[:, None] * np.ones((1, w))
        rows = weight.sum(axis=1)
        self.row_pdf = rows / rows.sum()
        self.cdf_rows = np.concatenate([[0.0], np.cumsum(self.row_pdf)])
        self.col_pdf = np.ascontiguousarray(weight / np.maximum(rows[:, None], DIVISION_FLOOR))
        self.cdf_cols = np.concatenate([np.zeros((h, 1)), np.cumsum(self.col_pdf, axis=1)], axis=1)

    @cached_property
    def mean_level(self) -> float:
        """The mean over the sphere of the radiance that lights the scene,
        W/(m^2 sr), max channel."""
        image = self.world.environment
        if image is None:
            return float(np.max(self.world.color))
        solid_angle = row_solid_angles(*image.shape[:2])
        mean = (image * solid_angle[:, None, None]).sum(axis=(0, 1)) / (4.0 * math.pi)
        return float(np.max(mean * self.world.color))

    def light(self, dirs: np.ndarray) -> np.ndarray:
        """(n,3) W/(m^2 sr) that lights the scene from `dirs (n,3)`: the
        pixel each falls in, times the world's colour."""
        image = self.world.environment
        if image is None:
            return np.broadcast_to(self.world.color, (len(dirs), 3)).copy()
        out = np.empty((len(dirs), 3))
        _light_rows(contiguous(dirs, np.float64), image, contiguous(self.world.color, np.float64), out)
        return out

    def radiance(self, dirs: np.ndarray) -> np.ndarray:
        """(n,3) W/(m^2 sr) the eye sees toward `dirs (n,3)`: the image
        looked up bilinearly (Cycles' Linear interpolation), wrapping
        around u and clamped at the poles, times the world's colour."""
        image = self.world.environment
        if image is None:
            return np.broadcast_to(self.world.color, (len(dirs), 3)).copy()
        return lookup(image, directions_to_uv(dirs), "Linear", ("REPEAT", "EXTEND")) * self.world.color

    def sample(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(dirs (n,3), density (n,) per steradian) at `uv (n,2)` in the unit
        square, in proportion to the world's image."""
        uv = contiguous(uv, np.float64)
        dirs, density = np.empty((len(uv), 3)), np.empty(len(uv))
        _image_samples(uv, self.cdf_rows, self.row_pdf, self.cdf_cols, self.col_pdf, dirs, density)
        return dirs, density

    def density(self, dirs: np.ndarray) -> np.ndarray:
        """(n,) the solid-angle density at which `sample` draws `dirs (n,3)`."""
        out = np.empty(len(dirs))
        _densities(contiguous(dirs, np.float64), self.row_pdf, self.col_pdf, out)
        return out


@per_world
def environment_of(world: World) -> Environment:
    """Environment(world), kept while the same world comes back (kept_worlds.py)."""
    return Environment(world)
