"""The beams' light on a flat receiver as the camera sees it: each pixel
the exact mean of the beams' irradiance over the part of it that sees the
receiver, at folds and cusps too.

A pixel shows the mean, over its square, of the radiance of what it sees (a
box filter). The map's cells cannot give that mean where a caustic folds:
pixels cut cells, and a fold's irradiance, which rises as 1/sqrt of the
distance to it, is held in a cell as the cell's mean, so part of its light
goes to the wrong pixel (benchmarks/README.md: folds and cusps). But a plane maps to the
image by a projective map, which takes a beam's triangle to the triangle of
its projected corners, and a beam's irradiance is uniform over it: so the
projected beams, rasterised with exact coverage (raster.py) on the pixel
grid, give each pixel the integral of the irradiance over its area in the
image, and the receiver's own triangles, rasterised the same way, the area
of the pixel that sees the receiver. Their ratio is the mean over that part.

Parts of the plane nearer than the camera's clip start are not seen, and
a triangle that crosses the clip plane is cut at it, in the plane's own
coordinates (where depth is affine) before it is projected.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..util.jit import inline, kernel
from .grid import as_rgb
from .raster import Coverage


@dataclass(frozen=True)
class ImageView:
    """How a camera maps world points to its image (camera_rays.image_view).

    world_to_camera  12 floats: the (3,4) rows of the world-to-camera map
                     (rotation and translation; the camera looks down -Z)
    pixx, pixy       the image's width and height in pixels
    pixel            a pixel's size at unit distance (PERSP), or its size (ORTHO)
    centre           (x, y) image position of the view's axis, in pixels
                     from the left and from the top (the lens shift moves it)
    clip             the clip start: nearer points are not seen
    ortho            orthographic
    """

    world_to_camera: tuple
    pixx: int
    pixy: int
    pixel: float
    centre: tuple
    clip: float
    ortho: bool

    def of_plane(self, point: np.ndarray, axis_x: np.ndarray, axis_y: np.ndarray) -> np.ndarray:
        """(3,3) A with camera-space q = A [x, y, 1] for the plane point
        point + x axis_x + y axis_y."""
        rows = np.asarray(self.world_to_camera, dtype=np.float64).reshape(3, 4)
        return np.ascontiguousarray(np.stack([rows[:, :3] @ axis_x, rows[:, :3] @ axis_y,
                                              rows[:, :3] @ point + rows[:, 3]], axis=1))


class ScreenLayer:
    """The beams landed on a flat receiver (its chart a PlaneChart), as
    the camera `view` sees them: `at(pixels)` is the mean irradiance W/m^2
    over the part of each pixel that sees the receiver, of the beams
    `add`ed until `prepare`. `receiver (t,3,2)` the receiver's triangles
    in chart metres."""

    def __init__(self, view: ImageView, chart, receiver: np.ndarray):
        self.view, self.chart, self.receiver = view, chart, receiver
        self._to_camera = view.of_plane(chart.point, chart.axis_x, chart.axis_y)
        self._flux = Coverage((view.pixy, view.pixx), 1)
        self._values = None

    def for_view(self, view: ImageView) -> "ScreenLayer":
        """An empty layer of the same receiver for another camera view."""
        return ScreenLayer(view, self.chart, self.receiver)

    def _image_triangles(self, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(image triangles (k,3,2) pixels (x right, y down), source (k,)
        row of `corners (m,3,2)` chart metres each comes from); of convex
        polygons `corners (m,j,2)`, j > 3, image polygons (k,j+1,2)."""
        corners = np.ascontiguousarray(corners, dtype=np.float64)
        fan = corners.shape[1] == 3
        shape = (2 * len(corners), 3, 2) if fan else (len(corners), corners.shape[1] + 1, 2)
        out, source = np.empty(shape), np.empty(shape[0], dtype=np.int64)
        view = self.view
        count = _image_triangles(corners, self._to_camera, 1.0 / view.pixel, float(view.centre[0]),
                                 float(view.centre[1]), float(view.clip), bool(view.ortho), fan, out, source)
        return out[:count], source[:count]

    def add(self, corners: np.ndarray, irradiance: np.ndarray) -> None:
        """Beams `corners (m,k,2)` chart metres (BeamMap.add_beams), `irradiance (m,3)` W/m^2."""
        for job in self.add_jobs(corners, irradiance, bands=1):
            job()

    def add_jobs(self, corners: np.ndarray, irradiance: np.ndarray, bands: int) -> list[Callable[[], None]]:
        """`add`, as jobs that each rasterise a band of the image's rows
        (raster.Coverage.add_jobs)."""
        triangles, source = self._image_triangles(corners)
        values = np.take(irradiance, source, axis=0)
        if ((values[:, 0] != values[:, 1]) | (values[:, 0] != values[:, 2])).any():
            self._flux.widen(3)
        self._values = None
        return self._flux.add_jobs(triangles, values, bands=bands)

    def prepare(self) -> None:
        """Divide the beams' integral in each pixel by the area the receiver covers in it."""
        if self._values is not None:
            return
        triangles, _ = self._image_triangles(self.receiver)
        seen = Coverage(self._flux.shape, 1)
        seen.add(triangles, np.ones((len(triangles), 1)))
        # a receiver whose faces overlap covers a pixel at most once
        covered = np.minimum(seen.planes()[0], 1.0)
        flux = self._flux.planes()
        with np.errstate(divide="ignore", invalid="ignore"):
            values = np.where(covered > 1e-9, flux / covered, 0.0)
        # float32, as the image is: a 4K image's values take 100 MB, not 200
        self._values = np.ascontiguousarray(values.reshape(len(values), -1).T, dtype=np.float32)

    def at(self, pixels: np.ndarray) -> np.ndarray:
        """(n,3) mean irradiance W/m^2 over the receiver's part of the
        flat image pixels `pixels (n,)` (y * pixx + x)."""
        self.prepare()
        return as_rgb(np.take(self._values, pixels, axis=0))


@kernel("i8(f8[:, :, ::1], f8[:, ::1], f8, f8, f8, f8, b1, b1, f8[:, :, ::1], i8[::1])")
def _image_triangles(corners, to_camera, inverse_pixel, centre_x, centre_y, clip, ortho, fan, out, source):
    """Write into `out (2m,3,2)` the image triangles of the plane
    triangles `corners (m,3,2)` (chart metres), or unless `fan` into `out
    (m,j+1,2)` the image polygons of convex polygons (m,j,2), each padded by
    repeating its last corner, and into `source` the row each comes from;
    returns how many. Camera space q = A [x, y, 1] (`to_camera` A (3,3)) and
    depth -q_z are affine in the chart, so each polygon is cut to depth >=
    `clip` there first (Sutherland and Hodgman 1974, one plane: a triangle
    keeps 3 or 4 corners, 1 or 2 triangles; a corner that repeats the one
    before it is dropped). A point at depth d shows at
    x = centre_x + q_x / (d p), y = centre_y - q_y / (d p) pixels (p the
    pixel at unit distance, `inverse_pixel` 1/p; `ortho`: q / p, no d),
    the inverse of camera_rays._eye_rays."""
    sides = corners.shape[1]
    kept, image = np.empty((sides + 1, 2)), np.empty((sides + 1, 2))
    camera = (to_camera[0, 0], to_camera[0, 1], to_camera[0, 2], to_camera[1, 0], to_camera[1, 1],
              to_camera[1, 2], to_camera[2, 0], to_camera[2, 1], to_camera[2, 2])
    count = 0
    for t in range(len(corners)):
        n = 0
        for k in range(sides):
            # the corners' values, not views of `corners`: a view takes a reference to it (util.jit.inline)
            a = (corners[t, k, 0], corners[t, k, 1])
            b = (corners[t, (k + 1) % sides, 0], corners[t, (k + 1) % sides, 1])
            if a[0] == b[0] and a[1] == b[1]:
                continue
            da = -(to_camera[2, 0] * a[0] + to_camera[2, 1] * a[1] + to_camera[2, 2]) - clip
            db = -(to_camera[2, 0] * b[0] + to_camera[2, 1] * b[1] + to_camera[2, 2]) - clip
            if da >= 0.0:
                kept[n, 0], kept[n, 1] = a[0], a[1]
                n += 1
            if (da >= 0.0) != (db >= 0.0):
                s = da / (da - db)
                kept[n, 0], kept[n, 1] = a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])
                n += 1
        if not fan and n >= 3:
            for k in range(out.shape[1]):
                if k < n:
                    image[k, 0], image[k, 1] = _image_point1(kept[k, 0], kept[k, 1], camera, inverse_pixel, centre_x,
                                                             centre_y, ortho)
                out[count, k, 0], out[count, k, 1] = image[min(k, n - 1), 0], image[min(k, n - 1), 1]
            source[count] = t
            count += 1
            continue
        for first in range(n - 2):
            for k in range(3):
                corner = 0 if k == 0 else first + k
                out[count, k, 0], out[count, k, 1] = _image_point1(kept[corner, 0], kept[corner, 1], camera,
                                                                   inverse_pixel, centre_x, centre_y, ortho)
            source[count] = t
            count += 1
    return count


@inline
def _image_point1(x, y, camera, inverse_pixel, centre_x, centre_y, ortho):
    """(x, y) pixels of the plane point (x, y) (_image_triangles), `camera`
    the 9-tuple of to_camera's rows (values, not a view of the array:
    util.jit.inline)."""
    qx = camera[0] * x + camera[1] * y + camera[2]
    qy = camera[3] * x + camera[4] * y + camera[5]
    scale = inverse_pixel
    if not ortho:
        scale /= -(camera[6] * x + camera[7] * y + camera[8])
    return centre_x + qx * scale, centre_y - qy * scale
