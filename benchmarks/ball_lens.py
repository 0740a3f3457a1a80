"""Issue 4's ball-lens scene and its pixel-level error metric.

A glass sphere (R = 1, n = 1.5, centre 1.5 m up) on the axis of a 1000 W
point lamp 6 m up, over a white floor, seen by a 320x240 camera from the
side. The metric: relative L2 error, over the pixels that see the floor
directly inside the sphere's shadow disc, of the rendered caustic irradiance
against the exact reference evaluated at the very same sub-pixel sample
points, so that pixel filtering cannot hide or add error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import reference
from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, Scene, shapes
from caustic_addon.accel import Accelerator
from caustic_addon.camera import eye_rays, pixel_offsets

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

    region     (pixy, pixx) bool: every sample of the pixel sees the floor
               directly, inside the shadow disc
    irradiance (pixy, pixx) W/m^2: the exact caustic irradiance averaged over
               the pixel's samples
    """

    region: np.ndarray
    irradiance: np.ndarray

    def error(self, caustic_pass: np.ndarray) -> float:
        """Relative L2 error of a render's caustic pass (pixy, pixx, 3) on a
        white floor, whose irradiance is radiance * pi."""
        ours = caustic_pass[..., 0].astype(np.float64)[self.region] * math.pi
        exact = self.irradiance[self.region]
        return float(np.linalg.norm(ours - exact) / np.linalg.norm(exact))


def pixel_reference(the_scene: Scene, spp: int, seed: int = 0, bins: int = 4000) -> PixelReference:
    """The exact caustic at the same sample points the engine's eye pass uses."""
    cam = the_scene.camera
    edges = np.linspace(0.0, shadow_radius(), bins + 1)
    exact = reference.ball_lens_irradiance(RADIUS, IOR, CENTER_Z, LAMP_Z, INTENSITY, edges)
    accel = Accelerator(the_scene.objects, the_scene.extent(), 2)
    pixels = cam.pixx * cam.pixy
    sample = np.arange(pixels * spp)
    origins, dirs = eye_rays(cam, sample // spp, pixel_offsets(spp, seed)[sample % spp])
    hits = accel.intersect(origins, dirs)
    accel.close()
    points = origins + hits.t[:, None] * dirs
    r = np.hypot(points[:, 0], points[:, 1])
    inside = (hits.obj == 0) & (r < edges[-1])
    value = exact.caustic[np.clip(np.searchsorted(edges, r) - 1, 0, bins - 1)]
    region = inside.reshape(pixels, spp).all(axis=1)
    irradiance = np.where(inside, value, 0.0).reshape(pixels, spp).mean(axis=1)
    return PixelReference(region.reshape(cam.pixy, cam.pixx), irradiance.reshape(cam.pixy, cam.pixx))
