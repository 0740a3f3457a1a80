"""What each of the engine's skips saves (issue 4, section 4: "Skip what a
scene does not need. Each item is measured in the benchmark with its
saving").

    .venv/bin/python benchmarks/skips.py [--repeats 3]

Each skip is rendered on a scene that exercises it, once as the engine does
and once with the skip disabled here: by patching, inside this script, the
engine function that makes it (the engine has no switch for them), or, for
targeted emission, with the paper's sphere emission. Each time is the
fastest of `repeats` runs of the stage the skip changes; rays are those
the two passes cast. Where turning a skip off changes the image (the photon
budget), the caustic's noise is reported too: the relative L2 difference
from a 3,000,000-photon render with the same density estimate, over the
floor pixels of the ball's shadow disc. Writes
benchmarks/results/skips.json and prints the markdown table README quotes.
On a machine other jobs load, the small savings are within its noise.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from contextlib import contextmanager
from datetime import date
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import ball_lens  # noqa: E402
from caustic_addon import (Camera, Dielectric, Diffuse, MapCache, Object, PointLight, RenderSettings,  # noqa: E402
                           Scene, SpotLight, SunLight, paper, render, shapes)
from caustic_addon import renderer  # noqa: E402
from caustic_addon.emission import aims  # noqa: E402
from caustic_addon.emission.lamp_samples import sample_lamp  # noqa: E402
from caustic_addon.passes import direct_light, eye, photon  # noqa: E402
from caustic_addon.tracing.accelerator import Accelerator  # noqa: E402
from caustic_addon.util.vectors import dot  # noqa: E402
from speed import machine  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
PIXELS = (160, 120)


@contextmanager
def patched(module, name: str, replacement):
    """`module.name` replaced by `replacement` inside the block."""
    original = getattr(module, name)
    setattr(module, name, replacement)
    try:
        yield
    finally:
        setattr(module, name, original)


def timed(scene: Scene, settings: RenderSettings, repeats: int, cache: MapCache | None = None):
    """(fastest seconds of `repeats` renders per stage, 'total' for the
    whole, and the last render's result)."""
    best, result = {}, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = render(scene, settings, cache=cache)
        seconds = dict(result.stats["seconds"], total=time.perf_counter() - start)
        best = {stage: min(best.get(stage, math.inf), t) for stage, t in seconds.items()}
    return best, result


def rays(result) -> int:
    return int(result.stats["rays_lamp_pass"] + result.stats["rays_eye_pass"])


def row(name: str, scene_text: str, disabled_text: str, stage: str, on, off, effect: str = "",
        equal_quality: bool = True, **extra) -> dict:
    """One skip's figures: `on` and `off` are (seconds, result) with the
    skip and without; `stage` ('bvh', 'lamp_pass', 'eye' or 'total') is the
    time it changes; `effect`, what it does to the image. Without
    `equal_quality` the two differ in noise, and time alone is no saving."""
    (t_on, r_on), (t_off, r_off) = on, off
    saving = t_off[stage] - t_on[stage]
    entry = dict(skip=name, scene=scene_text, without=disabled_text, stage=stage, seconds_with=t_on,
                 seconds_without=t_off, rays_with=rays(r_on), rays_without=rays(r_off), saving_seconds=saving,
                 saving_fraction=saving / t_off[stage], equal_quality=equal_quality, effect=effect, **extra)
    print(f"{name}: {stage} {t_on[stage]:.2f} s / {t_off[stage]:.2f} s, rays {rays(r_on):,} / {rays(r_off):,}"
          f" {effect}", flush=True)
    return entry


def caustic_noise(result, reference, region: np.ndarray) -> float:
    """Relative L2 difference of the caustic pass from `reference`'s over
    the pixels of `region` (pixy, pixx): with the same density estimate and
    a reference of many more photons, the estimate's noise alone."""
    ours, theirs = (r.passes["caustic"][..., 0].astype(np.float64)[region] for r in (result, reference))
    return float(np.linalg.norm(ours - theirs) / np.linalg.norm(theirs))


def ball_scene(extra_lights=()) -> Scene:
    scene = ball_lens.scene(*PIXELS, segments=128)
    scene.lights += list(extra_lights)
    return scene


# The photon-budget rows estimate density with the paper's bilinear map at
# a fixed cell, so that both sides have the same bias and differ in noise.
SPLAT = dict(density="splat", map_scale=20.0, spp=1)


class Quality:
    """The ball lens's caustic from REFERENCE_PHOTONS targeted photons, and
    the pixels inside its shadow disc that see the floor."""

    REFERENCE_PHOTONS = 3_000_000

    def __init__(self):
        scene = ball_scene()
        self.region = ball_lens.pixel_reference(scene, supersample=2, bins=2000).region
        self.reference = render(scene, RenderSettings(lamp_rays=self.REFERENCE_PHOTONS, **SPLAT))

    def noise(self, result) -> float:
        return caustic_noise(result, self.reference, self.region)


def lamps_out_of_view(repeats: int, quality: Quality) -> list[dict]:
    """A spot lamp whose cone misses the glass gets no photons. Without the
    check (every lamp aims at every glass): alone, the spot costs a photon
    pass whose photons its cone gives no flux; beside the point lamp over
    the glass, it takes a share of the photon budget for nothing, so the
    budget must grow to land as many photons (equal noise)."""
    spot = SpotLight((3.0, 0.0, 3.0), (0.0, 0.0, -1.0), 1000.0, math.radians(30.0), 0.1)
    keep_all = partial(patched, aims, "visible_targets", lambda light, targets: list(targets))
    alone = ball_scene()
    alone.lights = [spot]
    settings = RenderSettings(lamp_rays=1_000_000, **SPLAT)
    on = timed(alone, settings, repeats)
    with keep_all():
        off = timed(alone, settings, repeats)
    out = [row("no photons from a lamp that sees no glass", "ball lens under a spot lamp aimed 3 m from it; "
               "1,000,000 photons", "`aims.visible_targets` keeps every glass", "lamp_pass", on, off,
               "the same: nothing lands")]

    both = ball_scene([spot])
    photons = 200_000
    on = timed(both, RenderSettings(lamp_rays=photons, **SPLAT), repeats)
    with keep_all():
        probe = render(both, RenderSettings(lamp_rays=photons, **SPLAT))
        count = int(round(photons * on[1].stats["landed"] / probe.stats["landed"], -4))
        off = timed(both, RenderSettings(lamp_rays=count, **SPLAT), repeats)
    landed = (on[1].stats["landed"], off[1].stats["landed"])
    out.append(row("no photons from a lamp that sees no glass", f"ball lens, its point lamp and the spot lamp; "
                   f"{photons:,} photons", f"`visible_targets` keeps every glass; {count:,} photons land as many",
                   "lamp_pass", on, off, f"landed {landed[0]:,} vs {landed[1]:,}; caustic noise "
                   f"{100 * quality.noise(on[1]):.1f}% vs {100 * quality.noise(off[1]):.1f}%",
                   photons_without=count, landed_with=landed[0], landed_without=landed[1]))
    return out


def targeted_emission(repeats: int, quality: Quality) -> list[dict]:
    """Photons only into the glass's cone, against the paper's whole sphere
    (eq. 1): at equal photon count, and with the sphere given as many
    photons as it needs to land as many on the floor (equal noise)."""
    scene = ball_scene()
    photons = 100_000
    on = timed(scene, RenderSettings(lamp_rays=photons, **SPLAT), repeats)
    out = []
    landed = on[1].stats["landed"]
    sphere_counts = {"equal photon count": photons}
    probe = render(scene, RenderSettings(lamp_rays=photons, emission="sphere", **SPLAT))
    sphere_counts["as many landed"] = int(round(photons * landed / probe.stats["landed"], -4))
    for label, count in sphere_counts.items():
        off = timed(scene, RenderSettings(lamp_rays=count, emission="sphere", **SPLAT), repeats)
        effect = (f"landed {landed:,} vs {off[1].stats['landed']:,}; "
                  f"caustic noise {100 * quality.noise(on[1]):.1f}% vs {100 * quality.noise(off[1]):.1f}%")
        out.append(row("photons only toward the glass", f"ball lens, {photons:,} photons",
                       f"`emission='sphere'` (the paper's eq. 1), {label}: {count:,} photons", "lamp_pass", on, off,
                       effect, equal_quality=label != "equal photon count",
                       sphere_photons=count, landed_with=landed,
                       landed_without=off[1].stats["landed"]))
    return out


def direct_radiance_shadowing_all(accel, lights, energy, points, shading, facing, view, diffuse, lobe, far,
                                  *strata):
    """direct_light.direct_radiance, after casting the shadow rays it skips:
    one per point and (point) lamp behind the surface."""
    for light in lights:
        lamp = sample_lamp(light, energy, points, np.full((len(points), 2), 0.5), far)
        behind = ~((dot(shading, lamp.dirs) > 0.0) & (dot(facing, lamp.dirs) > 0.0))
        if behind.any():
            accel.occluded(accel.offset(points[behind], -facing[behind], lamp.dirs[behind]), lamp.dirs[behind],
                           lamp.dist[behind] - 2.0 * accel.epsilon)
    return direct_light.direct_radiance(accel, lights, energy, points, shading, facing, view, diffuse, lobe, far,
                                        *strata)


def shadow_rays_behind(repeats: int) -> dict:
    """A second lamp under the floor: every floor point faces away from it."""
    scene = ball_scene([PointLight((0.0, 0.0, -2.0), 1000.0)])
    settings = RenderSettings(lamp_rays=20_000, spp=4, density="adaptive")
    on = timed(scene, settings, repeats)
    with patched(eye, "direct_radiance", direct_radiance_shadowing_all):
        off = timed(scene, settings, repeats)
    same = float(np.abs(on[1].image - off[1].image).max())
    return row("no shadow ray toward a lamp behind the surface", "ball lens + a lamp under the floor, 4 spp",
               "a shadow ray per point and lamp", "eye", on, off, f"same image (max difference {same:.0e})")


shade_opaque = eye.EyeTracer.arrived


def shade_opaque_and_reflect(self, rays, hits):
    """EyeTracer.arrived, then a mirror ray from every opaque hit, as a
    Whitted tracer casts at any surface (it carries nothing from these
    diffuse materials); one level only, so a lower bound of the cost."""
    shade_opaque(self, rays, hits)
    if len(rays) == 0:
        return
    facing = np.take(self.accel.face_normal, hits.prim, axis=0)
    facing = np.where((dot(facing, rays.dirs) > 0.0)[:, None], -facing, facing)
    mirrored = rays.dirs - 2.0 * dot(rays.dirs, facing)[:, None] * facing
    self.accel.intersect(self.accel.offset(hits.points, facing, mirrored), mirrored)


def no_recursion_at_diffuse(repeats: int) -> dict:
    scene = ball_scene()
    settings = RenderSettings(lamp_rays=20_000, spp=4, density="adaptive")
    on = timed(scene, settings, repeats)
    with patched(eye.EyeTracer, "arrived", shade_opaque_and_reflect):
        off = timed(scene, settings, repeats)
    return row("no recursion at diffuse surfaces", "ball lens, 4 spp",
               "a mirror ray at every diffuse hit (one level)", "eye", on, off, "same image")


def russian_roulette(repeats: int) -> dict:
    """Tinted diamond, point down: each reflection or refraction keeps 30%
    of a photon's flux, and below 5% of its start a photon plays Russian
    roulette. Unbiased: the landed flux agrees within its noise."""
    scene = Scene(
        objects=[Object("Floor", shapes.plane(paper.FLOOR_SIZE), Diffuse(albedo=0.8)),
                 Object("Gem", paper.glass("pointed"), Dielectric(2.41, reflection_tint=0.3, transmission_tint=0.3))],
        lights=[PointLight(paper.LAMP_POSITION, 100.0)],
        camera=Camera.from_paper(paper.FOV, *PIXELS, 1.0, paper.EYE, paper.TARGET))
    settings = RenderSettings(lamp_rays=500_000, spp=1, density="adaptive")
    on = timed(scene, settings, repeats)
    with patched(photon, "roulette", lambda flux, threshold, xi: (flux, flux.max(axis=1) > 0.0)):
        off = timed(scene, settings, repeats)
    flux = (on[1].stats["flux_landed_w"][0], off[1].stats["flux_landed_w"][0])
    return row("Russian roulette below 5% of a photon's start flux", "diamond cone tinted 0.3, 500k photons",
               "every photon traced to max depth (12) or escape", "lamp_pass", on, off,
               f"landed flux {flux[0]:.4g} vs {flux[1]:.4g} W", flux_landed_with=flux[0], flux_landed_without=flux[1])


def pool_scene() -> Scene:
    """A 2 m slab of wavy water (IOR 1.33) on a 4 m floor under a 0.5-degree
    sun 20 degrees off the vertical, seen from the side at 4 samples: the
    animation benchmark's pool, small."""
    sun = SunLight((-0.17, 0.3, -0.94), 3.0, angle=math.radians(0.5))
    return Scene(
        objects=[Object("Floor", shapes.plane(4.0), Diffuse(albedo=0.8)),
                 Object("Water", shapes.wavy_slab(2.0, 0.5), Dielectric(1.33))],
        lights=[sun], camera=Camera.look_at((0.0, -3.0, 2.5), (0.0, 0.0, 0.3), pixx=PIXELS[0], pixy=PIXELS[1]))


def eye_roulette(repeats: int) -> dict:
    """The eye branches fainter than 5% of their camera ray play Russian
    roulette; without, every branch is followed down to 1e-4 of it."""
    scene, settings = pool_scene(), RenderSettings(lamp_rays=20_000)
    on = timed(scene, settings, repeats)
    with patched(eye, "ROULETTE_WEIGHT", 0.0):
        off = timed(scene, settings, repeats)
    return row("Russian roulette of eye branches below 5% of their camera ray", "wavy water slab, 0.5-degree sun",
               "every branch to 1e-4 of its camera ray", "eye", on, off, image_change(on[1], off[1]))


def small_lamp_shadows(repeats: int) -> dict:
    """A lamp under a degree casts its first shadow rays, two a pixel at
    least (one a point of 4), the rest of its 8 where a pixel's disagree;
    without, all 8 from every point."""
    scene, settings = pool_scene(), RenderSettings(lamp_rays=20_000)
    on = timed(scene, settings, repeats)
    with patched(direct_light, "SMALL_LAMP", 0.0):
        off = timed(scene, settings, repeats)
    return row("a small lamp's first shadow rays where a pixel's agree", "wavy water slab, 0.5-degree sun",
               "8 shadow rays a point", "eye", on, off, image_change(on[1], off[1]))


def image_change(on, off) -> str:
    """The relative L2 difference between two renders' images."""
    a, b = (r.image[..., :3].astype(np.float64) for r in (on, off))
    return f"image {100 * np.linalg.norm(a - b) / np.linalg.norm(b):.2f}% from the one without"


def one_embree_scene(repeats: int) -> dict:
    """The speed scene's 65k-triangle sphere: one BVH for both passes,
    against a second one built for the eye pass."""
    scene = Scene(
        objects=[Object("Floor", shapes.plane(10.0), Diffuse(albedo=0.8)),
                 Object("Glass", shapes.uv_sphere(1.0, (0, 0, 1.5), 256, 128), Dielectric(1.5))],
        lights=[PointLight((0, 0, 6), 1000.0)],
        camera=Camera.look_at((0, -6, 5), (0, 0, 0.5), pixx=PIXELS[0], pixy=PIXELS[1]))
    original = renderer.eye_pass

    def eye_pass_own_bvh(scene, settings, accel, materials, maps, monitor, start):
        own = Accelerator(scene.objects, scene.extent(), settings.threads)
        try:
            return original(scene, settings, own, materials, maps, monitor, start)
        finally:
            accel.rays_cast += own.rays_cast
            own.close()

    settings = RenderSettings(lamp_rays=100_000, spp=1, density="adaptive")
    on = timed(scene, settings, repeats)
    with patched(renderer, "eye_pass", eye_pass_own_bvh):
        off = timed(scene, settings, repeats)
    return row("one Embree scene for both passes", "65,536-triangle glass sphere, 100k photons",
               "a second BVH built for the eye pass", "total", on, off, "same image")


def map_cache(repeats: int) -> dict:
    """Render, move the camera, render again: the second render's time."""
    scene = ball_scene()
    moved = ball_scene()
    moved.camera = Camera.look_at((2.0, -4.5, 3.0), (0.0, 0.3, 0.0), pixx=PIXELS[0], pixy=PIXELS[1],
                                  fov=ball_lens.FOV)
    settings = RenderSettings(lamp_rays=1_000_000, spp=1, density="adaptive")
    cache = MapCache()
    render(scene, settings, cache=cache)
    on = timed(moved, settings, repeats, cache=cache)
    off = timed(moved, settings, repeats)
    assert on[1].stats["maps_cached"] and not off[1].stats["maps_cached"]
    return row("illumination maps kept when only the camera moves", "ball lens, 1M photons, re-render after a "
               "camera move", "no cache: the photon pass again", "total", on, off, "same image")


def markdown(rows: list[dict]) -> str:
    lines = ["| skip | scene | without it | time with / without | rays with / without | saving | image |",
             "|---|---|---|---|---|---|---|"]
    stage = {"bvh": "BVH", "lamp_pass": "photon pass", "eye": "eye pass", "total": "render"}
    for r in rows:
        t_on, t_off = r["seconds_with"][r["stage"]], r["seconds_without"][r["stage"]]
        saving = (f"{r['saving_seconds']:.2f} s ({100 * r['saving_fraction']:.0f}%)" if r["equal_quality"]
                  else "see noise")
        lines.append(f"| {r['skip']} | {r['scene']} | {r['without']} | {stage[r['stage']]} {t_on:.2f} / "
                     f"{t_off:.2f} s | {r['rays_with']:,} / {r['rays_without']:,} | {saving} | {r['effect']} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    start = time.perf_counter()
    quality = Quality()
    rows = [*lamps_out_of_view(args.repeats, quality), *targeted_emission(args.repeats, quality),
            shadow_rays_behind(args.repeats), no_recursion_at_diffuse(args.repeats),
            russian_roulette(args.repeats), eye_roulette(args.repeats), small_lamp_shadows(args.repeats),
            one_embree_scene(args.repeats), map_cache(args.repeats)]
    table = markdown(rows)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "skips.json").write_text(json.dumps(
        dict(date=date.today().isoformat(), machine=machine(), repeats=args.repeats,
             wall_seconds=time.perf_counter() - start, skips=rows, table=table), indent=2) + "\n")
    print("\n" + table)


if __name__ == "__main__":
    main()
