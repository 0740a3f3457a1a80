"""Small analytic scenes the engine tests share: a point lamp on the axis of
a glass sphere over a diffuse floor, seen from straight above."""

import math

import numpy as np

from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, RenderSettings, Scene
from caustic_addon import shapes

LAMP_Z = 6.0
POWER = 1000.0


def top_camera(half_width: float, pixels: int, height: float = 20.0) -> Camera:
    """An orthographic camera looking straight down at the floor, square
    image spanning [-half_width, half_width] in x and y."""
    matrix = np.eye(4)
    matrix[2, 3] = height
    return Camera(matrix, pixx=pixels, pixy=pixels, kind="ORTHO", ortho_scale=2 * half_width)


def ball_lens(scale=1.0, ior=1.5, center_z=1.5, radius=1.0, pixels=64, half_width=2.0, floor=8.0,
              albedo=1.0, absorption=0.0, segments=128) -> Scene:
    """Everything scaled by `scale`; the lamp's power by scale^2 so that
    irradiance (power / distance^2) does not change."""
    glass = shapes.uv_sphere(radius * scale, (0, 0, center_z * scale), segments, segments // 2)
    return Scene(
        objects=[Object("Floor", shapes.plane(floor * scale), Diffuse(albedo=albedo)),
                 Object("Glass", glass, Dielectric(ior, absorption=absorption))],
        lights=[PointLight((0, 0, LAMP_Z * scale), POWER * scale ** 2)],
        camera=top_camera(half_width * scale, pixels, 20.0 * scale),
    )


def floor_points(scene: Scene) -> np.ndarray:
    """(pixy, pixx, 2) floor x, y under each pixel centre of the top camera."""
    cam = scene.camera
    step = cam.ortho_scale / cam.pixx
    xs = (np.arange(cam.pixx) + 0.5) * step - 0.5 * cam.ortho_scale
    ys = 0.5 * cam.ortho_scale - (np.arange(cam.pixy) + 0.5) * step
    return np.stack(np.meshgrid(xs, ys), axis=-1)


def unobstructed_irradiance(xy: np.ndarray, lamp_z: float = LAMP_Z, power: float = POWER) -> np.ndarray:
    """I cos(theta) / d^2 on the floor z = 0 from the point lamp on the axis."""
    intensity = power / (4 * math.pi)
    d2 = (xy ** 2).sum(axis=-1) + lamp_z ** 2
    return intensity * lamp_z / d2 ** 1.5


def shadow_radius(center_z=1.5, radius=1.0, lamp_z=LAMP_Z) -> float:
    """Radius of the sphere's geometric shadow on the floor."""
    half = math.asin(radius / (lamp_z - center_z))
    return lamp_z * math.tan(half)


def quick(**kwargs) -> RenderSettings:
    base = dict(lamp_rays=400_000, spp=1, chunk_size=1 << 16, density="adaptive")
    base.update(kwargs)
    return RenderSettings(**base)
