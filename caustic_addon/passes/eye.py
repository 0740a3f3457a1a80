"""The backward pass: Whitted ray tracing from the eye (the paper's backward
ray tracing), with the illumination maps' light on the receivers.

Where a camera ray meets a flat receiver directly, the caustic is averaged
over the footprint of the ray's pixel stratum, not read at one point: a
caustic's folds are singular, and point samples of them alias.

At an opaque surface: ambient * albedo, plus direct light from each lamp and
from the world (direct_light.py), plus caustic irradiance E_c * albedo / pi
read from the receiver's map. Under a Principled BSDF's specular layer the
albedo is the base colour times the share the layer leaves it toward the
eye (optics/principled.py); the lobe itself reflects the lamps and the
world, but not the caustic, whose directions the map does not keep.

At a dielectric: both the reflected ray (weight F) and the refracted ray
(weight 1 - F) carry on, each tinted by the glass colour and by
Beer-Lambert absorption inside, up to `max_depth` bounces. At a reflector the reflected ray carries on, times the reflectance
colour. At a rough surface both branches leave about one GGX microfacet
normal per eye sample (bounce.facets), the pixel's samples stratified over
the visible normals, so rough glass and metal look rough, and lamps add
their highlights there by next-event estimation (direct_light.py), as in
Cycles. A ray that leaves the scene sees the world. Eye rays refract with a dispersive glass's
IOR at 587.6 nm: the caustics it throws are spectral (photon pass), the view
through it is not.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..emission.environment import Environment
from ..maps.charts import PlaneChart
from ..maps.illumination_map import IlluminationMap
from ..scene import RenderSettings, Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import CAMERA, Accelerator
from ..tracing.hits import Hits
from ..util.parallel import Monitor, chunk_size, run_chunks
from ..util.rows import take_rows
from ..util.vectors import dot
from .bounce import Interface, facets, multiscatter, split, trace
from .camera_rays import eye_rays, pixel_offsets, ray_differentials
from .direct_light import direct_radiance, rough_specular_radiance, strata, world_light
from .paths import Paths, relative_floor

PASSES = ("direct", "caustic", "ambient")
# The buffer of each pixel's share cut out by holdouts (its alpha is 1 minus it).
HOLDOUT = "holdout"
# Hash streams of the rotations of a pixel's microfacet strata: two a bounce.
_FACET_STREAM = 1 << 17


class EyeTracer:
    """The eye pass's choices in the bounce (bounce.trace), for the eye rays
    of the flat pixels [first_pixel, end_pixel): the world where a ray
    escapes, shading where it meets an opaque surface, both branches at a
    specular one, where camera rays meeting a holdout stop. A path's id is
    its eye sample, `spp` to a pixel. Pass buffers, the holdout's among
    them, are each (end_pixel - first_pixel, 3). A camera ray (one with no
    specular event yet) stands for a square stratum of its pixel, of side
    1 / sqrt(spp) pixels. `holdout (m,)` bool per object."""

    def __init__(self, accel: Accelerator, scene: Scene, materials: Materials, maps: dict[int, IlluminationMap],
                 environment: Environment, settings: RenderSettings, first_pixel: int, end_pixel: int,
                 holdout: np.ndarray):
        self.accel, self.scene, self.materials, self.maps = accel, scene, materials, maps
        self.holdout = holdout
        self.environment, self.settings = environment, settings
        self.energy, self.spp = settings.energy, settings.spp
        self.stratum = 1.0 / math.sqrt(settings.spp)
        self.first_pixel, self.end_pixel = int(first_pixel), int(end_pixel)
        self.far = 4.0 * scene.extent() + float(np.abs(scene.camera.position).max())
        self.buffers = {name: np.zeros((self.end_pixel - self.first_pixel, 3)) for name in (*PASSES, HOLDOUT)}

    def _add(self, name: str, pixel: np.ndarray, radiance: np.ndarray) -> None:
        size = self.end_pixel - self.first_pixel
        for c in range(3):
            self.buffers[name][:, c] += np.bincount(pixel - self.first_pixel, weights=radiance[:, c], minlength=size)

    def escaped(self, rays: Paths) -> None:
        self._add("ambient", rays.ids // self.spp, rays.weight * self.environment.radiance(rays.dirs))

    def _cut_out(self, rays: Paths, hits: Hits) -> np.ndarray:
        """(n,) bool: the camera rays that met a holdout, their weight added
        to the holdout buffer."""
        cut = np.take(self.holdout, hits.obj) & (rays.kind == CAMERA)
        if cut.any():
            here = rays.select(cut)
            self._add(HOLDOUT, here.ids // self.spp, here.weight)
        return cut

    def arrived(self, rays: Paths, hits: Hits) -> None:
        cut = self._cut_out(rays, hits)
        if cut.any():
            rays, hits = rays.select(~cut), hits.select(~cut)
        if len(rays) == 0:
            return
        m, accel = self.materials, self.accel
        view = -rays.dirs
        facing = np.take(accel.face_normal, hits.prim, axis=0)
        facing = np.where((dot(facing, view) < 0.0)[:, None], -facing, facing)
        shading = accel.shading_normal(hits.prim, hits.u, hits.v)
        shading = np.where((dot(shading, view) < 0.0)[:, None], -shading, shading)
        triangle = hits.prim - np.take(accel.prim_offset, hits.obj)
        albedo = m.albedo_at(hits.obj, triangle, hits.u, hits.v, hits.points)
        lobe, share = m.lobe_at(hits.obj, dot(shading, view))
        diffuse = albedo * share[:, None]

        points, settings = hits.points, self.settings
        pixel, stratum = rays.ids // self.spp, rays.ids % self.spp
        direct = direct_radiance(accel, self.scene.lights, self.energy, points, shading, facing, view, diffuse,
                                 lobe, self.far, pixel, stratum, settings.lamp_samples, settings.seed)
        self._add("direct", pixel, rays.weight * (direct + np.take(m.emission, hits.obj, axis=0)))
        ambient = self.scene.ambient * diffuse
        if not self.scene.world.is_black:
            world, glossy = world_light(accel, self.environment, points, shading, facing, view, lobe, self.far,
                                        pixel, stratum, settings.world_samples, settings.seed)
            ambient = ambient + world * diffuse / math.pi + glossy
        self._add("ambient", pixel, rays.weight * ambient)

        for index, imap in self.maps.items():
            on_map = hits.obj == index
            if not on_map.any():
                continue
            here, at = rays.select(on_map), hits.select(on_map)
            xy = imap.chart.coords(at.prim - accel.prim_offset[index], at.u, at.v, at.points)
            irradiance = np.empty((len(xy), 3))
            spread = np.zeros(len(xy), dtype=bool)
            primary = np.flatnonzero(~here.specular)
            if len(primary) and isinstance(imap.chart, PlaneChart):
                origins, dirs = np.take(here.origins, primary, axis=0), np.take(here.dirs, primary, axis=0)
                lo, hi, ok = imap.chart.footprint(origins, dirs, *ray_differentials(self.scene.camera, dirs),
                                                  self.stratum)
                spread[primary[ok]] = True
                irradiance[spread] = imap.mean_over(lo[ok], hi[ok])
            irradiance[~spread] = imap.irradiance_at(xy[~spread])
            radiance = irradiance * take_rows(on_map, diffuse)[0] / math.pi
            self._add("caustic", here.ids // self.spp, here.weight * radiance)

    def scattered(self, rays: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        cut = self._cut_out(rays, hits)
        if cut.any():
            rays, hits, surface = rays.select(~cut), hits.select(~cut), surface.select(~cut)
        if surface.rough.any():
            self._highlights(rays, hits, surface)
            uv = strata(rays.ids // self.spp, rays.ids % self.spp, _FACET_STREAM + 2 * depth, self.settings.seed)
            surface = facets(surface, rays.dirs, self.materials, hits.obj, uv)
        return split(self.accel, self.materials, rays, hits, surface, carries_light=False)

    def _highlights(self, rays: Paths, hits: Hits, surface: Interface) -> None:
        """The lamps' direct light on the rough rows of `surface`, into the
        direct pass, times the tint and Multiscatter GGX's factor."""
        if not self.scene.lights:
            return
        rows = np.flatnonzero(surface.rough)
        m, obj = self.materials, hits.obj[rows]
        pixel, stratum = rays.ids[rows] // self.spp, rays.ids[rows] % self.spp
        radiance = rough_specular_radiance(
            self.accel, self.scene.lights, self.energy, np.take(surface.points, rows, axis=0),
            np.take(surface.shading, rows, axis=0), np.take(surface.facing, rows, axis=0),
            -np.take(rays.dirs, rows, axis=0), surface.alpha[rows], surface.eta[rows], m.reflector[obj], self.far,
            pixel, stratum, self.settings.lamp_samples, self.settings.seed)
        factor = multiscatter(surface, m, hits.obj, rays.dirs, rays.dirs, np.zeros(len(rays), dtype=bool), False)
        tint = np.take(m.color, obj, axis=0) * np.take(factor, rows, axis=0)
        self._add("direct", pixel, np.take(rays.weight, rows, axis=0) * tint * radiance)


def eye_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
             maps: dict[int, IlluminationMap], monitor: Monitor, start: float) -> dict[str, np.ndarray]:
    """Trace `spp` eye rays through every pixel, chunk by chunk, reporting
    progress from `start` to 1. Returns the pass buffers and the holdout's,
    each (pixels, 3)."""
    cam = scene.camera
    pixels = cam.pixx * cam.pixy
    offsets = pixel_offsets(settings.spp, settings.seed)
    samples = pixels * settings.spp
    camera_medium = int(accel.medium_at(cam.position[None])[0])
    size = chunk_size(samples, settings.chunk_size, settings.threads)

    environment = Environment(scene.world)
    holdout = np.array([o.visibility.holdout for o in scene.objects], dtype=bool)

    def job(first: int) -> EyeTracer:
        sample = np.arange(first, min(first + size, samples))
        pixel = sample // settings.spp
        origins, dirs = eye_rays(cam, pixel, offsets[sample % settings.spp])
        weight = np.full((len(sample), 3), 1.0 / settings.spp)
        tracer = EyeTracer(accel, scene, materials, maps, environment, settings, pixel[0], pixel[-1] + 1, holdout)
        trace(accel, materials, Paths.start(origins, dirs, weight, sample, camera_medium, relative_floor(weight),
                                            camera=True), settings.max_depth, tracer)
        return tracer

    jobs = [partial(job, first) for first in range(0, samples, size)]
    buffers = {name: np.zeros((pixels, 3)) for name in (*PASSES, HOLDOUT)}

    def add(tracer: EyeTracer) -> None:
        for name in buffers:
            buffers[name][tracer.first_pixel:tracer.end_pixel] += tracer.buffers[name]

    run_chunks(jobs, settings.threads, monitor, start, 1.0 - start, "eye pass", add)
    return buffers
