"""A glossy floor under a large lamp: its highlight taken by the lamp's
samples and the lobe's rays, weighed by multiple importance sampling, by
the add-on and by Cycles at equal samples.

    .venv/bin/python benchmarks/glossy_floor.py [--cycles-samples 4096]

The scene is tests/addon/blender_scenes.glossy_floor_under_a_softbox at
160x120: a dark Principled floor (base 0.1, Specular IOR Level 0.5) in a
black world under a 1 m square lamp of 200 W, at roughness 0.05, 0.2 and
0.5. Cycles renders it with no bounces (direct light only), box filter,
no denoising; its render of --cycles-samples is the reference, and a
second one of another seed gives its own noise.

Recorded per roughness, at 4, 16 and 64 samples a pixel: the add-on with
one Light Sample to each (an eye ray, a light sample and a ray drawn from
the lobe a sample) and Cycles (an eye ray, a light sample and a BSDF ray
a sample): the image's mean against the reference's, its relative L2
error over the image, and its time.
Writes benchmarks/results/glossy_floor.json.
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
ROUGHNESS = [0.05, 0.2, 0.5]
SAMPLES = [4, 16, 64]


def ours(samples: int) -> tuple[np.ndarray, float]:
    settings = bpy.context.scene.caustic
    settings.spp, settings.edge_samples, settings.lamp_samples = samples, max(8, samples), 1
    clock = time.perf_counter()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64), time.perf_counter() - clock


def cycles(samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    bpy.context.scene.cycles.seed = seed
    clock = time.perf_counter()
    image = scenes.cycles_render(folder, samples=samples)[..., :3]
    return image, time.perf_counter() - clock


def figures(image: np.ndarray, seconds: float, reference: np.ndarray) -> dict:
    return {"seconds": seconds, "mean_ratio": float(image.mean() / reference.mean()),
            "relative_l2": float(np.linalg.norm(image - reference) / np.linalg.norm(reference))}


def one_floor(roughness: float, cycles_samples: int, folder: str) -> dict:
    scenes.glossy_floor_under_a_softbox(PIXX, PIXY, roughness)
    bpy.context.scene.caustic.lamp_rays = 1000
    ours(1)  # the first render builds what later ones keep
    reference, reference_s = cycles(cycles_samples, 0, folder)
    second, _ = cycles(cycles_samples, 1, folder)
    noise = float(np.linalg.norm(reference - second) / np.linalg.norm(reference) / np.sqrt(2.0))
    return {"cycles_reference": {"samples": cycles_samples, "seconds": reference_s, "relative_l2_noise": noise},
            "ours": {str(k): figures(*ours(k), reference) for k in SAMPLES},
            "cycles": {str(k): figures(*cycles(k, 2, folder), reference) for k in SAMPLES}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=4096)
    args = parser.parse_args()
    conftest.registered_addon()
    with tempfile.TemporaryDirectory() as folder:
        floors = {str(r): one_floor(r, args.cycles_samples, folder) for r in ROUGHNESS}
    path = record.write("glossy_floor", {
        "scene": f"dark Principled floor under a 1 m square lamp of 200 W, black world, {PIXX}x{PIXY}",
        "roughness": floors})
    print(f"wrote {path}")
    for r, floor in floors.items():
        for who in ("ours", "cycles"):
            for samples, f in floor[who].items():
                print(f"roughness {r}, {who} {samples} samples: mean x{f['mean_ratio']:.3f}, "
                      f"L2 {f['relative_l2']:.1%}, {f['seconds']:.2f} s")


if __name__ == "__main__":
    main()
