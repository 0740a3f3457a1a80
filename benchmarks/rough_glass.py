"""Rough glass: the ball lens's caustic through a Glass BSDF of Roughness
0.05, 0.2 and 0.5, the engine against a long Cycles path-traced render, and
beam mode's two ways with a rough caster.

    .venv/bin/python benchmarks/rough_glass.py [--cycles-samples 1024] [--roughness 0.05 0.2 0.5]

The scene is the ball lens (benchmarks/scenes/ball_lens.py) at 160x120,
its glass given Roughness r (Multiscatter GGX, Blender's default), under a
sphere lamp of radius RADIUS (Soft Falloff off) in place of the point lamp:
Cycles' path tracing reaches a lamp through rough glass by the light
sampling at the glass's last vertex, which a point lamp would leave to a
narrow lobe's BSDF evaluation alone, and the sphere's own hits add the MIS
half. Cycles renders it with MNEE off and Filter Glossy 0 (as
benchmarks/sized_lamps.py: its default 1.0 would roughen the glass further
after the floor's bounce), box filter, no denoising, the floor white to
camera rays and black to all others, at most 12 glass bounces (the
engine's default max_depth); two renders of --cycles-samples with
different seeds give the reference (their mean) and its noise (half their
difference).

Measured for each roughness, over the pixels that see the floor directly
within sized_lamps.REGION shadow radii (the relative L2 error as in sized_lamps.py):
- the caustic's width, the radius holding three quarters of its flux over
  the region (the smooth ball's bright disc reaches its fold at 0.13 m), in
  Cycles' caustic (the reference less the engine's direct light, which
  the lamp tests hold to Cycles') and in the engine's converged caustic
  (CONVERGED: photons, the adaptive estimate with k = 256);
- the converged engine render against Cycles, beside Cycles' own noise;
- the engine's caustic against Cycles' at the default settings for lamp
  rays from 10,000 up, with the whole render's time (the fastest of
  REPEATS), and its error beyond the reference's own noise (the two are
  independent: sqrt(error^2 - noise^2)), by which the time to reach each
  threshold is counted, three ways:
  beam grids whose paths land as photons past the rough surface (beam
  mode with the lamp's grids of points kept for a rough caster; patched in
  here, see `grid_photons`), beam mode with spread beams (SPREAD_REPLICAS
  grids a lamp point, every vertex of a grid scattering about the
  microfacet normal of the same random numbers, so that its neighbours
  stay together and bound beams; patched in, see `spread_beams`), and the
  photon pass (density 'adaptive'), which is what beam mode ships for a
  lamp that lights a rough caster (passes.beam.photon_lamps), chosen by
  these figures;
- Cycles at 16 to 256 samples against the converged engine render, with
  its time.
Writes benchmarks/results/rough_glass.json, and rough_glass.png: a row
per roughness of Cycles' reference, the converged engine render and the
three ways at the default 40,000 lamp rays (sRGB).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

import bpy  # noqa: E402

from benchmarks import record  # noqa: E402
from benchmarks.accuracy import THRESHOLDS, time_to_reach  # noqa: E402
from benchmarks.scenes import ball_lens, ball_lens_cycles  # noqa: E402
from benchmarks.sized_lamps import floor_region, relative_l2  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.cli.image_io import write_image  # noqa: E402
from caustic_addon.passes import beam, bounce  # noqa: E402
from caustic_addon.sampling.sequences import r2_sequence  # noqa: E402

RESULTS = record.RESULTS
RADIUS = 0.1
PIXX, PIXY = 160, 120
ROUGHNESS = [0.05, 0.2, 0.5]
CONVERGED = RenderSettings(lamp_rays=4_000_000, density="adaptive", k_nearest=256, spp=16, lamp_samples=32)
LAMP_RAYS = [10_000, 20_000, 40_000, 80_000, 160_000, 320_000]
# Spread beams cost several times more a lamp ray: their curve stops sooner.
SPREAD_LAMP_RAYS = [10_000, 20_000, 40_000, 80_000]
CYCLES_SAMPLES = [16, 64, 256, 1024]
SPREAD_REPLICAS = 16
REPEATS = 2
# The lamp rays of the curves' renders shown in rough_glass.png: the default.
SHOWN = 40_000
EXPOSURE = 0.0


def engine_scene(roughness: float):
    the_scene = ball_lens.scene(PIXX, PIXY)
    the_scene.lights = [replace(the_scene.lights[0], radius=RADIUS, soft_falloff=False)]
    the_scene.objects[1].material.roughness = roughness
    return the_scene


def flux_radius(caustic: np.ndarray, region: np.ndarray, radius: np.ndarray, share: float = 0.75,
                ring: float = 0.02) -> float:
    """The radius within which `share` of the caustic's flux over the
    region lands (red channel): the pixels' mean irradiance in rings of
    `ring` m about the axis times each ring's area, its cumulative sum
    interpolated within the ring it crosses `share`."""
    e = caustic[..., 0][region].astype(np.float64)
    index = (radius[region] / ring).astype(np.int64)
    count = np.bincount(index)
    mean = np.bincount(index, weights=e) / np.maximum(count, 1)
    k = np.arange(len(mean))
    flux = np.cumsum(mean * np.pi * ring ** 2 * (2 * k + 1))
    target = share * flux[-1]
    at = int(np.searchsorted(flux, target))
    below = flux[at - 1] if at else 0.0
    return float(ring * (at + (target - below) / (flux[at] - below)))


@contextmanager
def grid_photons():
    """Beam mode keeping beam grids for lamps that light a rough caster
    (the way the engine does not ship; every caster taken as smooth in
    choosing what photons light): their paths land as photons past the
    rough surface."""
    original = beam.smooth_and_rough
    beam.smooth_and_rough = lambda scene, targets: (targets, [])
    try:
        yield
    finally:
        beam.smooth_and_rough = original


@contextmanager
def spread_beams(replicas: int):
    """Beam mode with spread beams, the way the engine does not ship: each
    beam source (a lamp point's grid over a caster) becomes `replicas`
    grids of 1 / sqrt(replicas) the side, sharing its light by the balance
    heuristic as aims that overlap do; at a rough surface every vertex of
    one grid scatters about the GGX normal of the same random numbers (the
    R2 point of the grid's index, rotated per bounce), so the grid keeps
    its families and its cells bound beams, and the replicas' sharp
    caustics, each about another microfacet normal, sum to the blurred one."""
    local = threading.local()
    original = beam.beam_sources, beam.band_beams, beam.BeamTracer.scattered, bounce._own_families

    def sources(*args):
        out = [replace(s, grid=max(3, int(round(s.grid / replicas ** 0.5)))) for s in original[0](*args)
               for _ in range(replicas)]
        for s in out:
            s.overlap = [(o.aim, 1.0 / o.cell_measure) for o in out if o.aim.light is s.aim.light]
        return out

    def band_beams(*args):
        local.keys = ((args[0].grid - 1) * (1 << args[8]) + 1) ** 2
        return original[1](*args)

    def scattered(self, paths, hits, surface, depth):
        if surface.rough.any():
            shift = np.random.default_rng(depth).random(2)
            surface = bounce.facets(surface, paths.dirs, self.materials, hits.obj,
                                    r2_sequence(paths.ids // local.keys, shift))
        return bounce.split(self.accel, self.materials, paths, hits, surface, carries_light=True)

    def own_families(surface):
        return np.zeros(len(surface.alpha), dtype=bool)

    beam.beam_sources, beam.band_beams, beam.BeamTracer.scattered, bounce._own_families = (
        sources, band_beams, scattered, own_families)
    try:
        with grid_photons():
            yield
    finally:
        beam.beam_sources, beam.band_beams, beam.BeamTracer.scattered, bounce._own_families = original


def cycles_scene(roughness: float) -> None:
    """The ball lens in bpy, its glass of `roughness`, under the sphere lamp."""
    _, objects = ball_lens_cycles.build_scene()
    lamp = objects["Lamp"].data
    lamp.shadow_soft_size, lamp.use_soft_falloff = RADIUS, False
    ball_lens_cycles.set_mnee(objects, False)
    objects["Glass"].active_material.node_tree.nodes["Glass BSDF"].inputs["Roughness"].default_value = roughness
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = PIXX, PIXY
    scene.cycles.blur_glossy = 0.0
    # the engine's default of 12 specular bounces, after the floor's diffuse one
    scene.cycles.max_bounces, scene.cycles.transmission_bounces, scene.cycles.glossy_bounces = 13, 12, 12


def cycles_renders(roughness: float, samples: int, sweep: list[int]):
    """(first and second reference render (h,w,3), [(samples, seconds, image)] of the sweep)."""
    cycles_scene(roughness)
    scene = bpy.context.scene
    with tempfile.TemporaryDirectory() as folder:
        swept = []
        for count in sweep:
            image, seconds = ball_lens_cycles.render(count, folder)
            swept.append((count, seconds, image))
            print(f"  Cycles {count:6d} spp {seconds:8.2f} s", flush=True)
        renders = []
        for seed in (1, 2):
            scene.cycles.seed = seed
            image, seconds = ball_lens_cycles.render(samples, folder)
            renders.append(image)
            print(f"  Cycles reference, seed {seed}: {samples} spp {seconds:.1f} s", flush=True)
    return renders[0], renders[1], swept


def engine_curve(name: str, roughness: float, density: str, truth: np.ndarray, region: np.ndarray,
                 noise: float, shown: dict, counts: list[int] = LAMP_RAYS) -> list[dict]:
    """The curve's points, each with its error against `truth` and that
    error beyond the truth's own `noise` (relative, independent of the
    engine's: sqrt(error^2 - noise^2)); its image at SHOWN lamp rays goes
    into `shown[name]`."""
    the_scene = engine_scene(roughness)
    points = []
    for lamp_rays in counts:
        runs = []
        for _ in range(REPEATS):
            start = time.perf_counter()
            result = render(the_scene, RenderSettings(lamp_rays=lamp_rays, density=density))
            runs.append((time.perf_counter() - start, result))
        seconds, result = min(runs, key=lambda run: run[0])
        error = relative_l2(result.passes["caustic"], truth, region)
        if lamp_rays == SHOWN:
            shown[name] = result.image[..., :3]
        excess = math.sqrt(max(error * error - noise * noise, 0.0))
        points.append(dict(lamp_rays=lamp_rays, paths=result.stats["lamp_rays"], seconds=seconds, error=error,
                           excess=excess))
        print(f"  {name:14s} {lamp_rays:>9,d} lamp rays {seconds:7.2f} s  caustic error {100 * error:6.2f}% "
              f"({100 * excess:5.2f}% beyond Cycles' noise)", flush=True)
    return points


def measure(roughness: float, cycles_samples: int) -> dict:
    print(f"Roughness {roughness}", flush=True)
    the_scene = engine_scene(roughness)
    region, radius = floor_region(the_scene)
    start = time.perf_counter()
    converged = render(the_scene, CONVERGED)
    converged_seconds = time.perf_counter() - start
    first, second, swept = cycles_renders(roughness, cycles_samples, [s for s in CYCLES_SAMPLES
                                                                       if s < cycles_samples])
    reference = 0.5 * (first + second)
    cycles_noise = float(0.5 * relative_l2(first, second, region) * np.linalg.norm(first[..., 0][region])
                         / np.linalg.norm(reference[..., 0][region]))
    against_cycles = relative_l2(converged.image[..., :3], reference, region)
    cycles_caustic = reference - converged.passes["direct"]
    caustic_noise = float(0.5 * np.linalg.norm((first - second)[..., 0][region])
                          / np.linalg.norm(cycles_caustic[..., 0][region]))
    widths = dict(cycles=flux_radius(cycles_caustic, region, radius),
                  engine=flux_radius(converged.passes["caustic"], region, radius))
    print(f"  engine converged ({converged_seconds:.1f} s) against Cycles {2 * cycles_samples} spp: "
          f"{100 * against_cycles:.2f}% (Cycles' own noise {100 * cycles_noise:.2f}%); caustic width "
          f"Cycles {widths['cycles']:.4f} m, engine {widths['engine']:.4f} m", flush=True)
    cycles_curve = [dict(samples=s, seconds=t, error=relative_l2(image, converged.image[..., :3], region))
                    for s, t, image in swept]
    shown = {"Cycles": reference, "engine converged": converged.image[..., :3]}
    print(f"  Cycles' caustic: noise {100 * caustic_noise:.2f}% of it", flush=True)
    args = (cycles_caustic, region, caustic_noise, shown)
    with grid_photons():
        curves = {"beam (photons past rough)": engine_curve("beam", roughness, "beam", *args)}
    with spread_beams(SPREAD_REPLICAS):
        curves["beam (spread beams)"] = engine_curve("spread beams", roughness, "beam", *args, SPREAD_LAMP_RAYS)
    curves["photons (adaptive)"] = engine_curve("photons", roughness, "adaptive", *args)
    table = {name: {f"{int(100 * t)}%": time_to_reach([dict(p, error=p["excess"]) for p in points], t)
                    for t in THRESHOLDS} for name, points in curves.items()}
    table["Cycles path tracing"] = {f"{int(100 * t)}%": time_to_reach(cycles_curve, t) for t in THRESHOLDS}
    return shown, dict(roughness=roughness, cycles_noise=cycles_noise, cycles_caustic_noise=caustic_noise,
                       engine_against_cycles=against_cycles, engine_converged_seconds=converged_seconds,
                       width_m=widths, cycles_curve=cycles_curve, curves=curves, time_to_reach=table)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=1024)
    parser.add_argument("--roughness", type=float, nargs="+", default=ROUGHNESS)
    args = parser.parse_args()
    shots, runs = zip(*[measure(r, args.cycles_samples) for r in args.roughness])
    RESULTS.mkdir(exist_ok=True)
    grid = np.concatenate([np.concatenate(list(shot.values()), axis=1) for shot in shots], axis=0)
    write_image(RESULTS / "rough_glass.png", np.concatenate([grid, np.ones_like(grid[..., :1])], axis=-1), EXPOSURE)
    print("benchmarks/results/rough_glass.png: rows Roughness " + ", ".join(map(str, args.roughness))
          + "; columns " + ", ".join(shots[0]) + f" ({SHOWN:,} lamp rays)")
    record.write("rough_glass", dict(
        blender=bpy.app.version_string, radius=RADIUS, pixels=[PIXX, PIXY], cycles_samples=2 * args.cycles_samples,
        spread_replicas=SPREAD_REPLICAS, runs=list(runs)))
    print("\nroughness  width Cycles / engine   engine vs Cycles (noise)   time to reach " +
          "  ".join(f"{int(100 * t)}%" for t in THRESHOLDS))
    for run in runs:
        print(f"{run['roughness']:9.2f}  {run['width_m']['cycles']:.4f} / {run['width_m']['engine']:.4f} m"
              f"   {100 * run['engine_against_cycles']:5.2f}% ({100 * run['cycles_noise']:.2f}%)")
        for name, row in run["time_to_reach"].items():
            print(f"           {name:28s}" + "  ".join(f"{v:6.2f}s" if v is not None else "     -"
                                                     for v in row.values()))


if __name__ == "__main__":
    main()
