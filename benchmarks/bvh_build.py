"""Building the BVH: embreex's upload against Embree's shared buffers, and
what each build quality costs to build and saves in casting.

    .venv/bin/python benchmarks/bvh_build.py [--repeats 3]

For each scene, the seconds to put its meshes into Embree and commit the
BVH: through embreex (every coordinate copied through its Cython loop),
and directly from the engine's own arrays (tracing/embree.py: shared
buffers) at Embree's three build qualities, LOW (Live updates), MEDIUM
(embreex's) and HIGH. Beside each quality, the seconds Embree takes to
cast every ray of one render of the scene (recorded from the render and
replayed on 2 threads, casts.py), so that build plus casts shows which
quality a frame wants. The scenes: the 320x240 ball lens (65,024
triangles), the gallery's wavy water at 480x360, and 500 glass balls at
4,000 lamp rays (many small meshes).

Writes benchmarks/results/bvh_build.json.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from embreex import rtcore_scene  # noqa: E402
from embreex.mesh_construction import TriangleMesh  # noqa: E402

from benchmarks import casts, gallery, record  # noqa: E402
from benchmarks.scenes import ball_lens  # noqa: E402
from caustic_addon import (Camera, Dielectric, Diffuse, Object, PointLight, RenderSettings, Scene,  # noqa: E402
                           compile_kernels, render, shapes)
from caustic_addon.tracing import embree  # noqa: E402

QUALITIES = ("low", "medium", "high")


def many_balls(count: int) -> Scene:
    """`count` glass balls (0.1 m, 32 x 16) in a square grid over a floor, a point lamp above, 320x240."""
    side = int(np.ceil(np.sqrt(count)))
    centres = [((i % side - side / 2) * 0.3, (i // side - side / 2) * 0.3, 0.3) for i in range(count)]
    balls = [Object(f"Ball {i}", shapes.uv_sphere(0.1, c, 32, 16), Dielectric(1.5)) for i, c in enumerate(centres)]
    half = 0.3 * side
    return Scene(objects=[Object("Floor", shapes.plane(2.0 * half + 1.0), Diffuse(0.8)), *balls],
                 lights=[PointLight((0.0, 0.0, 3.0 * half), 1000.0 * half ** 2)],
                 camera=Camera.look_at((0.0, -2.0 * half, 2.0 * half), (0.0, 0.0, 0.0), pixx=320, pixy=240))


def through_embreex(meshes) -> None:
    scene = rtcore_scene.EmbreeScene()
    for mesh in meshes:
        TriangleMesh(scene, mesh.vertices.astype(np.float32), mesh.triangles.astype(np.int32))
    scene.run(np.zeros((1, 3), dtype=np.float32), np.ones((1, 3), dtype=np.float32))  # commits


def directly(meshes, quality: str) -> None:
    embree.Scene([embree.Geometry(m.vertices, m.triangles) for m in meshes], quality)


def measure(scene, settings: RenderSettings, repeats: int) -> dict:
    meshes = [o.mesh for o in scene.objects]
    batches: list = []
    with casts.recording(batches):
        render(scene, settings)
    figures = {"triangles": sum(len(m.triangles) for m in meshes), "objects": len(meshes),
               "rays": sum(len(b) for b in batches),
               "embreex_build_s": record.fastest(repeats, lambda: through_embreex(meshes))}
    for quality in QUALITIES:
        replay = casts.Replay(scene.objects, batches, quality=quality)
        try:
            figures[quality] = {"build_s": record.fastest(repeats, lambda: directly(meshes, quality)),
                                "casts_s": replay.seconds("direct1", repeats=repeats)}
        finally:
            replay.close()
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    compile_kernels()
    scenes = {"ball lens 320x240": (ball_lens.scene(), RenderSettings()),
              "wavy water 480x360": (gallery.wavy_water(), RenderSettings()),
              "500 glass balls": (many_balls(500), RenderSettings(lamp_rays=4000))}
    results = {name: measure(scene, settings, args.repeats) for name, (scene, settings) in scenes.items()}
    record.write("bvh_build", {"qualities": list(QUALITIES), "scenes": results})
    for name, r in results.items():
        print(f"{name}: {r['triangles']:,} triangles in {r['objects']} objects, {r['rays']:,} rays; "
              f"embreex builds in {1e3 * r['embreex_build_s']:.1f} ms")
        for quality in QUALITIES:
            q = r[quality]
            print(f"  {quality:7s} build {1e3 * q['build_s']:7.1f} ms, casts {q['casts_s']:.3f} s, "
                  f"sum {q['build_s'] + q['casts_s']:.3f} s")


if __name__ == "__main__":
    main()
