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
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks.against_cycles import record_against_cycles  # noqa: E402

PIXX, PIXY = 160, 120
OURS = {"defaults (4 samples)": 4, "16 samples": 16}
CYCLES_SAMPLES = [256, 1024]


def ours(spp: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(image, caustic pass, seconds) of the add-on's render at `spp`."""
    settings = bpy.context.scene.caustic
    settings.spp, settings.edge_samples = spp, max(8, spp)
    return scenes.warm_caustic_render()


def cycles(samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    """Cycles with the caustic's bounces (blender_scenes.cycles_caustics): (image, seconds)."""
    return scenes.timed_cycles_caustics(folder, samples, seed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=4096)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's render at its defaults beside the reference")
    args = parser.parse_args()
    conftest.registered_addon()
    scenes.glass_ball_under_an_emitting_plane(PIXX, PIXY)
    renders = {name: ours(spp) for name, spp in OURS.items()}
    record_against_cycles(
        "emitters", f"glass ball (radius 0.5) on a white floor under a 1 m emitting plane of strength 12, "
                    f"black world, {PIXX}x{PIXY}",
        renders, "defaults (4 samples)", cycles, args.cycles_samples, CYCLES_SAMPLES, args.side_by_side)


if __name__ == "__main__":
    main()
