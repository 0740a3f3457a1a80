"""The image of sunlight through meshed water, traced by a particle tracer
of its own: an independent reference for mitsuba_folds.py's slab scenes, with
a thousandth of the noise that Mitsuba's particle tracer reaches in minutes.

The water is shapes.wavy_slab's, rebuilt here from the field its docstring
gives: a height field on square cells, each cut along its diagonal from
(x_i, y_j) to (x_i+1, y_j+1), with the field's unit normals at the vertices,
interpolated barycentrically and normalised. Since the top is a height
field, the triangle a ray meets is found from its cell, with no BVH; the
meeting point solves z0 + tau d_z = h(q + tau d_xy) by fixed-point
iteration (a contraction by |grad h| |d_xy| / |d_z|, about 0.1 here).

Particles leave a horizontal plane above the water on a jittered grid, each
carrying S |d_z| of the plane's area, are refracted into the water and out
of its flat bottom (Snell; the unpolarised Fresnel transmittance as a
weight), and land on the floor, where they are binned by the pixel of the
camera looking straight down from under the water (scenes/wavy_slab
.under_water's). In float64 throughout. Left out: the light reflected inside
the water (2% of 2%), and the light through the walls, whose pixels
`wall_free` names.
"""

from __future__ import annotations

import math

import numba
import numpy as np

# scenes/wavy_slab.under_water's pool: the water's bottom 0.35 m above the floor,
# 0.25 m deep, the camera 0.3 m up looking down, 90 degrees across 240x180
BOTTOM, DEPTH, IOR = 0.35, 0.25, 1.33
EYE_HEIGHT, PIXX, PIXY = 0.3, 240, 180
# the floor's width one pixel sees from there
PIXEL = 2.0 * EYE_HEIGHT / PIXX


def refract(d: np.ndarray, n: np.ndarray, eta: float) -> np.ndarray:
    """Snell's law for unit directions `d (n,3)` meeting unit normals
    `n (n,3)` that face them, eta = n_from / n_to (no total internal
    reflection here): t = eta d + (eta cos_i - cos_t) n."""
    cos_i = -np.einsum("ij,ij->i", d, n)
    cos_t = np.sqrt(1.0 - eta * eta * (1.0 - cos_i * cos_i))
    return eta * d + (eta * cos_i - cos_t)[:, None] * n


def water_grid(size: float, cells: int, waves) -> tuple[np.ndarray, np.ndarray]:
    """The top's heights (cells+1, cells+1) above the floor and unit
    normals (cells+1, cells+1, 3), indexed [x, y]: depth + sum of
    a cos(k . (x, y)) over waves (amplitude, wavelength, angle)."""
    ticks = np.linspace(-0.5 * size, 0.5 * size, cells + 1)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    h, gx, gy = np.full_like(x, BOTTOM + DEPTH), np.zeros_like(x), np.zeros_like(x)
    for amplitude, wavelength, angle in waves:
        k = 2.0 * math.pi / wavelength
        kx, ky = k * math.cos(angle), k * math.sin(angle)
        h += amplitude * np.cos(kx * x + ky * y)
        gx -= amplitude * kx * np.sin(kx * x + ky * y)
        gy -= amplitude * ky * np.sin(kx * x + ky * y)
    normals = np.stack([-gx, -gy, np.ones_like(x)], axis=-1)
    return h, normals / np.linalg.norm(normals, axis=-1, keepdims=True)


@numba.vectorize(["f8(f8, f8)"], cache=True)
def fresnel_transmittance(cos_i, eta):
    """Unpolarised Fresnel transmittance 1 - (Rs + Rp)/2 at incidence
    cosine `cos_i` from a medium of index ratio eta = n_from / n_to
    (Born and Wolf, 1.5.3); 0 past total internal reflection."""
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return 0.0
    cos_t = math.sqrt(1.0 - sin_t2)
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 1.0 - 0.5 * (rs * rs + rp * rp)


@numba.njit(cache=True, inline="always")
def _weights(origin, step, cells, px, py):
    """The cell (i, j) under (px, py) and the barycentric weights of its
    corners (i, j), (i+1, j), (i+1, j+1), (i, j+1): the triangle below the
    diagonal has no (i, j+1), the one above no (i+1, j)."""
    s, t = (px - origin) / step, (py - origin) / step
    i, j = min(max(int(math.floor(s)), 0), cells - 1), min(max(int(math.floor(t)), 0), cells - 1)
    s, t = s - i, t - j
    if s >= t:
        return i, j, 1.0 - s, s - t, t, 0.0
    return i, j, 1.0 - t, 0.0, s, t - s


@numba.njit(cache=True, inline="always")
def _height(heights, origin, step, px, py):
    i, j, wa, wb, wc, wd = _weights(origin, step, heights.shape[0] - 1, px, py)
    return wa * heights[i, j] + wb * heights[i + 1, j] + wc * heights[i + 1, j + 1] + wd * heights[i, j + 1]


@numba.njit(cache=True, inline="always")
def _normal(normals, origin, step, px, py):
    i, j, wa, wb, wc, wd = _weights(origin, step, normals.shape[0] - 1, px, py)
    a, b, c, d = normals[i, j], normals[i + 1, j], normals[i + 1, j + 1], normals[i, j + 1]
    nx = wa * a[0] + wb * b[0] + wc * c[0] + wd * d[0]
    ny = wa * a[1] + wb * b[1] + wc * c[1] + wd * d[1]
    nz = wa * a[2] + wb * b[2] + wc * c[2] + wd * d[2]
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    return nx / norm, ny / norm, nz / norm


@numba.njit(cache=True, parallel=True)
def _trace(heights, normals, origin, step, half, d, strength, rect, side, seed, view, image):
    """Particles on a side x side jittered grid over rect (x0, y0, x1, y1)
    of the plane z = 1 m, binned over the floor's `view` (x0, y0 at the
    image's top left corner, pixel size); image (threads, rows, columns) is
    added to, a layer per thread."""
    threads, rows, columns = image.shape
    pixel = view[2]
    dx, dy = (rect[2] - rect[0]) / side, (rect[3] - rect[1]) / side
    weight = strength * -d[2] * dx * dy / (pixel * pixel)
    eta = 1.0 / IOR
    for thread in numba.prange(threads):
        np.random.seed(seed + thread)
        for row in range(thread, side, threads):
            for col in range(side):
                qx = rect[0] + (col + np.random.random()) * dx
                qy = rect[1] + (row + np.random.random()) * dy
                tau = 0.0
                for _ in range(30):
                    last = tau
                    tau = (1.0 - _height(heights, origin, step, qx + tau * d[0], qy + tau * d[1])) / -d[2]
                    if abs(tau - last) < 1e-11:
                        break
                px, py = qx + tau * d[0], qy + tau * d[1]
                if abs(px) > half or abs(py) > half:
                    continue
                h = 1.0 + tau * d[2]
                nx, ny, nz = _normal(normals, origin, step, px, py)
                cos_i = -(d[0] * nx + d[1] * ny + d[2] * nz)
                w = fresnel_transmittance(cos_i, eta)
                cos_t = math.sqrt(1.0 - eta * eta * (1.0 - cos_i * cos_i))
                k = eta * cos_i - cos_t
                tx, ty, tz = eta * d[0] + k * nx, eta * d[1] + k * ny, eta * d[2] + k * nz
                bx, by = px + tx * (h - BOTTOM) / -tz, py + ty * (h - BOTTOM) / -tz
                if abs(bx) > half or abs(by) > half:
                    continue
                ox, oy = IOR * tx, IOR * ty
                sin2 = ox * ox + oy * oy
                if sin2 >= 1.0:
                    continue
                oz = -math.sqrt(1.0 - sin2)
                w *= fresnel_transmittance(-tz, IOR)
                fx, fy = bx + ox * BOTTOM / -oz, by + oy * BOTTOM / -oz
                c = int(math.floor((fx - view[0]) / pixel))
                r = int(math.floor((view[1] - fy) / pixel))
                if 0 <= c < columns and 0 <= r < rows:
                    image[thread, r, c] += w * weight


def radiance(size: float, cells: int, waves, sun, strength: float, albedo: float = 1.0,
             particles: float = 1e9, margin: float = 0.15, seed: int = 0,
             window=(-EYE_HEIGHT, EYE_HEIGHT * PIXY / PIXX, PIXEL, PIXY, PIXX)) -> np.ndarray:
    """(rows, columns) the floor's radiance albedo E / pi under the water,
    row 0 at +y, from `particles` particles leaving the floor's window,
    moved back along the sun to z = 1 m and widened by `margin` m (more
    than the light's sideways travel through the waves). The window (x, y
    of its top left corner, pixel size, rows, columns) is by default the
    view of the camera under the water."""
    heights, normals = water_grid(size, cells, waves)
    d = np.asarray(sun, dtype=np.float64) / np.linalg.norm(sun)
    x0, y0, pixel, rows, columns = window
    back = np.tile(-d[:2] / -d[2], 2)
    rect = np.array([x0 - margin, y0 - rows * pixel - margin, x0 + columns * pixel + margin, y0 + margin]) + back
    image = np.zeros((numba.get_num_threads(), rows, columns))
    _trace(heights, normals, -0.5 * size, size / cells, 0.5 * size, d, strength, rect, int(math.sqrt(particles)),
           seed, np.array([x0, y0, pixel]), image)
    return albedo * image.sum(axis=0) / math.pi


def wall_free(size: float, top: float, sun) -> np.ndarray:
    """(PIXY, PIXX) the pixels no wall's light reaches: outside the band
    where the sun's light through each wall facing it lands (entering at
    any height up to `top` above the bottom, out through the flat bottom),
    two pixels wider."""
    d = np.asarray(sun, dtype=np.float64) / np.linalg.norm(sun)
    x = (np.arange(PIXX) + 0.5 - 0.5 * PIXX) * PIXEL
    y = (0.5 * PIXY - np.arange(PIXY) - 0.5) * PIXEL
    free = np.ones((PIXY, PIXX), dtype=bool)
    for axis, along in ((0, x[None, :]), (1, y[:, None])):
        if abs(d[axis]) < 1e-12:
            continue
        wall = np.zeros(3)
        wall[axis] = -math.copysign(1.0, d[axis])
        inside = refract(d[None], wall[None], 1.0 / IOR)[0]
        out = refract(inside[None], np.array([[0.0, 0.0, 1.0]]), IOR)[0]
        band = wall[axis] * 0.5 * size + np.array([0.0, top]) * inside[axis] / -inside[2] \
            + BOTTOM * out[axis] / -out[2]
        free &= ~((along > band.min() - 2 * PIXEL) & (along < band.max() + 2 * PIXEL))
    return free
