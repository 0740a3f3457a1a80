"""The README's gallery: caustics the engine renders at its default
settings (40,000 lamp rays as beams, 4 samples per pixel), each written to
docs/gallery/<name>.png with its render time in docs/gallery/gallery.json.

    .venv/bin/python benchmarks/gallery.py

- ball_lens: a glass ball (n = 1.5) under a point lamp focuses its light
  into a bright disc ringed by the fold of the caustic.
- mirror_ring: a polished ring on a table under a low sun: the cardioid of a
  coffee cup, its cusp at half the ring's radius.
- wavy_water: sunlight through a rippled slab of water: the network of lines
  on a pool's floor.
- dispersive_gem: a facetted gem of strongly dispersive glass (n = 2.0,
  Abbe number 20): each facet throws a beam that the spectrum fans out.
- softbox: the glass ball under a studio's square area lamp, 1.5 m across:
  a soft caustic in a soft shadow.
- sunny_sky: the glass ball under a sky with a sun in it, the world's light
  alone: a blue sky lights the floor and fills the shadow, and the sun's
  caustic comes through the glass.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # the repository root

import numpy as np  # noqa: E402

from benchmarks import record  # noqa: E402
from caustic_addon import (AreaLight, Camera, Dielectric, Diffuse, Mesh, Object, PointLight, Reflector,  # noqa: E402
                           RenderSettings, Scene, SunLight, World, compile_kernels, render, shapes)
from caustic_addon.emission.environment import uv_to_directions  # noqa: E402
from caustic_addon.cli.image_io import write_image  # noqa: E402

OUT = REPO / "docs" / "gallery"
PIXELS = (480, 360)


def ball_lens() -> Scene:
    return Scene(
        objects=[Object("Floor", shapes.plane(8.0), Diffuse(albedo=0.8)),
                 Object("Ball", shapes.uv_sphere(1.0, (0.0, 0.0, 1.5), 256, 128), Dielectric(1.5))],
        lights=[PointLight((0.0, 0.0, 6.0), 1000.0)],
        camera=Camera.look_at((0.0, -6.5, 3.6), (0.0, 0.0, 0.6), pixx=PIXELS[0], pixy=PIXELS[1],
                              fov=math.radians(40.0)),
        world=World(0.05))


def mirror_ring() -> Scene:
    sun = (math.cos(math.radians(25.0)), 0.0, -math.sin(math.radians(25.0)))
    return Scene(
        objects=[Object("Table", shapes.plane(3.0), Diffuse(albedo=0.8)),
                 Object("Ring", shapes.tube(0.5, 0.25, segments=512), Reflector(0.9))],
        lights=[SunLight(sun, 3.0)],
        camera=Camera.look_at((-0.3, -1.2, 1.6), (0.05, 0.0, 0.0), pixx=PIXELS[0], pixy=PIXELS[1],
                              fov=math.radians(45.0)),
        world=World(0.05))


def wavy_water() -> Scene:
    water = shapes.wavy_slab(2.4, 0.25, ((0.012, 0.45, 0.3), (0.009, 0.31, 1.4), (0.006, 0.23, 2.5)), 192,
                             (0.0, 0.0, 0.35))
    return Scene(
        objects=[Object("Pool floor", shapes.plane(4.0), Diffuse(albedo=0.7)),
                 Object("Water", water, Dielectric(1.33))],
        lights=[SunLight((0.15, 0.1, -1.0), 4.0)],
        camera=Camera.look_at((0.0, -1.6, 2.2), (0.0, 0.15, 0.0), pixx=PIXELS[0], pixy=PIXELS[1],
                              fov=math.radians(40.0)),
        world=World(0.05))


def dispersive_gem() -> Scene:
    cone = shapes.cone(0.4, 0.55, (0.0, 0.0, 0.45), segments=10)
    gem = Mesh(cone.vertices, cone.triangles)  # flat facets: no corner normals
    return Scene(
        objects=[Object("Floor", shapes.plane(4.0), Diffuse(albedo=0.6)),
                 Object("Gem", gem, Dielectric(2.0, abbe=20.0))],
        lights=[PointLight((0.6, 0.3, 3.0), 600.0)],
        camera=Camera.look_at((0.0, -2.6, 2.4), (-0.1, 0.1, 0.25), pixx=PIXELS[0], pixy=PIXELS[1],
                              fov=math.radians(40.0)),
        world=World(0.05))


def softbox() -> Scene:
    scene = ball_lens()
    tilt = math.radians(20.0)
    scene.lights = [AreaLight((0.0, -1.0, 5.0), (0.75, 0.0, 0.0), (0.0, 0.75 * math.cos(tilt), 0.75 * math.sin(tilt)),
                              (0.0, math.sin(tilt), -math.cos(tilt)), 3000.0)]
    return scene


def sky_with_sun(width: int = 1024, elevation: float = 40.0, azimuth: float = 120.0) -> np.ndarray:
    """(h, w, 3) a lat-long sky, W/(m^2 sr): blue overhead and white at the
    horizon, a dim ground, and a sun 0.6 degrees across at `elevation` and
    `azimuth` (degrees from +X toward +Y) giving 300 W/m^2, six times the
    sky's."""
    h = width // 2
    v, u = np.meshgrid((np.arange(h) + 0.5) / h, (np.arange(width) + 0.5) / width, indexing="ij")
    dirs = uv_to_directions(np.stack([u.ravel(), v.ravel()], axis=1)).reshape(h, width, 3)
    up = np.clip(dirs[..., 2], 0.0, 1.0)[..., None]
    sky = 16.0 * np.where(dirs[..., 2:] > 0.0,
                          (1.0 - up) * np.array([0.9, 0.95, 1.0]) + up * np.array([0.25, 0.45, 1.0]),
                          np.array([0.05, 0.045, 0.04]))
    e, a = math.radians(elevation), math.radians(azimuth)
    sun = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    half = math.radians(0.3)
    inside = dirs @ sun > math.cos(half)
    sky[inside] = 300.0 / (2.0 * math.pi * (1.0 - math.cos(half)))
    return sky


def sunny_sky() -> Scene:
    scene = ball_lens()
    scene.lights = []
    scene.world = World(1.0, sky_with_sun())
    return scene


# name -> (scene, exposure of its PNG in stops)
SCENES = {"ball_lens": (ball_lens, -1.0), "mirror_ring": (mirror_ring, -1.0), "wavy_water": (wavy_water, -1.5),
          "dispersive_gem": (dispersive_gem, -1.2), "softbox": (softbox, -3.5), "sunny_sky": (sunny_sky, -6.5)}


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    kernels = compile_kernels()
    print(f"compiling the engine's {kernels} kernels, once (or loading them): {time.perf_counter() - start:.1f} s")
    settings = RenderSettings()
    times = {}
    for name, (build, exposure) in SCENES.items():
        scene = build()
        start = time.perf_counter()
        result = render(scene, settings)
        seconds = time.perf_counter() - start
        write_image(OUT / f"{name}.png", result.image, exposure)
        times[name] = dict(seconds=round(seconds, 2), lamp_rays=result.stats["lamp_rays"],
                           triangles=result.stats["triangles"], warnings=result.warnings)
        print(f"{name:16s} {seconds:5.2f} s  {result.stats['lamp_rays']:,} lamp rays", flush=True)
    record.write("gallery", dict(pixels=list(PIXELS), spp=settings.spp, renders=times), folder=OUT)


if __name__ == "__main__":
    main()
