"""Where the time of issue 4's ball-lens render goes: the part embreex and
Embree fix, and the part that is ours.

    .venv/bin/python benchmarks/budget.py [--repeats 5]

Renders the 320x240 ball lens (benchmarks/ball_lens.py) with Beam at the
lamp-ray count that first reaches 5% error in benchmarks/results/accuracy.json,
and measures, each the fastest of `repeats`:

- upload: embreex's `TriangleMesh` copying the meshes into Embree. It reads
  each coordinate and index through Python indexing, holding the GIL, so
  nothing else in the process runs meanwhile;
- build: Embree's BVH build, which embreex runs on the scene's first query;
- trace: Embree alone on the very batches of rays the render casts,
  recorded from it and replayed on 2 threads, split as the engine splits
  them, and on 1;
- the whole render's wall time, and the process's CPU time, on 1 thread
  and on 2;
- raw embreex rays/s as `speed.py` measures it, to compare this machine's
  speed on the day with README's other figures;
- how two threads scale the passes' kind of numpy work (row gathers, row
  dot products, selects) on arrays of 5,000 to 80,000 rows.

What is left of the wall time is the engine's numpy work. Under the bar,
numpy could have at most the bar less upload, build and half of the
one-thread trace (Embree on both cores with no loss). Writes
benchmarks/results/budget.json.
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import threading
import time
from datetime import date
from pathlib import Path

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

import ball_lens  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.tracing.accelerator import Accelerator  # noqa: E402
from embreex import rtcore_scene  # noqa: E402
from embreex.mesh_construction import TriangleMesh  # noqa: E402
from skips import patched  # noqa: E402
from speed import benchmark_scene, machine, raw_embree_rays_per_second  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
BAR_SECONDS = 0.2


def lamp_rays_for(error: float) -> int:
    """The fewest lamp rays on accuracy.json's Beam curve that reach `error`."""
    curve = json.loads((RESULTS / "accuracy.json").read_text())["curves"]["beam"]
    return min(p["lamp_rays"] for p in curve if p["error"] <= error)


def upload_and_build(scene, repeats: int) -> tuple[float, float]:
    """Seconds (upload, build) of the scene's meshes in a fresh Embree scene."""
    meshes = [(o.mesh.vertices.astype(np.float32), o.mesh.triangles.astype(np.int32)) for o in scene.objects]
    one_ray = np.zeros((1, 3), np.float32), np.array([[0.0, 0.0, 1.0]], np.float32)
    uploads, builds = [], []
    for _ in range(repeats):
        embree = rtcore_scene.EmbreeScene()
        start = time.perf_counter()
        for vertices, triangles in meshes:
            TriangleMesh(embree, vertices, triangles)
        uploads.append(time.perf_counter() - start)
        start = time.perf_counter()
        embree.run(*one_ray)
        builds.append(time.perf_counter() - start)
    return min(uploads), min(builds)


def recorded_batches(scene, settings: RenderSettings) -> list[tuple]:
    """Every (origins, dirs, kwargs) batch one render hands to Embree."""
    batches = []
    original = Accelerator._run

    def recording(self, embree, origins, dirs, **kwargs):
        batches.append((np.array(origins), np.array(dirs), dict(kwargs)))
        return original(self, embree, origins, dirs, **kwargs)

    with patched(Accelerator, "_run", recording):
        render(scene, settings)
    return batches


def replay(scene, batches: list[tuple], threads: int) -> float:
    """Seconds Embree takes over `batches`, one after another, each split
    over `threads` as the engine splits it."""
    accel = Accelerator(scene.objects, scene.extent(), threads)
    embree = accel._all.embree  # the budget's scene: every ray sees every object
    accel._run(embree, *batches[0][:2], **batches[0][2])  # builds the BVH outside the clock
    start = time.perf_counter()
    for origins, dirs, kwargs in batches:
        accel._run(embree, origins, dirs, **kwargs)
    seconds = time.perf_counter() - start
    accel.close()
    return seconds


def numpy_thread_scaling(rows: int, repeats: int) -> float:
    """Speed-up of two threads over one, each thread doing the same work:
    the passes' kind of numpy calls on (rows,3) arrays, 4M rows in all."""
    rng = np.random.default_rng(0)
    a, b, table = rng.random((rows, 3)), rng.random((rows, 3)), rng.random((65536, 3, 3))
    index, prim = rng.integers(0, rows, rows), rng.integers(0, len(table), rows)

    def work():
        for _ in range(4_000_000 // rows):
            d = np.einsum("ij,ij->i", a, b)
            np.take(table, prim, axis=0)
            np.take(np.where((d > 0.5)[:, None], a * d[:, None] + b, a), index, axis=0)
            np.flatnonzero(np.sqrt(d) > 0.3)

    def run(threads: int) -> float:
        workers = [threading.Thread(target=work) for _ in range(threads)]
        start = time.perf_counter()
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        return time.perf_counter() - start

    return 2 * min(run(1) for _ in range(repeats)) / min(run(2) for _ in range(repeats))


def timed_render(scene, settings: RenderSettings, repeats: int) -> dict:
    """Wall and CPU (user + system) seconds of the fastest of `repeats` renders."""
    best = None
    for _ in range(repeats):
        before, start = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
        render(scene, settings)
        wall, after = time.perf_counter() - start, resource.getrusage(resource.RUSAGE_SELF)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        if best is None or wall < best["wall_s"]:
            best = dict(wall_s=wall, cpu_s=cpu, cores_busy=cpu / wall)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    scene = ball_lens.scene()
    lamp_rays = lamp_rays_for(0.05)
    settings = {threads: RenderSettings(lamp_rays=lamp_rays, spp=1, density="beam", threads=threads)
                for threads in (1, 2)}
    renders = {threads: timed_render(scene, s, args.repeats) for threads, s in settings.items()}
    upload, build = upload_and_build(scene, args.repeats)
    batches = recorded_batches(scene, settings[2])
    trace = min(replay(scene, batches, 2) for _ in range(args.repeats))
    trace_one = min(replay(scene, batches, 1) for _ in range(args.repeats))
    scaling = {rows: numpy_thread_scaling(rows, 3) for rows in (5_000, 20_000, 80_000)}
    raw = max(raw_embree_rays_per_second(benchmark_scene(), 2_000_000, 2) for _ in range(3))
    wall = renders[2]["wall_s"]
    fixed = upload + build + trace
    fixed_ideal = upload + build + trace_one / 2
    report = {
        "date": date.today().isoformat(),
        "machine": machine(),
        "scene": "ball lens, 320x240, 1 spp, Beam (benchmarks/ball_lens.py)",
        "raw_embree_rays_per_s": raw,
        "lamp_rays": lamp_rays,
        "render_2_threads": renders[2],
        "render_1_thread": renders[1],
        "embreex_upload_s": upload,
        "embree_build_s": build,
        "embree_trace_s": trace,
        "embree_trace_1_thread_s": trace_one,
        "rays": int(sum(len(b[0]) for b in batches)),
        "batches": len(batches),
        "embree_total_s": fixed,
        "numpy_s": wall - fixed,
        "numpy_two_thread_speedup_by_rows": scaling,
        "bar_s": BAR_SECONDS,
        "embree_total_ideal_s": fixed_ideal,
        "left_for_numpy_under_bar_s": BAR_SECONDS - fixed_ideal,
    }
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "budget.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"{report['date']}, {report['machine']}")
    print(f"raw embreex, 2 threads    {raw / 1e6:6.2f} M rays/s")
    print(f"ball lens 320x240 at {lamp_rays:,} lamp rays (5% error)")
    for threads in (2, 1):
        r = renders[threads]
        print(f"render, {threads} thread{'s' if threads > 1 else ' '}       {r['wall_s']:6.3f} s wall, "
              f"{r['cpu_s']:.3f} s CPU ({r['cores_busy']:.2f} cores busy)")
    print(f"embreex upload (GIL held) {upload:6.3f} s")
    print(f"Embree BVH build          {build:6.3f} s")
    print(f"Embree tracing            {trace:6.3f} s for {report['rays']:,} rays in {len(batches)} batches "
          f"({trace_one:.3f} s on 1 thread)")
    print(f"the rest (numpy)          {wall - fixed:6.3f} s")
    print("numpy, 2 threads over 1   " + ", ".join(f"{x:.2f}x at {r:,} rows" for r, x in scaling.items()))
    print(f"under the {BAR_SECONDS} s bar, numpy would have at most {BAR_SECONDS - fixed_ideal:.3f} s")


if __name__ == "__main__":
    main()
