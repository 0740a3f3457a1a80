"""Glass shaded smooth across its hard edges, as Shade Smooth leaves a
lathed tumbler without Smooth by Angle, by the add-on and by Cycles.

    .venv/bin/python benchmarks/smooth_edges.py [--cycles-samples 1024] [--side-by-side pair.png]

The empty tumbler of benchmarks/liquid_glass.py (its floor, sun and camera),
with its edges sharp and with every edge smooth, whose normals then lean
up to 45 degrees off the faces. Both renderers take direct light only
(Cycles: no diffuse bounce, 24 glossy and transmission bounces, box filter,
no denoising, at --cycles-samples; the add-on's image less its caustic
pass, at its defaults), which Cycles converges on: what the glass shows of
the floor and the sky is its reflections and refractions alone.

Recorded per shading: the mean over the pixels that see the tumbler
(liquid_glass.tumbler_pixels) against Cycles', the relative L2 error there,
and the add-on's time. Writes benchmarks/results/smooth_edges.json.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
import liquid_glass  # noqa: E402
from benchmarks import record  # noqa: E402
from benchmarks.against_cycles import relative_l2, write_pair  # noqa: E402

SHADINGS = {"edges sharp (Smooth by Angle, 30 degrees)": True, "every edge smooth (Shade Smooth)": False}


def one_shading(sharp_edges: bool, samples: int, folder: str) -> tuple[dict, np.ndarray, np.ndarray]:
    liquid_glass.tumbler_scene((liquid_glass.INNER, liquid_glass.BASE), empty=True, sharp_edges=sharp_edges)
    image, caustic, seconds = scenes.warm_caustic_render()
    ours = image - caustic
    reference, cycles_seconds = scenes.timed_cycles_caustics(folder, samples, 0, liquid_glass.SPECULAR_BOUNCES,
                                                             diffuse_bounces=0)
    glass = liquid_glass.tumbler_pixels()
    return ({"seconds": seconds, "cycles_seconds": cycles_seconds,
             "glass_mean_ratio": float(ours[glass].mean() / reference[glass].mean()),
             "glass_relative_l2": relative_l2(ours[glass], reference[glass]), "glass_pixels": int(glass.sum())},
            ours, reference)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=1024)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's smooth tumbler beside Cycles'")
    args = parser.parse_args()
    conftest.registered_addon()
    with tempfile.TemporaryDirectory() as folder:
        runs = {name: one_shading(sharp, args.cycles_samples, folder) for name, sharp in SHADINGS.items()}
    path = record.write("smooth_edges", {
        "scene": f"empty glass tumbler (IOR {liquid_glass.GLASS}) on a white floor under a "
                 f"{liquid_glass.SUN_ANGLE:g} degree sun, black world, {liquid_glass.PIXX}x{liquid_glass.PIXY}",
        "cycles_samples": args.cycles_samples, "shadings": {name: run[0] for name, run in runs.items()}})
    print(f"wrote {path}")
    for name, (f, _, _) in runs.items():
        print(f"{name}: glass mean x{f['glass_mean_ratio']:.3f}, L2 {f['glass_relative_l2']:.1%}, "
              f"{f['seconds']:.2f} s")
    if args.side_by_side:
        _, ours, reference = runs["every edge smooth (Shade Smooth)"]
        write_pair(args.side_by_side, ours, reference)


if __name__ == "__main__":
    main()
