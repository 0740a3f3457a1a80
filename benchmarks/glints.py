"""Glints: an area lamp seen in a smooth glass ball, by reflection and
through the glass, by the add-on and by Cycles.

    .venv/bin/python benchmarks/glints.py [--cycles-samples 4096]

The scene is tests/addon/blender_scenes.glass_ball_under_a_softbox at
160x120: a glass ball (radius 0.5) in a black world under a 0.5 m square
lamp of 200 W, so that every lit pixel sees the ball. Cycles renders it
with 8 glossy and transmission bounces, no diffuse bounce, neither
clamped nor blurred (Filter Glossy 0), box filter, no denoising; its
render of --cycles-samples is the reference, and a second one of another
seed gives its own noise.

Recorded: the add-on's render at 4 (its default), 16 and 64 samples, and
with the lamp hidden from glossy and transmission rays (the render before
glints; in this black world the ball is then black): the image's mean
against the reference's, its relative L2 error over the image, and its
time (the maps kept from the first render: the eye pass and its images);
Cycles at 64 to 1,024 samples, the same.
Writes benchmarks/results/glints.json.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks import record  # noqa: E402

PIXX, PIXY = 160, 120
OURS = {"4 samples (default)": 4, "16 samples": 16, "64 samples": 64}
CYCLES_SAMPLES = [64, 256, 1024]


def ours(spp: int) -> tuple[np.ndarray, float]:
    settings = bpy.context.scene.caustic
    settings.spp, settings.edge_samples = spp, max(8, spp)
    clock = time.perf_counter()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64), time.perf_counter() - clock


def cycles(samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    settings = bpy.context.scene.cycles
    settings.sample_clamp_indirect, settings.blur_glossy, settings.seed = 0.0, 0.0, seed
    clock = time.perf_counter()
    image = scenes.cycles_render(folder, samples=samples, specular_bounces=8)[..., :3]
    return image, time.perf_counter() - clock


def figures(image: np.ndarray, seconds: float, reference: np.ndarray) -> dict:
    return {"seconds": seconds, "mean_ratio": float(image.mean() / reference.mean()),
            "relative_l2": float(np.linalg.norm(image - reference) / np.linalg.norm(reference))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=4096)
    args = parser.parse_args()
    addon = conftest.registered_addon()
    lamp = scenes.glass_ball_under_a_softbox(PIXX, PIXY)
    ours(4)  # the first render builds what later ones keep
    with tempfile.TemporaryDirectory() as folder:
        reference, reference_s = cycles(args.cycles_samples, 0, folder)
        second, _ = cycles(args.cycles_samples, 1, folder)
        results = {name: figures(*ours(spp), reference) for name, spp in OURS.items()}
        lamp.visible_glossy = lamp.visible_transmission = False
        results["4 samples, no glints (the lamp hidden from glossy and transmission rays)"] = figures(
            *ours(4), reference)
        lamp.visible_glossy = lamp.visible_transmission = True
        swept = {samples: figures(*cycles(samples, 2, folder), reference) for samples in CYCLES_SAMPLES}
    noise = float(np.linalg.norm(reference - second) / np.linalg.norm(reference) / np.sqrt(2.0))
    path = record.write("glints", {
        "scene": f"glass ball (radius 0.5) under a 0.5 m square lamp of 200 W, black world, {PIXX}x{PIXY}",
        "cycles_reference": {"samples": args.cycles_samples, "seconds": reference_s, "relative_l2_noise": noise},
        "ours": results, "cycles": {str(s): f for s, f in swept.items()}})
    print(f"wrote {path}")
    for name, f in {**results, **{f"Cycles {s}": f for s, f in swept.items()}}.items():
        print(f"{name}: mean x{f['mean_ratio']:.3f}, L2 {f['relative_l2']:.1%}, {f['seconds']:.2f} s")


if __name__ == "__main__":
    main()
