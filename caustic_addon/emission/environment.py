"""The world's light as directions: its radiance in any direction, and
directions sampled in proportion to it (a piecewise-constant 2D
distribution over the lat-long image, rows weighted by sin(theta): pbrt-v4's
ImageInfiniteLight, Cycles' background map), with their solid-angle
density, so the eye pass and the photon pass can importance-sample a bright
sky or a sun in an HDRI.

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

import numpy as np

from ..scene import World
from ..util.image_lookup import lookup
from ..util.vectors import DIVISION_FLOOR


def directions_to_uv(dirs: np.ndarray) -> np.ndarray:
    """(n,2) image coordinates in [0,1)^2 (u across, v down from the top) of unit `dirs (n,3)`."""
    u = np.mod(0.5 - np.arctan2(dirs[:, 1], dirs[:, 0]) / (2.0 * math.pi), 1.0)
    v = np.arccos(np.clip(dirs[:, 2], -1.0, 1.0)) / math.pi
    return np.stack([u, v], axis=1)


def uv_to_directions(uv: np.ndarray) -> np.ndarray:
    """(n,3) unit directions of image coordinates `uv (n,2)`."""
    phi = (0.5 - uv[:, 0]) * 2.0 * math.pi
    theta = uv[:, 1] * math.pi
    sin_t = np.sin(theta)
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), np.cos(theta)], axis=1)


def _pixels(dirs: np.ndarray, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """(row (n,), col (n,)) of the pixel of an h x w lat-long image each of `dirs (n,3)` falls in."""
    uv = directions_to_uv(dirs)
    return (np.clip((uv[:, 1] * h).astype(np.int64), 0, h - 1), np.clip((uv[:, 0] * w).astype(np.int64), 0, w - 1))


def luminance(rgb: np.ndarray) -> np.ndarray:
    """(...) Rec.709 luminance of linear `rgb (..., 3)`."""
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


class Environment:
    """A world, ready to evaluate and sample.

    A plain colour is sampled uniformly over the sphere; an image by its
    pixels' luminance times sin(theta) (each pixel's solid angle), with a
    density of p_pixel w h / (2 pi^2 sin(theta)) per steradian."""

    def __init__(self, world: World):
        self.world = world
        image = world.environment
        if image is None:
            self.cdf_rows = self.cdf_cols = None
            return
        h, w = image.shape[:2]
        theta = (np.arange(h) + 0.5) / h * math.pi
        weight = np.maximum(luminance(image * world.color), 0.0) * np.sin(theta)[:, None]
        if not weight.sum() > 0:
            weight = np.sin(theta)[:, None] * np.ones((1, w))
        rows = weight.sum(axis=1)
        self.row_pdf = rows / rows.sum()
        self.cdf_rows = np.concatenate([[0.0], np.cumsum(self.row_pdf)])
        self.col_pdf = weight / np.maximum(rows[:, None], DIVISION_FLOOR)
        self.cdf_cols = np.concatenate([np.zeros((h, 1)), np.cumsum(self.col_pdf, axis=1)], axis=1)
        # every row's column CDF, offset by its row number: one sorted array to search
        self._stacked_cdf = (self.cdf_cols + np.arange(h)[:, None]).ravel()

    def light(self, dirs: np.ndarray) -> np.ndarray:
        """(n,3) W/(m^2 sr) that lights the scene from `dirs (n,3)`: the
        pixel each falls in, times the world's colour."""
        image = self.world.environment
        if image is None:
            return np.broadcast_to(self.world.color, (len(dirs), 3)).copy()
        row, col = _pixels(dirs, *image.shape[:2])
        return image[row, col] * self.world.color

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
        square: uniform over the sphere for a plain colour, else in
        proportion to the image."""
        if self.cdf_rows is None:
            z = 1.0 - 2.0 * uv[:, 0]
            r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
            phi = 2.0 * math.pi * uv[:, 1]
            dirs = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
            return dirs, np.full(len(uv), 1.0 / (4.0 * math.pi))
        h, w = self.col_pdf.shape
        row = np.clip(np.searchsorted(self.cdf_rows, uv[:, 1], side="right") - 1, 0, h - 1)
        v = (row + (uv[:, 1] - self.cdf_rows[row]) / np.maximum(self.row_pdf[row], DIVISION_FLOOR)) / h
        col = np.clip(np.searchsorted(self._stacked_cdf, row + uv[:, 0], side="right") - 1 - row * (w + 1), 0, w - 1)
        within = (uv[:, 0] - self.cdf_cols[row, col]) / np.maximum(self.col_pdf[row, col], DIVISION_FLOOR)
        u = (col + within) / w
        dirs = uv_to_directions(np.stack([u, np.clip(v, 0.0, 1.0)], axis=1))
        return dirs, self.density(dirs)

    def total(self) -> np.ndarray:
        """(3,) int L dw over the sphere, W/(m^2): the world's flux through a
        unit area from every direction."""
        image = self.world.environment
        if image is None:
            return 4.0 * math.pi * self.world.color
        h, w = image.shape[:2]
        theta = (np.arange(h) + 0.5) / h * math.pi
        solid_angle = (2.0 * math.pi / w) * (math.pi / h) * np.sin(theta)
        return (image * solid_angle[:, None, None]).sum(axis=(0, 1)) * self.world.color

    def density(self, dirs: np.ndarray) -> np.ndarray:
        """(n,) the solid-angle density at which `sample` draws `dirs (n,3)`."""
        if self.cdf_rows is None:
            return np.full(len(dirs), 1.0 / (4.0 * math.pi))
        h, w = self.col_pdf.shape
        row, col = _pixels(dirs, h, w)
        sin_t = np.sqrt(np.maximum(0.0, 1.0 - dirs[:, 2] ** 2))
        pixel = self.row_pdf[row] * self.col_pdf[row, col]
        return pixel * w * h / (2.0 * math.pi ** 2 * np.maximum(sin_t, DIVISION_FLOOR))
