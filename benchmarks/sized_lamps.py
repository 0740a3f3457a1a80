"""A lamp with a size through the ball lens: the engine's caustic against a
long Cycles path-traced render, and what the size costs against a point lamp.

    .venv/bin/python benchmarks/sized_lamps.py [--cycles-samples 8192]

The scene is the ball lens (benchmarks/scenes/ball_lens.py) at 160x120, lit
by a sphere lamp of radius RADIUS (Soft Falloff off: a Lambertian sphere in
both renderers) in place of the point lamp. Cycles path-traces it with MNEE
off (plain path tracing finds a lamp with a size through glass, by the
floor's BSDF samples) and Filter Glossy 0 (its default 1.0 roughens the
glass after the floor's bounce, which blurs the caustic and misplaces a
quarter of its light), box filter, no denoising, the floor white to camera
rays and black to all others (benchmarks/scenes/ball_lens_cycles.py, as
cycles_accuracy.py: the caustic and the direct light, not the floor's light
bounced back onto itself). Two renders of --cycles-samples each, with
different seeds, give the reference (their mean) and its own noise (half
their difference).

Measured, each as a relative L2 error over the pixels that see the floor
directly within REGION shadow radii (the caustic, the shadow's penumbra and
their rim):
- the converged engine render (CONVERGED settings) against Cycles, beside
  Cycles' own noise;
- Cycles against the converged engine render, for samples 16 to 4096, with
  the time of each;
- the engine's caustic pass at the default settings, for lamp rays from
  2,500 up, with the whole render's time (the fastest of REPEATS): for the
  sphere lamp against Cycles' caustic (the reference less the converged
  render's direct light, which the lamp tests hold to Cycles' within
  0.1%), and for the point lamp of the same power, which Cycles cannot
  render through glass, against its own converged caustic; the time each
  needs to reach 10%, 5% and 2%, and their ratio.
Writes benchmarks/results/sized_lamps.json.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

import bpy  # noqa: E402

from benchmarks import record  # noqa: E402
from benchmarks.accuracy import THRESHOLDS, time_to_reach  # noqa: E402
from benchmarks.scenes import ball_lens, ball_lens_cycles  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.passes.camera_rays import eye_rays  # noqa: E402
from caustic_addon.tracing.accelerator import Accelerator  # noqa: E402

RESULTS = record.RESULTS
RADIUS = 0.5
PIXX, PIXY = 160, 120
REGION = 1.5
CONVERGED = RenderSettings(lamp_rays=2_000_000, spp=16, lamp_samples=32)
LAMP_RAYS = [int(c) for c in 10 ** np.arange(np.log10(2500), 6.01, 0.25)]
CYCLES_SAMPLES = [16, 64, 256, 1024, 4096]
REPEATS = 2


def engine_scene(radius: float):
    the_scene = ball_lens.scene(PIXX, PIXY)
    the_scene.lights = [replace(the_scene.lights[0], radius=radius, soft_falloff=False)]
    return the_scene


def floor_region(the_scene, supersample: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """(region (pixy, pixx) bool: every sub-sample of the pixel sees the
    floor directly within REGION shadow radii of the axis; (pixy, pixx) the
    mean distance from the axis of what each pixel sees of the floor, m)."""
    cam = the_scene.camera
    spp = supersample ** 2
    ticks = (np.arange(supersample) + 0.5) / supersample
    offsets = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    sample = np.arange(cam.pixx * cam.pixy * spp)
    origins, dirs = eye_rays(cam, sample // spp, offsets[sample % spp])
    accel = Accelerator(the_scene.objects, the_scene.extent(), 2)
    hits = accel.intersect(origins, dirs)
    accel.close()
    points = origins + np.where(hits.obj == 0, hits.t, 0.0)[:, None] * dirs
    r = np.hypot(points[:, 0], points[:, 1])
    inside = (hits.obj == 0) & (r < REGION * ball_lens.shadow_radius())
    shape = (cam.pixy, cam.pixx)
    return inside.reshape(-1, spp).all(axis=1).reshape(shape), r.reshape(-1, spp).mean(axis=1).reshape(shape)


def relative_l2(image: np.ndarray, reference: np.ndarray, region: np.ndarray) -> float:
    a, b = image[..., 0][region].astype(np.float64), reference[..., 0][region].astype(np.float64)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def cycles_renders(samples: int, sweep: list[int]) -> tuple[np.ndarray, np.ndarray, list[tuple]]:
    """(first and second reference render (h,w,3), [(samples, seconds, image)] of the sweep), cached in
    results/_cycles_sized_lamps_<samples>.npz (not committed; delete it after a change to the scene)."""
    cache = RESULTS / f"_cycles_sized_lamps_{samples}.npz"
    if cache.exists():
        saved = np.load(cache)
        return saved["first"], saved["second"], [(int(s), float(t), image) for s, t, image in
                                                 zip(saved["samples"], saved["seconds"], saved["images"])]
    first, second, swept = _cycles_renders(samples, sweep)
    RESULTS.mkdir(exist_ok=True)
    np.savez(cache, first=first, second=second, samples=[s for s, _, _ in swept],
             seconds=[t for _, t, _ in swept], images=np.stack([image for _, _, image in swept]))
    return first, second, swept


def _cycles_renders(samples: int, sweep: list[int]) -> tuple[np.ndarray, np.ndarray, list[tuple]]:
    _, objects = ball_lens_cycles.build_scene()
    lamp = objects["Lamp"].data
    lamp.shadow_soft_size, lamp.use_soft_falloff = RADIUS, False
    ball_lens_cycles.set_mnee(objects, False)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = PIXX, PIXY
    # Filter Glossy (1.0 by default) would roughen the glass after the floor's bounce
    scene.cycles.blur_glossy = 0.0
    with tempfile.TemporaryDirectory() as folder:
        swept = []
        for count in sweep:
            image, seconds = ball_lens_cycles.render(count, folder)
            swept.append((count, seconds, image))
            print(f"Cycles path tracing {count:6d} spp {seconds:8.2f} s", flush=True)
        scene.cycles.seed = 1
        first, seconds = ball_lens_cycles.render(samples, folder)
        print(f"Cycles reference, seed 1: {samples} spp {seconds:.1f} s", flush=True)
        scene.cycles.seed = 2
        second, seconds = ball_lens_cycles.render(samples, folder)
        print(f"Cycles reference, seed 2: {samples} spp {seconds:.1f} s", flush=True)
    return first, second, swept


def engine_curve(name: str, radius: float, truth: np.ndarray, region: np.ndarray) -> list[dict]:
    the_scene = engine_scene(radius)
    points = []
    for lamp_rays in LAMP_RAYS:
        runs = []
        for _ in range(REPEATS):
            start = time.perf_counter()
            result = render(the_scene, RenderSettings(lamp_rays=lamp_rays))
            runs.append((time.perf_counter() - start, result))
        seconds, result = min(runs, key=lambda run: run[0])
        error = relative_l2(result.passes["caustic"], truth, region)
        points.append(dict(lamp_rays=lamp_rays, paths=result.stats["lamp_rays"], seconds=seconds, error=error))
        print(f"{name:12s} {lamp_rays:>9,d} lamp rays {seconds:7.2f} s  caustic error {100 * error:6.2f}%",
              flush=True)
    return points


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=8192)
    args = parser.parse_args()

    sized = engine_scene(RADIUS)
    region, _ = floor_region(sized)
    start = time.perf_counter()
    converged = render(sized, CONVERGED)
    converged_seconds = time.perf_counter() - start
    point_truth = render(engine_scene(0.0), CONVERGED).passes["caustic"]

    first, second, swept = cycles_renders(args.cycles_samples, [s for s in CYCLES_SAMPLES
                                                                if s < args.cycles_samples])
    reference = 0.5 * (first + second)
    cycles_noise = float(0.5 * relative_l2(first, second, region) * np.linalg.norm(first[..., 0][region])
                         / np.linalg.norm(reference[..., 0][region]))
    against_cycles = relative_l2(converged.image[..., :3], reference, region)
    cycles_curve = [dict(samples=s, seconds=t, error=relative_l2(image, converged.image[..., :3], region))
                    for s, t, image in swept]
    print(f"engine converged ({converged_seconds:.1f} s) against Cycles {2 * args.cycles_samples} spp: "
          f"{100 * against_cycles:.2f}% (Cycles' own noise {100 * cycles_noise:.2f}%)")

    cycles_caustic = reference - converged.passes["direct"]
    curves = {"sphere lamp": engine_curve("sphere lamp", RADIUS, cycles_caustic, region),
              "point lamp": engine_curve("point lamp", 0.0, point_truth, region)}
    table = {name: {f"{int(100 * t)}%": time_to_reach(points, t) for t in THRESHOLDS}
             for name, points in curves.items()}
    table["Cycles path tracing"] = {f"{int(100 * t)}%": time_to_reach(cycles_curve, t) for t in THRESHOLDS}
    ratio = {key: (table["sphere lamp"][key] / table["point lamp"][key]
                   if table["sphere lamp"][key] and table["point lamp"][key] else None)
             for key in table["point lamp"]}
    record.write("sized_lamps", dict(
        blender=bpy.app.version_string, radius=RADIUS, pixels=[PIXX, PIXY], cycles_samples=2 * args.cycles_samples,
        cycles_noise=cycles_noise, engine_against_cycles=against_cycles, engine_converged_seconds=converged_seconds,
        cycles_curve=cycles_curve, curves=curves, time_to_reach=table, sized_over_point=ratio))
    print("\ntime to reach         " + "  ".join(f"{int(100 * t):>6d}%" for t in THRESHOLDS))
    for name, row in table.items():
        print(f"{name:20s}" + "  ".join(f"{v:6.2f}s" if v is not None else "     -" for v in row.values()))
    print("sphere / point      " + "  ".join(f"{v:6.2f} " if v is not None else "     -" for v in ratio.values()))


if __name__ == "__main__":
    main()
