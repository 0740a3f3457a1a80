"""Error against time on issue 4's ball-lens scene (benchmarks/ball_lens.py).

    .venv/bin/python benchmarks/accuracy.py [--max-lamp-rays 1e6]

For each density estimate of the engine, and photon counts from 1e4 up,
renders the 320x240 view and measures the relative L2 error of the caustic
against the exact reference, and the wall time of the whole render (the
fastest of REPEATS). Writes
benchmarks/results/accuracy.json and accuracy.png (log-log), and prints the
time each method needs to reach 10%, 5% and 2%.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

import ball_lens  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from speed import machine  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
# One eye ray per pixel: each looks the caustic up averaged over its pixel's
# footprint on the floor (the rectangle with the footprint's mean and
# variance), which is the pixel's box average to second order, as the
# reference holds it. More samples only antialias geometry edges, which the
# metric's region excludes.
SPP = 1
THRESHOLDS = (0.10, 0.05, 0.02)
# Each render's time is the fastest of this many (as timeit does): a shared
# machine's noise only ever adds time. Renders are deterministic.
REPEATS = 3


def engine_methods(max_lamp_rays: float) -> dict[str, tuple[dict, list[int]]]:
    """Name -> (RenderSettings fields, photon counts) of each density
    estimate compared. Beams need far fewer paths, so they sweep lower
    counts (of the grid before refinement), in eighth decades."""
    photons = [int(c) for c in 10 ** np.arange(4, np.log10(max_lamp_rays) + 0.01, 0.5)]
    beams = [int(c) for c in 10 ** np.arange(2.5, 5.01, 0.125)]
    methods = {"beam": (dict(density="beam"), beams),
               "beam, plain grid": (dict(density="beam", beam_refinement=0), beams)}
    methods.update({f"adaptive k={k}": (dict(density="adaptive", k_nearest=k), photons) for k in (16, 64, 256)})
    methods.update({f"splat {mm:g} mm": (dict(density="splat", map_scale=mm), photons) for mm in (5.0, 10.0, 40.0)})
    return methods


def run_engine(name: str, fields: dict, lamp_ray_counts: list[int], truth) -> list[dict]:
    the_scene = ball_lens.scene()
    points = []
    for photons in lamp_ray_counts:
        settings = RenderSettings(lamp_rays=photons, spp=SPP, **fields)
        runs = []
        for _ in range(REPEATS):
            start = time.perf_counter()
            result = render(the_scene, settings)
            runs.append((time.perf_counter() - start, result))
        seconds, result = min(runs, key=lambda run: run[0])
        error = truth.error(result.passes["caustic"])
        points.append(dict(lamp_rays=photons, paths=result.stats["lamp_rays"], seconds=seconds, error=error,
                           stages={k: round(v, 3) for k, v in result.stats["seconds"].items()}))
        print(f"{name:18s} {photons:>11,d} photons {seconds:7.2f} s  error {100 * error:6.2f}%", flush=True)
    return points


def time_to_reach(points: list[dict], threshold: float):
    """Seconds of the fastest run at or below `threshold`, or None."""
    times = [p["seconds"] for p in points if p["error"] <= threshold]
    return min(times) if times else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max-lamp-rays", type=float, default=1e6)
    args = parser.parse_args()

    truth = ball_lens.pixel_reference(ball_lens.scene())
    curves = {name: run_engine(name, fields, counts, truth)
              for name, (fields, counts) in engine_methods(args.max_lamp_rays).items()}

    table = {name: {f"{int(100 * t)}%": time_to_reach(points, t) for t in THRESHOLDS} for name, points in curves.items()}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "accuracy.json").write_text(json.dumps(
        dict(date=date.today().isoformat(), machine=machine(), spp=SPP, curves=curves, time_to_reach=table),
        indent=2) + "\n")
    from plot_accuracy import main as plot_all
    plot_all()
    print("\ntime to reach   " + "  ".join(f"{int(100 * t):>6d}%" for t in THRESHOLDS))
    for name, row in table.items():
        print(f"{name:18s}" + "  ".join(f"{v:6.2f}s" if v is not None else "     -" for v in row.values()))


if __name__ == "__main__":
    main()
