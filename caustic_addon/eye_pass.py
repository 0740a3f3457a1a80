"""The backward pass: Whitted ray tracing from the eye (the paper's backward
ray tracing), with the illumination maps' light on the receivers.

Where a camera ray meets a flat receiver directly, the caustic is averaged
over the footprint of the ray's pixel stratum, not read at one point: a
caustic's folds are singular, and point samples of them alias.

At an opaque surface: ambient * albedo, plus direct light from each lamp
(lighting.py), plus caustic irradiance E_c * albedo / pi read from the
receiver's map. At a dielectric: both the reflected ray (weight F) and the
refracted ray (weight 1 - F) carry on, each tinted by the glass colour and by
Beer-Lambert absorption inside, up to `max_depth` bounces. At a reflector
the reflected ray carries on, times the reflectance colour. A ray that leaves
the scene sees the background. Eye rays refract with a dispersive glass's
IOR at 587.6 nm: the caustics it throws are spectral (photon pass), the view
through it is not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .accel import Accelerator, MISS
from .camera import ray_differentials
from .illumination_map import IlluminationMap, PlaneChart
from .interface import orient, scatter
from .lighting import direct_radiance
from .materials import Materials
from .optics import beer_lambert, dot
from .scene import Scene

PASSES = ("direct", "caustic", "ambient")
# A ray whose weight (max channel) drops below this is not traced further.
MIN_WEIGHT = 1e-4


@dataclass
class EyeRays:
    """n eye rays in flight: origins (n,3), dirs (n,3), weight (n,3)
    throughput, pixel (n,) flat pixel index, medium (n,) object inside or
    MISS. `primary`: these are camera rays, each through its own pixel
    stratum."""

    origins: np.ndarray
    dirs: np.ndarray
    weight: np.ndarray
    pixel: np.ndarray
    medium: np.ndarray
    primary: bool = False

    def select(self, mask: np.ndarray) -> "EyeRays":
        return EyeRays(self.origins[mask], self.dirs[mask], self.weight[mask], self.pixel[mask], self.medium[mask],
                       self.primary)

    @staticmethod
    def concat(parts: list["EyeRays"]) -> "EyeRays":
        return EyeRays(*(np.concatenate([getattr(p, f) for p in parts])
                         for f in ("origins", "dirs", "weight", "pixel", "medium")))


class EyePass:
    """Shades eye rays of the flat pixels [first_pixel, end_pixel) into pass
    buffers, each (end_pixel - first_pixel, 3). Each camera ray stands for a
    square stratum of its pixel, `stratum` pixels wide."""

    def __init__(self, accel: Accelerator, scene: Scene, materials: Materials,
                 maps: dict[int, IlluminationMap], energy: float, max_depth: int, stratum: float,
                 first_pixel: int, end_pixel: int):
        self.accel, self.scene, self.materials, self.maps = accel, scene, materials, maps
        self.energy, self.max_depth, self.stratum = energy, max_depth, stratum
        self.first_pixel, self.end_pixel = int(first_pixel), int(end_pixel)
        self.far = 4.0 * scene.extent() + float(np.abs(scene.camera.position).max())
        self.buffers = {name: np.zeros((self.end_pixel - self.first_pixel, 3)) for name in PASSES}

    def _add(self, name: str, pixel: np.ndarray, radiance: np.ndarray) -> None:
        size = self.end_pixel - self.first_pixel
        for c in range(3):
            self.buffers[name][:, c] += np.bincount(pixel - self.first_pixel, weights=radiance[:, c], minlength=size)

    def trace(self, rays: EyeRays) -> None:
        for _ in range(self.max_depth + 1):
            if len(rays.pixel) == 0:
                return
            hits = self.accel.intersect(rays.origins, rays.dirs, rays.medium)
            missed = ~hits.hit
            self._add("ambient", rays.pixel[missed], rays.weight[missed] * self.scene.background)
            rays, hits = rays.select(~missed), hits.select(~missed)
            points = hits.points
            inside = rays.medium != MISS
            if inside.any():
                rays.weight[inside] *= beer_lambert(self.materials.absorption[rays.medium[inside]], hits.t[inside])

            bounce = self.materials.specular_surface[hits.obj]
            self._shade_opaque(rays.select(~bounce), hits.select(~bounce), points[~bounce])
            rays = self._split_at_specular(rays.select(bounce), hits.select(bounce), points[bounce])

    def _shade_opaque(self, rays: EyeRays, hits, points: np.ndarray) -> None:
        if len(rays.pixel) == 0:
            return
        m, accel = self.materials, self.accel
        view = -rays.dirs
        facing = accel.face_normal[hits.prim]
        facing = np.where((dot(facing, view) < 0.0)[:, None], -facing, facing)
        shading = accel.shading_normal(hits.prim, hits.u, hits.v)
        shading = np.where((dot(shading, view) < 0.0)[:, None], -shading, shading)
        albedo = m.albedo[hits.obj]

        direct = direct_radiance(accel, self.scene.lights, self.energy, points, shading, facing, view,
                                 albedo, m.specular[hits.obj], m.exponent[hits.obj], self.far)
        self._add("direct", rays.pixel, rays.weight * direct)
        self._add("ambient", rays.pixel, rays.weight * self.scene.ambient * albedo)

        for index, imap in self.maps.items():
            sel = hits.obj == index
            if not sel.any():
                continue
            local = hits.prim[sel] - accel.prim_offset[index]
            xy = imap.chart.coords(local, hits.u[sel], hits.v[sel], points[sel])
            irradiance = np.empty((len(xy), 3))
            spread = np.zeros(len(xy), dtype=bool)
            if rays.primary and isinstance(imap.chart, PlaneChart):
                dirs = rays.dirs[sel]
                lo, hi, spread = imap.chart.footprint(rays.origins[sel], dirs,
                                                      *ray_differentials(self.scene.camera, dirs), self.stratum)
                irradiance[spread] = imap.mean_over(lo[spread], hi[spread])
            irradiance[~spread] = imap.irradiance_at(xy[~spread])
            radiance = irradiance * albedo[sel] / math.pi
            self._add("caustic", rays.pixel[sel], rays.weight[sel] * radiance)

    def _split_at_specular(self, rays: EyeRays, hits, points: np.ndarray) -> EyeRays:
        """The reflected children of rays at dielectric and reflector hits,
        and the refracted children at dielectric hits."""
        if len(rays.pixel) == 0:
            return rays
        surface = orient(self.accel, hits, rays.dirs, points, self.materials, rays.medium)
        tint = self.materials.color[hits.obj]
        children = []
        for mirror in (True, False):
            dirs, crossed = scatter(surface, rays.dirs, np.full(len(rays.pixel), mirror))
            share = surface.fresnel if mirror else np.where(crossed, 1.0 - surface.fresnel, 0.0)
            weight = rays.weight * tint * share[:, None]
            medium = np.where(crossed, np.where(surface.entering, hits.obj, MISS), rays.medium)
            origins = self.accel.offset(points, surface.facing, dirs)
            child = EyeRays(origins, dirs, weight, rays.pixel, medium)
            children.append(child.select(weight.max(axis=1) >= MIN_WEIGHT))
        return EyeRays.concat(children)
