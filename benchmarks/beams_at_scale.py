"""Beams from 10k to 10M lamp rays (and one render of 50M): time, error and
peak memory, on the ball lens against its exact reference and on sunlight
through a wavy water slab against a converged render.

    .venv/bin/python benchmarks/beams_at_scale.py [--counts 1e4 3e4 ...] [--big 5e7] [--threads 2]

Each render runs in a fresh process (peak RSS is the process's high-water
mark, VmHWM), with the default settings but 1 sample per
pixel, and then reads every receiver's map as a bake does
(`IlluminationMap.irradiance()`), so the figure covers render and bake.
The wall time is the whole render's; the CPU time (all threads) is given
too, since on a shared machine only it stays comparable.

Errors are relative L2 over the caustic's pixels:
- ball lens (benchmarks/scenes/ball_lens.py): against the exact pixel
  reference;
- wavy slab (benchmarks/scenes/wavy_slab.py's pool: the gallery's rippled
  water, 240x180): against this engine's own converged render,
  `--reference` lamp rays refined twice: a self-convergence figure, not an
  independent one (mitsuba_folds.py has Mitsuba's particle tracer there).

Writes benchmarks/results/beams_at_scale.json.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from benchmarks.references.metrics import region_relative_l2 as relative_l2  # noqa: E402
from benchmarks.scenes import ball_lens, wavy_slab  # noqa: E402
from caustic_addon import RenderSettings, Scene, render  # noqa: E402

RESULTS = record.RESULTS
COUNTS = (1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 1e7)


def scene_of(name: str) -> Scene:
    return ball_lens.scene() if name == "ball_lens" else wavy_slab.pool()


def peak_rss_mb() -> float:
    """This process's peak resident set, MB: VmHWM, which starts afresh at
    exec (ru_maxrss keeps the forking parent's high-water mark on Linux)."""
    status = Path("/proc/self/status")
    if status.exists():
        for line in status.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def child(name: str, lamp_rays: int, refinement: int, threads: int, out: str) -> None:
    """One render and bake in this process; its figures and caustic pass."""
    settings = RenderSettings(lamp_rays=lamp_rays, spp=1, beam_refinement=refinement, threads=threads)
    scene = scene_of(name)
    wall, cpu = time.perf_counter(), time.process_time()
    result = render(scene, settings)
    for imap in result.maps.values():
        imap.irradiance()
    figures = dict(scene=name, lamp_rays=lamp_rays, refinement=refinement, paths=result.stats["lamp_rays"],
                   seconds=time.perf_counter() - wall, cpu_seconds=time.process_time() - cpu,
                   stages={k: round(v, 3) for k, v in result.stats["seconds"].items()}, peak_rss_mb=peak_rss_mb())
    np.save(out, result.passes["caustic"][..., 0])
    print(json.dumps(figures))


def run(name: str, lamp_rays: float, refinement: int, threads: int) -> tuple[dict, np.ndarray]:
    out = RESULTS / f"_caustic_{name}.npy"
    done = subprocess.run([sys.executable, __file__, "--child", name, str(int(lamp_rays)), str(refinement),
                           str(threads), str(out)], check=True, capture_output=True, text=True)
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    caustic = np.load(out)
    out.unlink()
    return figures, caustic


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--counts", type=float, nargs="+", default=COUNTS)
    parser.add_argument("--scenes", nargs="+", default=["ball_lens", "wavy_slab"])
    parser.add_argument("--refinement", type=int, nargs="+", default=[1])
    parser.add_argument("--reference", type=float, default=1e7)
    parser.add_argument("--big", type=float, default=0.0, help="also one render of this many lamp rays")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--child", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        name, lamp_rays, refinement, threads, out = args.child
        child(name, int(lamp_rays), int(refinement), int(threads), out)
        return

    RESULTS.mkdir(exist_ok=True)
    report = record.read("beams_at_scale")
    for name in args.scenes:
        if name == "ball_lens":
            truth = ball_lens.pixel_reference(ball_lens.scene())
            region, exact = truth.region, truth.irradiance / math.pi
        else:
            cached = RESULTS / f"_reference_{name}_{int(args.reference)}.npy"
            if not cached.exists():
                figures, exact = run(name, args.reference, 2, args.threads)
                report.setdefault("references", {})[name] = figures
                np.save(cached, exact)
            exact = np.load(cached)
            region = exact > 0.02 * exact.max()
        rows = report.setdefault("curves", {}).setdefault(name, [])
        for refinement in args.refinement:
            for count in list(args.counts) + ([args.big] if args.big else []):
                figures, caustic = run(name, count, refinement, args.threads)
                figures["error"] = relative_l2(caustic.astype(np.float64), exact, region)
                rows[:] = [r for r in rows if (r["lamp_rays"], r["refinement"]) != (int(count), refinement)]
                rows.append(figures)
                rows.sort(key=lambda r: (r["refinement"], r["lamp_rays"]))
                record.write("beams_at_scale", report)
                print(f"{name:10s} refinement {refinement} {int(count):>11,d} lamp rays {figures['seconds']:8.1f} s "
                      f"(CPU {figures['cpu_seconds']:7.1f} s)  error {100 * figures['error']:6.2f}%  "
                      f"peak {figures['peak_rss_mb']:6.0f} MB", flush=True)


if __name__ == "__main__":
    main()
