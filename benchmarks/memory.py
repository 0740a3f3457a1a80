"""Memory against photon count: does a render of 10^8 photons fit in the
memory of one of 10^6?

    .venv/bin/python benchmarks/memory.py [--photons 1e8] [--baseline 1e6]

Renders the ball lens (a 128 x 64 glass sphere over a floor, a point lamp;
64 x 64 pixels, 1 sample per pixel, so the eye pass is negligible) once with
`--baseline` photons and once with `--photons`, each in a fresh process with
the default chunk size and threads, and prints for each the wall time, the
photon rate, the peak resident set size (getrusage ru_maxrss) before and after
the render, and the ratio of the two peaks. 10^8 photons take minutes.
Writes benchmarks/results/memory.json.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from caustic_addon import Dielectric, Diffuse, Object, PointLight, RenderSettings, Scene, render, shapes  # noqa: E402
from caustic_addon.scene import Camera  # noqa: E402


def ball_lens_scene() -> Scene:
    top = Camera.look_at((0.0, 0.0, 20.0), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixx=64, pixy=64,
                         kind="ORTHO", ortho_scale=4.0)
    return Scene(
        objects=[Object("Floor", shapes.plane(8.0), Diffuse(albedo=0.8)),
                 Object("Glass", shapes.uv_sphere(1.0, (0.0, 0.0, 1.5), 128, 64), Dielectric(1.5))],
        lights=[PointLight((0.0, 0.0, 6.0), 1000.0)],
        camera=top,
    )


def peak_rss_mb() -> float:
    """This process's peak resident set so far, MB (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def measure(photons: int) -> dict:
    """One render in this process; what it cost."""
    scene = ball_lens_scene()
    settings = RenderSettings(lamp_rays=photons, spp=1, density="adaptive")
    before = peak_rss_mb()
    start = time.perf_counter()
    result = render(scene, settings)
    seconds = time.perf_counter() - start
    return {
        "photons": result.stats["lamp_rays"],
        "landed": result.stats["landed"],
        "chunk_size": settings.chunk_size,
        "seconds": seconds,
        "photons_per_second": result.stats["lamp_rays"] / seconds,
        "peak_rss_mb_before": before,
        "peak_rss_mb": peak_rss_mb(),
    }


def in_fresh_process(photons: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", str(photons)], check=True, capture_output=True,
                         text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--photons", type=float, default=1e8)
    parser.add_argument("--baseline", type=float, default=1e6)
    parser.add_argument("--child", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(measure(int(args.child))))
        return

    rows = [in_fresh_process(int(args.baseline)), in_fresh_process(int(args.photons))]
    print(f"{'photons':>12} {'landed':>12} {'wall s':>9} {'photons/s':>11} {'RSS before MB':>14} {'peak RSS MB':>12}")
    for r in rows:
        print(f"{r['photons']:>12,} {r['landed']:>12,} {r['seconds']:>9.1f} {r['photons_per_second']:>11,.0f} "
              f"{r['peak_rss_mb_before']:>14.0f} {r['peak_rss_mb']:>12.0f}")
    small, large = rows
    print(f"peak RSS ratio {large['peak_rss_mb'] / small['peak_rss_mb']:.2f} for "
          f"{large['photons'] / small['photons']:.0f}x the photons (chunk size {large['chunk_size']:,})")
    record.write("memory", dict(scene="ball lens, 128 x 64 sphere, 64 x 64 pixels, 1 spp, adaptive", rows=rows,
                                peak_ratio=large["peak_rss_mb"] / small["peak_rss_mb"],
                                photon_ratio=large["photons"] / small["photons"]))


if __name__ == "__main__":
    main()
