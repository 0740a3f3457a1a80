"""Water in a glass tumbler: the caustic it throws on the floor, by the
add-on as artists model the water, and by Cycles with the glass-water
interface built as Cycles needs it.

    .venv/bin/python benchmarks/liquid_glass.py [--cycles-samples 4096] [--side-by-side pair.png]

A tumbler (outer radius 0.4 m, 1 m tall, 5 cm walls, 10 cm base, IOR 1.5)
filled with water (IOR 1.33) to 0.6 m stands on a white floor under a sun
of angle 15 degrees, 40 degrees from the vertical, in a black world; seen
from the front at 160x120. The sun is wide so that Cycles, which finds a
sun through glass only by chance, converges on the caustic; what it sees
of the floor through the tumbler's water it still does not.

The add-on renders the water modelled three ways: its surface coincident
with the tumbler's inner wall and floor, 0.5 mm inside them, and 1 mm into
the glass, at its defaults (Beam, 40,000 light rays, 4 samples).

Cycles traces no nested media: each surface's IOR is the ratio across it.
Its reference therefore has three surfaces, the glass against the air (IOR
1.5), the wetted inner wall and floor (IOR 1.5 / 1.33, normals into the
water) and the water's top (IOR 1.33), rendered on the CPU with one diffuse
bounce (the floor's light through the glass: its caustic), 24 glossy and
transmission bounces (an eye ray through the tumbler and the light it
finds cross a dozen surfaces), refractive caustics on, no clamp, box filter, no
denoising, at --cycles-samples; a second render of another seed gives its
own noise. Cycles also renders the water as Cycles users commonly model
it, overlapping the glass by 1 mm with IOR 1.33, where each ray crosses
two interfaces as if through air.

Recorded: the image's mean against the reference, its relative L2 error,
and those over the caustic on the floor (the pixels outside the tumbler's
silhouette where the add-on's caustic pass holds a tenth of its peak
there), and the time. Writes benchmarks/results/liquid_glass.json.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks import record  # noqa: E402
from benchmarks.against_cycles import figures, reference_noise, write_pair  # noqa: E402

PIXX, PIXY = 160, 120
GLASS, WATER = 1.5, 1.33
OUTER, HEIGHT, INNER, BASE, LEVEL = 0.4, 1.0, 0.35, 0.1, 0.6
SEGMENTS = 128
# how the add-on's water is modelled: its wall's radius and its bottom's height
MODELLINGS = {"coincident with the glass": (INNER, BASE), "0.5 mm from the glass": (INNER - 5e-4, BASE + 5e-4),
              "1 mm into the glass": (INNER + 1e-3, BASE - 1e-3)}
CYCLES_SAMPLES = [1024]
SPECULAR_BOUNCES = 24
SUN_ANGLE = 15.0


def lathe(name: str, profile: list[tuple[float, float]], material, sharp_edges: bool = True) -> bpy.types.Object:
    """A mesh turned about Z from `profile` [(r, z)] (r 0: a pole), its
    faces' normals on the right of the profile's direction (a profile that
    runs counterclockwise round a solid in the (r, z) half-plane faces out),
    shaded smooth, but for edges sharper than 30 degrees where
    `sharp_edges`."""
    rings, verts = [], []
    for r, z in profile:
        if r == 0.0:
            rings.append([len(verts)])
            verts.append((0.0, 0.0, z))
        else:
            rings.append(list(range(len(verts), len(verts) + SEGMENTS)))
            verts += [(r * math.cos(2 * math.pi * j / SEGMENTS), r * math.sin(2 * math.pi * j / SEGMENTS), z)
                      for j in range(SEGMENTS)]
    faces = []
    for a, b in zip(rings, rings[1:]):
        for j in range(SEGMENTS):
            k = (j + 1) % SEGMENTS
            if len(a) == 1:
                faces.append((a[0], b[k], b[j]))
            elif len(b) == 1:
                faces.append((a[j], a[k], b[0]))
            else:
                faces.append((a[j], a[k], b[k], b[j]))
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.materials.append(material)
    mesh.shade_smooth()
    if sharp_edges:
        mesh.set_sharp_from_angle(angle=math.radians(30.0))
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def tumbler_scene(water: tuple[float, float] | None, empty: bool = False, sharp_edges: bool = True) -> None:
    """The floor, the sun and the camera; the tumbler and its water as
    closed meshes, the water's wall radius and bottom height `water`, or,
    where None, Cycles' three surfaces; no water where `empty`."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scenes.add_plane(10.0, scenes.diffuse_material())
    if water is None:
        lathe("Glass", [(0.0, 0.0), (OUTER, 0.0), (OUTER, HEIGHT), (INNER, HEIGHT), (INNER, LEVEL)],
              scenes.glass_material("Glass", GLASS))
        lathe("Wetted", [(INNER, LEVEL), (INNER, BASE), (0.0, BASE)], scenes.glass_material("Wetted", GLASS / WATER))
        lathe("Water", [(INNER, LEVEL), (0.0, LEVEL)], scenes.glass_material("Water", WATER))
    else:
        radius, bottom = water
        lathe("Glass", [(0.0, 0.0), (OUTER, 0.0), (OUTER, HEIGHT), (INNER, HEIGHT), (INNER, BASE), (0.0, BASE)],
              scenes.glass_material("Glass", GLASS), sharp_edges)
        if not empty:
            lathe("Water", [(0.0, bottom), (radius, bottom), (radius, LEVEL), (0.0, LEVEL)],
                  scenes.glass_material("Water", WATER), sharp_edges)
    light = bpy.data.lights.new("Sun", 'SUN')
    light.energy, light.angle = 3.0, math.radians(SUN_ANGLE)
    sun = bpy.data.objects.new("Sun", light)
    sun.rotation_euler = Vector((-math.sin(math.radians(40)), 0.0, math.cos(math.radians(40)))).to_track_quat(
        'Z', 'Y').to_euler()
    bpy.context.scene.collection.objects.link(sun)
    scenes.add_camera((0.9, -3.6, 2.4), target=(0.6, 0.0, 0.3), lens=40.0)
    scenes.set_resolution(PIXX, PIXY)


def tumbler_pixels() -> np.ndarray:
    """(PIXY, PIXX) bool: the pixels whose view ray meets the tumbler's
    bounding cylinder, radius OUTER and height HEIGHT, 1 cm wider."""
    origin, dirs = scenes.pixel_rays(PIXX, PIXY)
    a = dirs[..., 0] ** 2 + dirs[..., 1] ** 2
    b = 2 * (origin[0] * dirs[..., 0] + origin[1] * dirs[..., 1])
    c = origin[0] ** 2 + origin[1] ** 2 - (OUTER + 0.01) ** 2
    root = np.sqrt(np.maximum(b * b - 4 * a * c, 0.0))
    seen = np.zeros((PIXY, PIXX), dtype=bool)
    for t in ((-b - root) / (2 * a), (-b + root) / (2 * a)):
        z = origin[2] + t * dirs[..., 2]
        seen |= (b * b - 4 * a * c >= 0) & (t > 0) & (z >= 0.0) & (z <= HEIGHT + 0.01)
    cap = (HEIGHT + 0.01 - origin[2]) / dirs[..., 2]
    at = origin[:2] + cap[..., None] * dirs[..., :2]
    return seen | ((cap > 0) & (np.hypot(at[..., 0], at[..., 1]) <= OUTER + 0.01))


def ours(water: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, float]:
    """(image, caustic pass, seconds) of the add-on's render at its defaults,
    a second render, with kernels and BVH warm."""
    tumbler_scene(water)
    return scenes.warm_caustic_render()


def cycles(water: tuple[float, float] | None, samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    """Cycles with the caustic's bounces (blender_scenes.cycles_caustics) on
    the scene of `water` (tumbler_scene): (image, seconds)."""
    tumbler_scene(water)
    return scenes.timed_cycles_caustics(folder, samples, seed, SPECULAR_BOUNCES)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=4096)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's coincident water beside the reference")
    args = parser.parse_args()
    conftest.registered_addon()
    renders = {name: ours(water) for name, water in MODELLINGS.items()}
    floor = ~tumbler_pixels()
    caustic_pass = renders["coincident with the glass"][1].sum(axis=-1) * floor
    caustic = caustic_pass >= 0.1 * caustic_pass.max()
    with tempfile.TemporaryDirectory() as folder:
        reference, reference_s = cycles(None, args.cycles_samples, 0, folder)
        second, _ = cycles(None, args.cycles_samples, 1, folder)
        swept = {f"{samples} samples": figures(*cycles(None, samples, 2, folder), reference, caustic)
                 for samples in CYCLES_SAMPLES}
        overlapping = cycles((INNER + 1e-3, BASE - 1e-3), args.cycles_samples, 2, folder)
    swept["the water overlapping the glass by 1 mm, IOR 1.33"] = figures(*overlapping, reference, caustic)
    results = {f"water {name}": figures(image, seconds, reference, caustic)
               for name, (image, _, seconds) in renders.items()}
    path = record.write("liquid_glass", {
        "scene": f"tumbler of water (IOR {GLASS} and {WATER}) on a white floor under a {SUN_ANGLE:g} degree sun, "
                 f"black world, {PIXX}x{PIXY}",
        "caustic_pixels": int(caustic.sum()),
        "cycles_reference": {"samples": args.cycles_samples, "seconds": reference_s,
                             **reference_noise(reference, second, caustic)},
        "ours": results, "cycles": swept})
    print(f"wrote {path}")
    for name, f in {**results, **{f"Cycles, {s}": f for s, f in swept.items()}}.items():
        print(f"{name}: mean x{f['mean_ratio']:.3f}, L2 {f['relative_l2']:.1%}, caustic mean "
              f"x{f['caustic_mean_ratio']:.3f}, caustic L2 {f['caustic_relative_l2']:.1%}, {f['seconds']:.2f} s")
    if args.side_by_side:
        write_pair(args.side_by_side, renders["coincident with the glass"][0], reference)


if __name__ == "__main__":
    main()
