"""A receiver's 2D parameterisation in metres: its plane when it is flat, else its UV map."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional

import numpy as np

from ..sampling.warps import orthonormal_basis
from ..scene import Object
from ..tracing.topology import triangle_normals
from ..util.vectors import DIVISION_FLOOR


@dataclass
class ImageFrame:
    """Where an image of a chart rectangle lies on the receiver, in the
    terms of a Mapping node of vector type TEXTURE, whose output
    R^T (p - location) / scale is the image's [0,1]^2 coordinate:

    coordinates  'POSITION': p is the world position (a flat receiver);
                 'UV': p is the receiver's UV coordinate (z = 0)
    location     (3,) p at the image's first corner (its first row's start)
    rotation     (3,3) world axes of the image's x and y and of the
                 receiver's normal, as columns; the identity for 'UV'
    scale        (3,) the image's width and height in p's units, and 1
    """

    coordinates: Literal["POSITION", "UV"]
    location: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray


class Chart:
    """A receiver's 2D parameterisation in metres.

    origin (2,) and size (2,): the rectangle of chart coordinates it covers.
    """

    origin: np.ndarray
    size: np.ndarray

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


class PlaneChart(Chart):
    """A flat receiver: coordinates along two unit axes in its plane."""

    def __init__(self, point: np.ndarray, normal: np.ndarray, vertices: np.ndarray):
        self.point, self.normal = point, normal
        self.axis_x, self.axis_y = orthonormal_basis(normal)
        local = self._local(vertices)
        self.origin, self.size = local.min(axis=0), np.ptp(local, axis=0)

    def _local(self, points: np.ndarray) -> np.ndarray:
        rel = points - self.point
        return np.stack([rel @ self.axis_x, rel @ self.axis_y], axis=1)

    def coords(self, prim, u, v, points):
        return self._local(points)

    def area_scale(self, prim):
        return np.ones(len(prim))

    def footprint(self, origins: np.ndarray, dirs: np.ndarray, d_origins: np.ndarray, d_dirs: np.ndarray,
                  stratum: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The chart rectangle that stands for the footprint of a pixel
        stratum, `stratum` pixels wide, around each ray `origins, dirs
        (n,3)` whose change per pixel step is `d_origins, d_dirs (n,2,3)`
        (camera.ray_differentials): (lo (n,2), hi (n,2), ok (n,) bool); not
        ok where the ray misses the plane.

        To first order the footprint is the parallelogram that J, the chart
        point's derivative per pixel step (2x2), spans around the hit, and a
        pixel is the mean over its square, uniform in pixel space. The
        rectangle with the same centre and, along each chart axis, the same
        variance (J_x^2 + J_y^2) stratum^2 / 12 keeps that mean to second
        order along each axis; the parallelogram's bounding box is wider
        where it is sheared (off the image's centre lines) and blurs a
        caustic's fold. The hit moves by dp = do + s dd - d (N.(do + s dd))
        / (N.d), s the distance along the ray (Igehy 1999)."""
        along = dirs @ self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            s = ((self.point - origins) @ self.normal) / along
        ok = np.isfinite(s) & (s > 0)
        s, along = np.where(ok, s, 0.0), np.where(ok, along, 1.0)
        moved = (d_origins + s[:, None, None] * d_dirs).reshape(-1, 3)
        across = np.repeat(dirs / along[:, None], 2, axis=0)
        d_points = moved - across * (moved @ self.normal)[:, None]
        jacobian = (d_points @ np.stack([self.axis_x, self.axis_y], axis=1)).reshape(-1, 2, 2)
        half = 0.5 * stratum * np.sqrt(jacobian[:, 0] ** 2 + jacobian[:, 1] ** 2)
        centre = self._local(origins + s[:, None] * dirs)
        return centre - half, centre + half, ok

    def image_frame(self, corner, extent):
        rotation = np.stack([self.axis_x, self.axis_y, self.normal], axis=1)
        return ImageFrame("POSITION", self.world(np.asarray(corner, dtype=np.float64)[None])[0], rotation,
                          np.array([extent[0], extent[1], 1.0]))

    def world(self, xy: np.ndarray) -> np.ndarray:
        """(n,3) world points of chart coordinates `xy (n,2)`."""
        return self.point + xy[:, :1] * self.axis_x + xy[:, 1:] * self.axis_y


class UVChart(Chart):
    """A curved receiver, through its UV map scaled to metres: one UV unit is
    `metres_per_uv` metres, chosen so that chart and world areas agree in total."""

    def __init__(self, corner_uvs: np.ndarray, world_areas: np.ndarray):
        self.corner_uvs = corner_uvs
        e1, e2 = corner_uvs[:, 1] - corner_uvs[:, 0], corner_uvs[:, 2] - corner_uvs[:, 0]
        uv_areas = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        self.metres_per_uv = math.sqrt(world_areas.sum() / max(uv_areas.sum(), DIVISION_FLOOR))
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = uv_areas * self.metres_per_uv ** 2 / world_areas
        self._area_scale = np.where(np.isfinite(scale), scale, 0.0)
        flat = corner_uvs.reshape(-1, 2) * self.metres_per_uv
        self.origin, self.size = flat.min(axis=0), np.ptp(flat, axis=0)

    def coords(self, prim, u, v, points):
        c = self.corner_uvs[prim]
        uv = (1.0 - u - v)[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        return uv * self.metres_per_uv

    def area_scale(self, prim):
        return self._area_scale[prim]

    def image_frame(self, corner, extent):
        return ImageFrame("UV", np.array([corner[0], corner[1], 0.0]) / self.metres_per_uv, np.eye(3),
                          np.array([extent[0] / self.metres_per_uv, extent[1] / self.metres_per_uv, 1.0]))


def make_chart(obj: Object, planarity_tolerance: float = 1e-6) -> Optional[Chart]:
    """The chart of a receiver: its plane if it is flat, else its UV map; None
    if it is curved and has no UVs."""
    mesh = obj.mesh
    normals, areas = triangle_normals(mesh.corners)
    if areas.sum() <= 0:
        return None
    normal = (normals * areas[:, None]).sum(axis=0)
    if np.linalg.norm(normal) > 0:
        normal /= np.linalg.norm(normal)
        center = mesh.vertices.mean(axis=0)
        size = np.ptp(mesh.vertices, axis=0).max()
        if np.abs((mesh.vertices - center) @ normal).max() <= planarity_tolerance * max(size, DIVISION_FLOOR):
            return PlaneChart(center, normal, mesh.vertices)
    if mesh.corner_uvs is not None:
        return UVChart(mesh.corner_uvs, areas)
    return None
