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

from ..maps.charts import PlaneChart
from ..maps.illumination_map import IlluminationMap
from ..optics.media import beer_lambert
from ..scene import Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS
from ..util.rows import take_rows
from ..util.vectors import dot, max_channel
from .bounce import orient, scatter
from .camera_rays import ray_differentials
from .direct_light import direct_radiance

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
        return EyeRays(*take_rows(mask, self.origins, self.dirs, self.weight, self.pixel, self.medium), self.primary)

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
            inside = rays.medium != MISS
            if inside.any():
                rays.weight[inside] *= beer_lambert(np.take(self.materials.absorption, rays.medium[inside], axis=0),
                                                    hits.t[inside])

            bounce = self.materials.specular_surface[hits.obj]
            self._shade_opaque(rays.select(~bounce), hits.select(~bounce))
            rays = self._split_at_specular(rays.select(bounce), hits.select(bounce))

    def _shade_opaque(self, rays: EyeRays, hits) -> None:
        if len(rays.pixel) == 0:
            return
        m, accel = self.materials, self.accel
        view = -rays.dirs
        facing = np.take(accel.face_normal, hits.prim, axis=0)
        facing = np.where((dot(facing, view) < 0.0)[:, None], -facing, facing)
        shading = accel.shading_normal(hits.prim, hits.u, hits.v)
        shading = np.where((dot(shading, view) < 0.0)[:, None], -shading, shading)
        albedo = np.take(m.albedo, hits.obj, axis=0)

        points = hits.points
        direct = direct_radiance(accel, self.scene.lights, self.energy, points, shading, facing, view,
                                 albedo, np.take(m.specular, hits.obj, axis=0), m.exponent[hits.obj], self.far)
        self._add("direct", rays.pixel, rays.weight * direct)
        self._add("ambient", rays.pixel, rays.weight * self.scene.ambient * albedo)

        for index, imap in self.maps.items():
            on_map = hits.obj == index
            if not on_map.any():
                continue
            here, at = rays.select(on_map), hits.select(on_map)
            xy = imap.chart.coords(at.prim - accel.prim_offset[index], at.u, at.v, at.points)
            irradiance = np.empty((len(xy), 3))
            spread = np.zeros(len(xy), dtype=bool)
            if here.primary and isinstance(imap.chart, PlaneChart):
                lo, hi, spread = imap.chart.footprint(here.origins, here.dirs,
                                                      *ray_differentials(self.scene.camera, here.dirs), self.stratum)
                irradiance[spread] = imap.mean_over(lo[spread], hi[spread])
            irradiance[~spread] = imap.irradiance_at(xy[~spread])
            radiance = irradiance * take_rows(on_map, albedo)[0] / math.pi
            self._add("caustic", here.pixel, here.weight * radiance)

    def _split_at_specular(self, rays: EyeRays, hits) -> EyeRays:
        """The reflected children of rays at dielectric and reflector hits,
        and the refracted children at dielectric hits."""
        if len(rays.pixel) == 0:
            return rays
        points = hits.points
        surface = orient(self.accel, hits, rays.dirs, points, self.materials, rays.medium)
        tint = np.take(self.materials.color, hits.obj, axis=0)
        children = []
        for mirror in (True, False):
            dirs, crossed = scatter(surface, rays.dirs, np.full(len(rays.pixel), mirror))
            share = surface.fresnel if mirror else np.where(crossed, 1.0 - surface.fresnel, 0.0)
            weight = rays.weight * tint * share[:, None]
            medium = np.where(crossed, np.where(surface.entering, hits.obj, MISS), rays.medium)
            origins = self.accel.offset(points, surface.facing, dirs)
            child = EyeRays(origins, dirs, weight, rays.pixel, medium)
            children.append(child.select(max_channel(weight) >= MIN_WEIGHT))
        return EyeRays.concat(children)
