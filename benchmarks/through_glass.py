"""The caustic seen through glass: the ball lens's focus and fold ring,
magnified by the ball, at 1 and 4 samples per pixel with the default Edge
Samples, against a 256-sample render, over the pixels whose centre ray
meets the ball first.

The edge pass's eye rays carry ray differentials through the glass
(passes/differentials.py), so the caustic there is the mean over each ray's
footprint.

    .venv/bin/python benchmarks/through_glass.py [--repeats 3]

Writes benchmarks/results/through_glass.json and through_glass.png (the
caustic pass, 1 sample, 4 samples, 256 samples, under the ball's top) and
prints its figures. Time is the whole render's wall time, the
fastest of `repeats` runs.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from benchmarks.scenes import ball_lens  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.passes.camera_rays import eye_rays  # noqa: E402
from caustic_addon.tracing.accelerator import Accelerator  # noqa: E402

RESULTS = record.RESULTS
LAMP_RAYS = 100_000
REFERENCE_SPP = 256


def through_the_ball(scene) -> np.ndarray:
    """(h,w) bool: the pixels whose centre ray meets the ball first."""
    cam = scene.camera
    pixels = np.arange(cam.pixx * cam.pixy)
    origins, dirs = eye_rays(cam, pixels, np.full((len(pixels), 2), 0.5))
    accel = Accelerator(scene.objects, scene.extent(), threads=1)
    glass = [o.name for o in scene.objects].index("Glass")
    return (accel.intersect(origins, dirs).obj == glass).reshape(cam.pixy, cam.pixx)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    scene = ball_lens.scene()
    mask = through_the_ball(scene)
    reference = render(scene, RenderSettings(lamp_rays=LAMP_RAYS, spp=REFERENCE_SPP)).passes["caustic"]
    rows, images = [], [reference]
    for spp in (1, 4):
        best, result = np.inf, None
        for _ in range(args.repeats):
            clock = time.perf_counter()
            result = render(scene, RenderSettings(lamp_rays=LAMP_RAYS, spp=spp))
            best = min(best, time.perf_counter() - clock)
        caustic = result.passes["caustic"]
        error = float(np.linalg.norm((caustic - reference)[mask]) / np.linalg.norm(reference[mask]))
        rows.append(dict(spp=spp, error=error, seconds=best, eye_seconds=result.stats["seconds"]["eye"]))
        images.insert(-1, caustic)
        print(f"{spp} samples: {100 * error:.2f}% from {REFERENCE_SPP} samples over {int(mask.sum())} pixels "
              f"seen through the ball, {best:.2f} s", flush=True)
    record.write("through_glass", dict(lamp_rays=LAMP_RAYS, reference_spp=REFERENCE_SPP, pixels=int(mask.sum()),
                                       rows=rows))
    strip = np.concatenate([image[:110, 60:260, 0] for image in images], axis=1)
    strip = np.clip(strip / np.percentile(images[-1][:110, 60:260, 0], 99.5), 0.0, 1.0) ** (1 / 2.2)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.imsave(RESULTS / "through_glass.png", np.repeat(np.repeat(strip, 2, axis=0), 2, axis=1), cmap="gray",
               vmin=0.0, vmax=1.0)

if __name__ == "__main__":
    main()
