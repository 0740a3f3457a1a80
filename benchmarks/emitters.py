"""A softbox built as an emitting mesh: an Emission shader on a plane over
a glass ball, by the add-on and by Cycles.

    .venv/bin/python benchmarks/emitters.py [--cycles-samples 4096] [--side-by-side pair.png]

The scene is tests/addon/blender_scenes.glass_ball_under_an_emitting_plane
at 160x120: a glass ball on a white floor in a black world under a 1 m
plane of Emission strength 12 facing it. The plane lights the floor, casts
the ball's soft caustic onto it and shows in the glass. Cycles renders it
with one diffuse bounce (the floor's light through the glass: its caustic),
8 glossy and transmission bounces, refractive and reflective caustics on,
no clamp, Filter Glossy 0, box filter, no denoising; its render of
--cycles-samples is the reference, and a second one of another seed gives
its own noise.

Recorded: the add-on at its defaults (Beam, 40,000 light rays, 4 samples)
and at 16 samples, and Cycles at 256 and 1,024 samples: the image's mean
against the reference's, the relative L2 error over the image and over
the caustic (the floor's pixels where the add-on's caustic pass holds at
least a tenth of its brightest), and the time (the add-on's second render
of a setting, its kernels and BVH warm).
Writes benchmarks/results/emitters.json.
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
from caustic_addon.cli.image_io import write_image  # noqa: E402

PIXX, PIXY = 160, 120
OURS = {"defaults (4 samples)": 4, "16 samples": 16}
CYCLES_SAMPLES = [256, 1024]


def ours(spp: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(image, caustic pass, seconds) of the add-on's render at `spp`."""
    settings = bpy.context.scene.caustic
    settings.spp, settings.edge_samples = spp, max(8, spp)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    clock = time.perf_counter()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    seconds = time.perf_counter() - clock
    return (scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64),
            scenes.pixels_of("Caustic Render Caustic")[..., :3].astype(np.float64), seconds)


def cycles(samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    """Cycles on the CPU with the caustic's bounces (above), box-filtered,
    neither denoised nor adaptive: (image, seconds)."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    settings = scene.cycles
    settings.device, settings.samples, settings.seed, settings.use_denoising = 'CPU', samples, seed, False
    settings.max_bounces, settings.diffuse_bounces = 9, 1
    settings.glossy_bounces = settings.transmission_bounces = 8
    settings.caustics_refractive = settings.caustics_reflective = True
    settings.sample_clamp_indirect, settings.blur_glossy = 0.0, 0.0
    settings.pixel_filter_type, settings.filter_width = 'BOX', 1.0
    settings.use_adaptive_sampling = False
    clock = time.perf_counter()
    image = scenes.rendered_pixels(folder)[..., :3]
    return image, time.perf_counter() - clock


def figures(image: np.ndarray, seconds: float, reference: np.ndarray, caustic: np.ndarray) -> dict:
    return {"seconds": seconds, "mean_ratio": float(image.mean() / reference.mean()),
            "relative_l2": float(np.linalg.norm(image - reference) / np.linalg.norm(reference)),
            "caustic_relative_l2": float(np.linalg.norm((image - reference)[caustic])
                                         / np.linalg.norm(reference[caustic]))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=4096)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's render at its defaults beside the reference")
    args = parser.parse_args()
    conftest.registered_addon()
    scenes.glass_ball_under_an_emitting_plane(PIXX, PIXY)
    renders = {name: ours(spp) for name, spp in OURS.items()}
    caustic_pass = renders["defaults (4 samples)"][1].sum(axis=-1)
    caustic = caustic_pass >= 0.1 * caustic_pass.max()
    with tempfile.TemporaryDirectory() as folder:
        reference, reference_s = cycles(args.cycles_samples, 0, folder)
        second, _ = cycles(args.cycles_samples, 1, folder)
        swept = {samples: figures(*cycles(samples, 2, folder), reference, caustic) for samples in CYCLES_SAMPLES}
    results = {name: figures(image, seconds, reference, caustic) for name, (image, _, seconds) in renders.items()}
    noise = float(np.linalg.norm(reference - second) / np.linalg.norm(reference) / np.sqrt(2.0))
    caustic_noise = float(np.linalg.norm((reference - second)[caustic]) / np.linalg.norm(reference[caustic])
                          / np.sqrt(2.0))
    path = record.write("emitters", {
        "scene": f"glass ball (radius 0.5) on a white floor under a 1 m emitting plane of strength 12, black world, "
                 f"{PIXX}x{PIXY}",
        "caustic_pixels": int(caustic.sum()),
        "cycles_reference": {"samples": args.cycles_samples, "seconds": reference_s, "relative_l2_noise": noise,
                             "caustic_relative_l2_noise": caustic_noise},
        "ours": results, "cycles": {str(s): f for s, f in swept.items()}})
    print(f"wrote {path}")
    for name, f in {**results, **{f"Cycles {s}": f for s, f in swept.items()}}.items():
        print(f"{name}: mean x{f['mean_ratio']:.3f}, L2 {f['relative_l2']:.1%}, "
              f"caustic L2 {f['caustic_relative_l2']:.1%}, {f['seconds']:.2f} s")
    if args.side_by_side:
        pair = np.concatenate([renders["defaults (4 samples)"][0], reference], axis=1)
        write_image(args.side_by_side, np.concatenate([pair, np.ones(pair.shape[:2] + (1,))], axis=2))


if __name__ == "__main__":
    main()
