"""The ball-lens scene and its pixel-level error metric.

A glass sphere (R = 1, n = 1.5, centre 1.5 m up) on the axis of a 1000 W
point lamp 6 m up, over a white floor, seen by a 320x240 camera from the
side. The metric: relative L2 error, over the pixels that see the floor
directly inside the sphere's shadow disc, of the rendered caustic irradiance
against the exact pixel value: the reference irradiance averaged over the
pixel (a box filter, 8 x 8 sub-samples). The caustic's fold and its axis are
singular, so no point sample is a fair reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from benchmarks.references import reference
from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, Scene, shapes
from caustic_addon.passes.camera_rays import eye_rays
from caustic_addon.tracing.accelerator import Accelerator

RADIUS, IOR, CENTER_Z, LAMP_Z, POWER = 1.0, 1.5, 1.5, 6.0, 1000.0
INTENSITY = POWER / (4 * math.pi)
EYE, TARGET, FOV = (0.0, -5.0, 2.5), (0.0, 0.3, 0.0), math.radians(30.0)


def shadow_radius() -> float:
    half = math.asin(RADIUS / (LAMP_Z - CENTER_Z))
    return LAMP_Z * math.tan(half)


def scene(pixx: int = 320, pixy: int = 240, segments: int = 256) -> Scene:
    return Scene(
        objects=[Object("Floor", shapes.plane(8.0), Diffuse(albedo=1.0)),
                 Object("Glass", shapes.uv_sphere(RADIUS, (0, 0, CENTER_Z), segments, segments // 2),
                        Dielectric(IOR))],
        lights=[PointLight((0, 0, LAMP_Z), POWER)],
        camera=Camera.look_at(EYE, TARGET, pixx=pixx, pixy=pixy, fov=FOV),
    )


@dataclass
class PixelReference:
    """Exact caustic irradiance per pixel, and which pixels count.

    region     (pixy, pixx) bool: all of the pixel sees the floor directly,
               inside the shadow disc
    irradiance (pixy, pixx) W/m^2: the exact caustic irradiance averaged over
               the pixel
    """

    region: np.ndarray
    irradiance: np.ndarray

    def error(self, caustic_pass: np.ndarray) -> float:
        """Relative L2 error of a render's caustic pass (pixy, pixx, 3) on a
        white floor, whose irradiance is radiance * pi."""
        ours = caustic_pass[..., 0].astype(np.float64)[self.region] * math.pi
        exact = self.irradiance[self.region]
        return float(np.linalg.norm(ours - exact) / np.linalg.norm(exact))


def _pixel_irradiance(accel, cam, pixels: np.ndarray, supersample: int, edges, caustic):
    """(caustic mean (n,), whole pixel on the floor inside the disc (n,),
    radius range (n,2)) over `supersample`^2 sub-samples of each pixel."""
    spp = supersample ** 2
    ticks = (np.arange(supersample) + 0.5) / supersample
    offsets = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    sample = np.arange(len(pixels) * spp)
    origins, dirs = eye_rays(cam, pixels[sample // spp], offsets[sample % spp])
    hits = accel.intersect(origins, dirs)
    points = origins + hits.t[:, None] * dirs
    r = np.hypot(points[:, 0], points[:, 1])
    inside = (hits.obj == 0) & (r < edges[-1])
    value = np.where(inside, caustic[np.clip(np.searchsorted(edges, r) - 1, 0, len(caustic) - 1)], 0.0)
    r = r.reshape(-1, spp)
    return (value.reshape(-1, spp).mean(axis=1), inside.reshape(-1, spp).all(axis=1),
            np.stack([r.min(axis=1), r.max(axis=1)], axis=1))


def pixel_reference(the_scene: Scene, supersample: int = 8, bins: int = 8000) -> PixelReference:
    """The exact caustic, box-filtered over each pixel: `supersample`^2
    sub-samples per pixel, and 8 times as many per side where the pixel
    meets the axis or the fold (the ring where the caustic ends), whose
    singularities point samples would miss or overweight."""
    cam = the_scene.camera
    edges = np.linspace(0.0, shadow_radius(), bins + 1)
    exact = reference.ball_lens_irradiance(RADIUS, IOR, CENTER_Z, LAMP_Z, INTENSITY, edges)
    fold = edges[np.argmax(exact.caustic[bins // 100:]) + bins // 100 + 1]
    accel = Accelerator(the_scene.objects, the_scene.extent(), 2)
    pixels = np.arange(cam.pixx * cam.pixy)
    irradiance, region, r_range = _pixel_irradiance(accel, cam, pixels, supersample, edges, exact.caustic)
    margin = 2.0 * edges[-1] / bins
    hot = region & ((r_range[:, 0] < 0.02) | ((r_range[:, 0] < fold + margin) & (r_range[:, 1] > fold - margin)))
    irradiance[hot] = _pixel_irradiance(accel, cam, pixels[hot], 8 * supersample, edges, exact.caustic)[0]
    accel.close()
    return PixelReference(region.reshape(cam.pixy, cam.pixx), irradiance.reshape(cam.pixy, cam.pixx))
