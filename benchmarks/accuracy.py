"""The engine's error against time on the ball-lens scene
(benchmarks/scenes/ball_lens.py), each density estimate against the exact
pixel reference.

    .venv/bin/python benchmarks/accuracy.py [--max-lamp-rays 1e6]
    .venv/bin/python benchmarks/accuracy.py --plot   # only redraw accuracy.png

For each density estimate of the engine, and photon counts from 1e4 up,
renders the 320x240 view and measures the relative L2 error of the caustic
against the exact reference, and the wall time of the whole render (the
fastest of REPEATS). Writes benchmarks/results/accuracy.json and
accuracy.png: relative L2 error (%) against wall time (s), log-log, with
the 10%, 5% and 2% levels, beside Cycles' curves from cycles_accuracy.json
if measured; and prints the time each method needs to reach 10%, 5% and 2%.
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


def load_curves() -> dict[str, tuple[list[dict], str]]:
    """Name -> (points, matplotlib line style) of every curve measured: the
    engine's solid (accuracy.json), Cycles' dashed (cycles_accuracy.json)."""
    curves = {name: (points, "o-") for name, points in record.read("accuracy").get("curves", {}).items()}
    curves.update({name: (points, "s--") for name, points in record.read("cycles_accuracy").get("curves", {}).items()})
    return curves


def plot(curves: dict[str, tuple[list[dict], str]], path: Path) -> None:
    """Error (%) against seconds of every curve, log-log, saved to `path` (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for name, (points, style) in curves.items():
        ax.loglog([p["seconds"] for p in points], [100 * p["error"] for p in points], style, label=name)
    for threshold in THRESHOLDS:
        ax.axhline(100 * threshold, color="grey", lw=0.6, ls=":")
        ax.annotate(f"{100 * threshold:g}%", (1, 100 * threshold), xycoords=("axes fraction", "data"),
                    xytext=(3, 0), textcoords="offset points", va="center", fontsize=8, color="grey")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relative L2 error of the caustic (%)")
    ax.set_title("Ball lens, 320x240: error against time")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max-lamp-rays", type=float, default=1e6)
    parser.add_argument("--plot", action="store_true", help="only redraw accuracy.png from the results")
    args = parser.parse_args()
    if args.plot:
        plot(load_curves(), record.RESULTS / "accuracy.png")
        return

    truth = ball_lens.pixel_reference(ball_lens.scene())
    curves = {name: run_engine(name, fields, counts, truth)
              for name, (fields, counts) in engine_methods(args.max_lamp_rays).items()}

    table = {name: {f"{int(100 * t)}%": time_to_reach(points, t) for t in THRESHOLDS} for name, points in curves.items()}
    record.write("accuracy", dict(spp=SPP, curves=curves, time_to_reach=table))
    plot(load_curves(), record.RESULTS / "accuracy.png")
    print("\ntime to reach   " + "  ".join(f"{int(100 * t):>6d}%" for t in THRESHOLDS))
    for name, row in table.items():
        print(f"{name:18s}" + "  ".join(f"{v:6.2f}s" if v is not None else "     -" for v in row.values()))


if __name__ == "__main__":
    main()
