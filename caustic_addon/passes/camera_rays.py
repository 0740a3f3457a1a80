"""Eye rays through pixels, with Blender's view plane.

Source: Blender's `BKE_camera_params_compute_viewplane`. The sensor-fit side
spans `viewfac` pixels (the width for HORIZONTAL, or AUTO with a landscape
image; the height otherwise); at unit distance one pixel is
2 tan(fov/2) / viewfac wide (ortho_scale / viewfac for ORTHO), and the lens
shift moves the view plane by shift * viewfac pixels.

Pixel (x, y) counts x from the left and y from the top of the image.
"""

from __future__ import annotations

import math

import numpy as np

from ..maps.charts import PlaneChart, plane_footprint1
from ..maps.screen_layer import ImageView
from ..sampling.sequences import r2_sequence
from ..scene import Camera
from ..util.jit import inline, kernel
from ..util.vectors import float_rows, row, set_subrow


def _viewfac(camera: Camera) -> int:
    horizontal = camera.sensor_fit == "HORIZONTAL" or (camera.sensor_fit == "AUTO" and camera.pixx >= camera.pixy)
    return camera.pixx if horizontal else camera.pixy


def pixel_offsets(spp: int, seed: int) -> np.ndarray:
    """(spp,2) sub-pixel positions in [0,1)^2. A square count s^2 takes the
    centres of an s x s grid of strata, which tile the pixel exactly (the eye
    pass averages caustics over them); other counts take the R2 sequence
    with a random rotation."""
    side = int(round(math.sqrt(spp)))
    if side * side == spp:
        ticks = (np.arange(side) + 0.5) / side
        return np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    return r2_sequence(np.arange(spp), np.random.default_rng(seed).random(2))


def _view(camera: Camera) -> tuple[np.ndarray, float]:
    """The camera's frame (4,3), rows X, Y, Z (its axes) and its position,
    and p, a pixel's size at unit distance (its size for ORTHO)."""
    viewfac = _viewfac(camera)
    rot = camera.matrix[:3, :3]
    frame = np.ascontiguousarray(np.concatenate([rot.T, camera.matrix[None, :3, 3]]), dtype=np.float64)
    if camera.kind == "ORTHO":
        return frame, camera.ortho_scale / viewfac
    return frame, 2.0 * math.tan(0.5 * camera.fov) / viewfac


def image_view(camera: Camera) -> ImageView:
    """How `camera` maps world points to pixels: the inverse of `eye_rays`."""
    frame, pixsize = _view(camera)
    viewfac = _viewfac(camera)
    rotation = frame[:3]
    to_camera = np.concatenate([rotation, -(rotation @ frame[3])[:, None]], axis=1)
    return ImageView(tuple(float(v) for v in to_camera.ravel()), camera.pixx, camera.pixy, pixsize,
                     (0.5 * camera.pixx - camera.shift_x * viewfac, 0.5 * camera.pixy + camera.shift_y * viewfac),
                     float(camera.clip_start), camera.kind == "ORTHO")


def eye_rays(camera: Camera, pixels: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World rays (origins (n,3), dirs (n,3) unit) through flat pixel indices
    `pixels (n,)` (y * pixx + x) at sub-pixel `offsets (n,2)`. Origins start at
    the clip-start plane, as Blender's do."""
    frame, pixsize = _view(camera)
    viewfac = _viewfac(camera)
    n = len(pixels)
    origins, dirs = np.empty((n, 3)), np.empty((n, 3))
    _eye_rays(origins, dirs, np.ascontiguousarray(pixels, dtype=np.int64),
              np.ascontiguousarray(offsets, dtype=np.float64), frame, camera.pixx, camera.pixy,
              camera.shift_x * viewfac, camera.shift_y * viewfac, pixsize, camera.clip_start,
              camera.kind == "ORTHO")
    return origins, dirs


@kernel("void(f8[:, ::1], f8[:, ::1], i8[::1], f8[:, ::1], f8[:, ::1], i8, i8, f8, f8, f8, f8, b1)")
def _eye_rays(origins, dirs, pixels, offsets, frame, pixx, pixy, shift_x, shift_y, pixsize, clip, ortho):
    """Fill `origins, dirs (n,3)` with the rays through `pixels (n,)` at
    `offsets (n,2)`. The point (x, y) of the image sits at
    sx = x - pixx/2 + shift_x, sy = pixy/2 - y + shift_y pixels from the
    view's centre (shifts in pixels). Perspective: d = D / |D|, D = sx p X +
    sy p Y - Z, from o = e + d c / (d.F) (F = -Z forward, c the clip start).
    Orthographic: d = F from o = e + sx p X + sy p Y + c F."""
    for i in range(len(pixels)):
        sx = (pixels[i] % pixx + offsets[i, 0] - 0.5 * pixx + shift_x) * pixsize
        sy = (0.5 * pixy - (pixels[i] // pixx + offsets[i, 1]) + shift_y) * pixsize
        if ortho:
            for k in range(3):
                dirs[i, k] = -frame[2, k]
                origins[i, k] = frame[3, k] + sx * frame[0, k] + sy * frame[1, k] - clip * frame[2, k]
            continue
        size = 0.0
        for k in range(3):
            dirs[i, k] = sx * frame[0, k] + sy * frame[1, k] - frame[2, k]
            size += dirs[i, k] * dirs[i, k]
        size = math.sqrt(size)
        along = 0.0
        for k in range(3):
            dirs[i, k] /= size
            along -= dirs[i, k] * frame[2, k]
        for k in range(3):
            origins[i, k] = frame[3, k] + dirs[i, k] * (clip / along)


def ray_differentials(camera: Camera, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How the camera rays with unit directions `dirs (n,3)`, as `eye_rays`
    makes them, change per pixel step right (+x) and down (+y): (d_origins
    (n,2,3), d_dirs (n,2,3)), world units per pixel (Igehy 1999, "Tracing
    ray differentials")."""
    frame, pixsize = _view(camera)
    n = len(dirs)
    d_origins, d_dirs = np.empty((n, 2, 3)), np.empty((n, 2, 3))
    _ray_differentials(d_origins, d_dirs, np.ascontiguousarray(dirs, dtype=np.float64), frame, pixsize,
                       camera.clip_start, camera.kind == "ORTHO")
    return d_origins, d_dirs


@kernel("void(f8[:, :, ::1], f8[:, :, ::1], f8[:, ::1], f8[:, ::1], f8, f8, b1)")
def _ray_differentials(d_origins, d_dirs, dirs, frame, pixsize, clip, ortho):
    """Fill `d_origins, d_dirs (n,2,3)`, ray_differential1 of each ray
    `dirs (n,3)` per pixel step right and down."""
    for i in range(len(dirs)):
        for j in range(2):
            d_origin, d_dir = ray_differential1(row(dirs, i), frame, pixsize, clip, ortho, j)
            set_subrow(d_origins, i, j, d_origin)
            set_subrow(d_dirs, i, j, d_dir)


@inline
def ray_differential1(d, frame, pixsize, clip, ortho, j):
    """(d_origin, d_dir), 3-tuples: the change of the camera ray of unit
    direction `d` per pixel step right (j = 0, step X of the camera's
    `frame`) or down (j = 1, step -Y).

    Perspective: d = D / |D| with D = sx p X + sy p Y - Z (p the pixel size
    at unit distance), so dD = p X per step right and -p Y per step down,
    and dd = (dD - d (d.dD)) / |D|, where |D| = 1 / (d.F) (F = -Z,
    forward). The origin o = e + d c / (d.F) (c the clip start) moves by
    c (dd (d.F) - d (dd.F)) / (d.F)^2.
    Orthographic: d = F throughout, and o moves by p X and -p Y."""
    sign = 1.0 if j == 0 else -1.0
    if ortho:
        return ((sign * pixsize * frame[j, 0], sign * pixsize * frame[j, 1], sign * pixsize * frame[j, 2]),
                (0.0, 0.0, 0.0))
    along = -(d[0] * frame[2, 0] + d[1] * frame[2, 1] + d[2] * frame[2, 2])
    d_along = (d[0] * sign * pixsize * frame[j, 0] + d[1] * sign * pixsize * frame[j, 1]
               + d[2] * sign * pixsize * frame[j, 2])
    dd = ((sign * pixsize * frame[j, 0] - d[0] * d_along) * along,
          (sign * pixsize * frame[j, 1] - d[1] * d_along) * along,
          (sign * pixsize * frame[j, 2] - d[2] * d_along) * along)
    d_forward = -dd[0] * frame[2, 0] - dd[1] * frame[2, 1] - dd[2] * frame[2, 2]
    scale = along * along
    return ((clip * (dd[0] * along - d[0] * d_forward) / scale, clip * (dd[1] * along - d[1] * d_forward) / scale,
             clip * (dd[2] * along - d[2] * d_forward) / scale), dd)


def camera_footprints(camera: Camera, chart: PlaneChart, origins: np.ndarray, dirs: np.ndarray,
                      stratum: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """chart.footprint of camera rays `origins, dirs (n,3)` with their
    differentials (ray_differentials), worked out ray by ray: (lo (n,2),
    hi (n,2), ok (n,))."""
    frame, pixsize = _view(camera)
    origins, dirs = float_rows(origins, dirs)
    lo, hi, ok = np.empty((len(dirs), 2)), np.empty((len(dirs), 2)), np.empty(len(dirs), dtype=bool)
    _camera_footprints(origins, dirs, frame, pixsize, camera.clip_start, camera.kind == "ORTHO", float(stratum),
                       chart.frame(), lo, hi, ok)
    return lo, hi, ok


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8, f8, b1, f8, f8[:, ::1], f8[:, ::1], f8[:, ::1], b1[::1])")
def _camera_footprints(origins, dirs, frame, pixsize, clip, ortho, stratum, plane, lo, hi, ok):
    for i in range(len(dirs)):
        d = row(dirs, i)
        d_origin_x, d_dir_x = ray_differential1(d, frame, pixsize, clip, ortho, 0)
        d_origin_y, d_dir_y = ray_differential1(d, frame, pixsize, clip, ortho, 1)
        ok[i] = plane_footprint1(row(origins, i), d, d_origin_x, d_dir_x, d_origin_y, d_dir_y, stratum, plane,
                                 lo, hi, i)
