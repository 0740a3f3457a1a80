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

from ..sampling.sequences import r2_sequence
from ..scene import Camera
from ..util.vectors import normalize


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


def eye_rays(camera: Camera, pixels: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World rays (origins (n,3), dirs (n,3) unit) through flat pixel indices
    `pixels (n,)` (y * pixx + x) at sub-pixel `offsets (n,2)`. Origins start at
    the clip-start plane, as Blender's do."""
    viewfac = _viewfac(camera)
    x = pixels % camera.pixx + offsets[:, 0]
    y = pixels // camera.pixx + offsets[:, 1]
    sx = x - 0.5 * camera.pixx + camera.shift_x * viewfac
    sy = 0.5 * camera.pixy - y + camera.shift_y * viewfac
    rot, eye = camera.matrix[:3, :3], camera.matrix[:3, 3]
    forward = -rot[:, 2]
    if camera.kind == "ORTHO":
        pixsize = camera.ortho_scale / viewfac
        local = np.stack([sx * pixsize, sy * pixsize, np.zeros_like(sx)], axis=1)
        origins = eye + local @ rot.T + camera.clip_start * forward
        return origins, np.broadcast_to(forward, origins.shape).copy()
    pixsize = 2.0 * math.tan(0.5 * camera.fov) / viewfac
    local = np.stack([sx * pixsize, sy * pixsize, -np.ones_like(sx)], axis=1)
    dirs = local @ rot.T
    dirs = normalize(dirs)
    origins = eye + dirs * (camera.clip_start / (dirs @ forward))[:, None]
    return origins, dirs


def ray_differentials(camera: Camera, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How the camera rays with unit directions `dirs (n,3)`, as `eye_rays`
    makes them, change per pixel step right (+x) and down (+y): (d_origins
    (n,2,3), d_dirs (n,2,3)), world units per pixel (Igehy 1999, "Tracing
    ray differentials").

    Perspective: d = D / |D| with D = sx p X + sy p Y - Z (X, Y, Z the
    camera's axes, p the pixel size at unit distance), so dD = p X per step
    right and -p Y per step down, and dd = (dD - d (d.dD)) / |D|, where
    |D| = 1 / (d.F) (F = -Z, forward). The origin o = e + d c / (d.F) (c the
    clip start) moves by c (dd (d.F) - d (dd.F)) / (d.F)^2.
    Orthographic: d = F throughout, and o moves by p X and -p Y."""
    viewfac = _viewfac(camera)
    rot = camera.matrix[:3, :3]
    forward = -rot[:, 2]
    steps = np.stack([rot[:, 0], -rot[:, 1]])
    if camera.kind == "ORTHO":
        d_origins = np.broadcast_to(steps * (camera.ortho_scale / viewfac), (len(dirs), 2, 3))
        return d_origins, np.zeros((len(dirs), 2, 3))
    pixsize = 2.0 * math.tan(0.5 * camera.fov) / viewfac
    along = (dirs @ forward)[:, None, None]
    d_big = pixsize * steps
    d_dirs = (d_big - dirs[:, None] * (dirs @ d_big.T)[..., None]) * along
    d_forward = (d_dirs.reshape(-1, 3) @ forward).reshape(-1, 2, 1)
    d_origins = camera.clip_start * (d_dirs * along - dirs[:, None] * d_forward) / along ** 2
    return d_origins, d_dirs
