"""The speed scene: a smooth 65,536-triangle glass sphere (R = 1 m, n = 1.5,
centre 1.5 m up) over a diffuse floor (albedo 0.8), a 1000 W point lamp 6 m
up, a 640x480 camera; or the same sphere of another material (speed.py's
mirror ball, dispersion.py's dispersive glass)."""

from __future__ import annotations

from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, Scene, shapes


def scene(material=None) -> Scene:
    """The glass sphere scene, or the same sphere of another `material`."""
    return Scene(
        objects=[Object("Floor", shapes.plane(10.0), Diffuse(albedo=0.8)),
                 Object("Glass", shapes.uv_sphere(1.0, (0, 0, 1.5), 256, 128), material or Dielectric(1.5))],
        lights=[PointLight((0, 0, 6), 1000.0)],
        camera=Camera.look_at((0, -6, 5), (0, 0, 0.5), pixx=640, pixy=480),
    )
