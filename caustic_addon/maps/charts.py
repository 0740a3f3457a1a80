"""A receiver's 2D parameterisation in metres: its plane when it is flat,
else its UV map, else a box projection (box_chart.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional

import numpy as np

from ..sampling.warps import orthonormal_basis
from ..scene import Mesh
from ..tracing.topology import mesh_pieces
from ..util.jit import inline, kernel
from ..util.rows import row_ids
from ..util.vectors import DIVISION_FLOOR, dot1, float_rows, row, subrow, sum1, transferred1
from .raster import rasterise_triangles


@dataclass
class ImageFrame:
    """Where an image of a chart rectangle lies on the receiver, in the
    terms of a Mapping node of vector type TEXTURE, whose output
    R^T (p - location) / scale is the image's [0,1]^2 coordinate:

    coordinates  'POSITION': p is the world position (a flat receiver);
                 'UV': p is the receiver's UV coordinate (z = 0);
                 'BOX': p is the box chart's coordinate (z = 0), which
                 `islands` give from the world position and true normal
    location     (3,) p at the image's first corner (its first row's start)
    rotation     (3,3) world axes of the image's x and y and of the
                 receiver's normal, as columns; the identity for 'UV'
    scale        (3,) the image's width and height in p's units, and 1
    islands      the box chart's islands (box_chart.BoxIsland), else empty
    """

    coordinates: Literal["POSITION", "UV", "BOX"]
    location: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    islands: tuple = ()


class Chart:
    """A receiver's 2D parameterisation in metres.

    origin (2,) and size (2,): the rectangle of chart coordinates it covers.
    front (3,): the side of the receiver whose light its map holds (a
    flat receiver's, PlaneChart); None, as here: both.
    """

    origin: np.ndarray
    size: np.ndarray
    front: Optional[np.ndarray] = None

    def image_frame(self, corner: np.ndarray, extent: np.ndarray) -> ImageFrame:
        """Where an image of the chart rectangle from `corner (2,)` over
        `extent (2,)` metres (x, y) lies on the receiver."""
        raise NotImplementedError

    def coords(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(n,2) chart coordinates of surface points given by triangle `prim`
        (local index), barycentrics `u, v` and world position `points (n,3)`."""
        raise NotImplementedError

    def area_scale(self, prim: np.ndarray) -> np.ndarray:
        """(n,) chart area per world area at triangle `prim`."""
        raise NotImplementedError

    def coverage(self, origin: np.ndarray, cell: float, shape: tuple[int, int]) -> Optional[np.ndarray]:
        """(h,w) the share of each cell of a grid of `shape`, edge `cell`
        m, first corner at chart `origin (2,)`, that the receiver covers
        (None: all of it); a density estimate divides by the area covered."""
        return None

    def islands_of(self, prim: np.ndarray) -> np.ndarray:
        """(n,) the island of the chart that triangle `prim` lies in: a
        beam whose corners land on different islands has no shape in it,
        unless the chart can `project` it into each."""
        return np.zeros(len(prim), dtype=np.int64)

    # Whether `project` places any world point in any island's coordinates.
    projects = False

    def project(self, island: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(n,k,2) chart metres of world `points (n,k,3)` in the coordinates
        of island `island (n,)` (only where `projects`)."""
        raise NotImplementedError


class PlaneChart(Chart):
    """A flat receiver: coordinates along two unit axes in its plane. Its
    map holds the light that arrives on one side, the side `front` (3,)
    points to (receivers.facing_casters), or on both where `front` is
    None: a plane's two sides share its chart, and the light from below a
    floor is not the light its top shows."""

    def __init__(self, point: np.ndarray, normal: np.ndarray, vertices: np.ndarray):
        self.point, self.normal = point, normal
        self.axis_x, self.axis_y = orthonormal_basis(normal)
        local = self.plane_coords(vertices)
        self.origin, self.size = local.min(axis=0), np.ptp(local, axis=0)

    def plane_coords(self, points: np.ndarray) -> np.ndarray:
        """(n,2) chart coordinates of world `points (n,3)` projected onto the plane."""
        rel = points - self.point
        return np.stack([rel @ self.axis_x, rel @ self.axis_y], axis=1)

    def coords(self, prim, u, v, points):
        return self.plane_coords(points)

    def area_scale(self, prim):
        return np.ones(len(prim))

    def footprint(self, origins: np.ndarray, dirs: np.ndarray, d_origins: np.ndarray, d_dirs: np.ndarray,
                  stratum: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The chart rectangle that stands for the footprint of a pixel
        stratum, `stratum` pixels wide, around each ray `origins, dirs
        (n,3)` whose change per pixel step is `d_origins, d_dirs (n,2,3)`
        (camera.ray_differentials): (lo (n,2), hi (n,2), ok (n,) bool); not
        ok where the ray runs parallel to the plane. The ray's line meets
        the plane behind its origin where the ray left a surface in contact
        with the receiver (tracing/contact.py), at -epsilon.

        To first order the footprint is the parallelogram that J, the chart
        point's derivative per pixel step (2x2), spans around the hit, and a
        pixel is the mean over its square, uniform in pixel space. The
        rectangle with the same centre and, along each chart axis, the same
        variance (J_x^2 + J_y^2) stratum^2 / 12 keeps that mean to second
        order along each axis; the parallelogram's bounding box is wider
        where it is sheared (off the image's centre lines) and blurs a
        caustic's fold. The hit moves by dp = do + s dd - d (N.(do + s dd))
        / (N.d), s the distance along the ray (Igehy 1999)."""
        origins, dirs = float_rows(origins, dirs)
        d_origins, d_dirs = float_rows(d_origins, d_dirs)
        lo, hi = np.empty((len(origins), 2)), np.empty((len(origins), 2))
        ok = np.empty(len(origins), dtype=bool)
        _plane_footprints(origins, dirs, d_origins, d_dirs, float(stratum), self.frame(), lo, hi, ok)
        return lo, hi, ok

    def frame(self) -> np.ndarray:
        """(4,3): a point on the plane, its unit normal, the chart's x and y axes."""
        return np.array([self.point, self.normal, self.axis_x, self.axis_y], dtype=np.float64)

    def image_frame(self, corner, extent):
        rotation = np.stack([self.axis_x, self.axis_y, self.normal], axis=1)
        return ImageFrame("POSITION", self.world(np.asarray(corner, dtype=np.float64)[None])[0], rotation,
                          np.array([extent[0], extent[1], 1.0]))

    def world(self, xy: np.ndarray) -> np.ndarray:
        """(n,3) world points of chart coordinates `xy (n,2)`."""
        return self.point + xy[:, :1] * self.axis_x + xy[:, 1:] * self.axis_y



@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, :, ::1], f8[:, :, ::1], f8, f8[:, ::1], f8[:, ::1], f8[:, ::1], "
        "b1[::1])")
def _plane_footprints(origins, dirs, d_origins, d_dirs, stratum, frame, lo, hi, ok):
    """PlaneChart.footprint's rectangles `lo, hi (n,2)` and `ok (n,)` on
    the plane of `frame` (PlaneChart.frame)."""
    for i in range(len(origins)):
        ok[i] = plane_footprint1(row(origins, i), row(dirs, i), subrow(d_origins, i, 0), subrow(d_dirs, i, 0),
                                 subrow(d_origins, i, 1), subrow(d_dirs, i, 1), stratum, frame, lo, hi, i)


@inline
def plane_footprint1(o, d, d_origin_x, d_dir_x, d_origin_y, d_dir_y, stratum, frame, lo, hi, i):
    """Row i of PlaneChart.footprint's rectangles `lo, hi (n,2)`, for the
    ray `o, d` whose changes per pixel step right and down are
    `d_origin_x, d_dir_x` and `d_origin_y, d_dir_y`, on the plane of
    `frame (4,3)`: a point on it, its unit normal, its chart's x and y
    axes. Returns whether the ray meets the plane (not parallel to it);
    the row is left as it was where it does not."""
    p, n, x, y = row(frame, 0), row(frame, 1), row(frame, 2), row(frame, 3)
    along = dot1(d, n)
    s = dot1(sum1(1.0, p, -1.0, o), n) / along if along != 0.0 else math.inf
    if not math.isfinite(s):
        return False
    right, down = transferred1(d_origin_x, d_dir_x, d, s, n), transferred1(d_origin_y, d_dir_y, d, s, n)
    var_x = dot1(right, x) ** 2 + dot1(down, x) ** 2
    var_y = dot1(right, y) ** 2 + dot1(down, y) ** 2
    rel = sum1(1.0, sum1(1.0, o, s, d), -1.0, p)
    centre_x, centre_y = dot1(rel, x), dot1(rel, y)
    half_x, half_y = 0.5 * stratum * math.sqrt(var_x), 0.5 * stratum * math.sqrt(var_y)
    lo[i, 0], lo[i, 1] = centre_x - half_x, centre_y - half_y
    hi[i, 0], hi[i, 1] = centre_x + half_x, centre_y + half_y
    return True


class UVChart(Chart):
    """A curved receiver, through its UV map scaled to metres: one UV unit is
    `metres_per_uv` metres, chosen so that chart and world areas agree in
    total. Its islands are the pieces the UV map keeps joined."""

    def __init__(self, mesh: Mesh, world_areas: np.ndarray):
        corner_uvs = self.corner_uvs = mesh.corner_uvs
        e1, e2 = corner_uvs[:, 1] - corner_uvs[:, 0], corner_uvs[:, 2] - corner_uvs[:, 0]
        uv_areas = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        self.metres_per_uv = math.sqrt(world_areas.sum() / max(uv_areas.sum(), DIVISION_FLOOR))
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = uv_areas * self.metres_per_uv ** 2 / world_areas
        self._area_scale = np.where(np.isfinite(scale), scale, 0.0)
        flat = corner_uvs.reshape(-1, 2) * self.metres_per_uv
        self.origin, self.size = flat.min(axis=0), np.ptp(flat, axis=0)
        weld = row_ids(np.round(mesh.vertices, 9))[mesh.triangles].reshape(-1, 1)
        keys = row_ids(np.concatenate([weld, np.round(corner_uvs.reshape(-1, 2) * (1 << 20))], axis=1))
        self._islands = mesh_pieces(mesh.triangles, keys.reshape(-1, 3), np.zeros(len(weld) // 3, dtype=np.int64))

    def coords(self, prim, u, v, points):
        c = self.corner_uvs[prim]
        uv = (1.0 - u - v)[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        return uv * self.metres_per_uv

    def area_scale(self, prim):
        return self._area_scale[prim]

    def islands_of(self, prim):
        return self._islands[prim]

    def coverage(self, origin, cell, shape):
        return covered_share(self.corner_uvs * self.metres_per_uv, origin, cell, shape)

    def image_frame(self, corner, extent):
        return ImageFrame("UV", np.array([corner[0], corner[1], 0.0]) / self.metres_per_uv, np.eye(3),
                          np.array([extent[0] / self.metres_per_uv, extent[1] / self.metres_per_uv, 1.0]))


def covered_share(triangles: np.ndarray, origin: np.ndarray, cell: float, shape: tuple[int, int]) -> np.ndarray:
    """(h,w) the share of each cell (edge `cell`, from `origin (2,)`) that
    chart triangles `triangles (n,3,2)` cover, exact, at most 1."""
    covered = rasterise_triangles(shape, (triangles - origin) / cell, np.ones((len(triangles), 1)))[0]
    return np.clip(covered, 0.0, 1.0)
