"""What the world's light through the casters costs, and what it is worth
(passes/world_paths.py): the gallery's scenes that have a world, rendered
at 240x180 with the default settings three ways, each against a render
with 64 World Samples whose every blocked direction is followed.

- `followed`: the default: blocked directions go on through the casters,
  with Russian roulette where the sky could bring under ROULETTE_SHARE of
  a point's other light;
- `every`: every blocked direction goes on (no roulette);
- `stopped`: blocked directions stop there, as shadow rays do: the world's
  light through glass is left out (the cost without it).

    .venv/bin/python benchmarks/world_paths.py

Writes benchmarks/results/world_paths.json: wall seconds (the best of 2),
eye rays and the relative L2 error of each.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

import numpy as np  # noqa: E402

from benchmarks import gallery, record  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.passes import world_paths  # noqa: E402

SCENES = ("ball_lens", "wavy_water", "softbox", "sunny_sky")
WAYS = {"followed": (world_paths.ROULETTE_SHARE, world_paths.MIN_CHANCE), "every": (0.0, 1.0), "stopped": None}


def rendered(scene, way, **settings) -> tuple[np.ndarray, float, int]:
    """(image (h,w,3), seconds, eye rays) of `scene` with the world's
    paths through the casters as `way` has them."""
    original = world_paths.WorldThroughCasters.light
    if way is None:
        def stop(self, origins, dirs, medium, surface, draws):
            n = len(dirs)
            return np.zeros(n, dtype=bool), np.zeros(n, dtype=bool), np.zeros((n, 3))
        world_paths.WorldThroughCasters.light = stop
    else:
        world_paths.ROULETTE_SHARE, world_paths.MIN_CHANCE = way
    try:
        best = None
        for _ in range(2):
            clock = time.perf_counter()
            result = render(scene, RenderSettings(**settings))
            seconds = time.perf_counter() - clock
            best = seconds if best is None else min(best, seconds)
    finally:
        world_paths.WorldThroughCasters.light = original
        world_paths.ROULETTE_SHARE, world_paths.MIN_CHANCE = WAYS["followed"]
    return result.image[..., :3], best, int(result.stats["rays_eye_pass"])


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    rows = {}
    for name in SCENES:
        scene = getattr(gallery, name)()
        scene.camera.pixx, scene.camera.pixy = 240, 180
        render(scene, RenderSettings(lamp_rays=1000))
        reference, _, _ = rendered(scene, WAYS["every"], world_samples=64)
        rows[name] = {}
        for way, setting in WAYS.items():
            image, seconds, rays = rendered(scene, setting)
            error = float(np.sqrt(((image - reference) ** 2).mean() / (reference ** 2).mean()))
            rows[name][way] = dict(seconds=round(seconds, 3), eye_rays=rays, relative_l2=round(error, 5))
            print(f"{name:12s} {way:9s} {seconds:6.2f} s  {rays / 1e6:6.2f} M eye rays  {100 * error:6.2f}%")
    record.write("world_paths", dict(resolution=[240, 180], reference_world_samples=64, scenes=rows), indent=1)


if __name__ == "__main__":
    main()
