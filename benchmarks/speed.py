"""The engine's photon and eye passes against Embree's own rays per second
(cast directly with nothing around the cast, and through embreex),
on a smooth 65k-triangle glass sphere over a floor (a point lamp, 640x480),
and the photon pass with the same sphere as a mirror (a reflector), whose
throughput per ray should be within 20% of the glass's.

The scene is benchmarks/scenes/glass_sphere.py.

    .venv/bin/python benchmarks/speed.py [--repeats 3]

Prints a table and writes benchmarks/results/speed.json. Each figure is the
best of `repeats` runs, so a busy machine shows less.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import casts, record  # noqa: E402
from benchmarks.scenes.glass_sphere import scene as benchmark_scene  # noqa: E402
from caustic_addon import MapCache, Reflector, RenderSettings, Scene, render  # noqa: E402
from caustic_addon.emission.aims import Sphere, aims  # noqa: E402
from caustic_addon.sampling.warps import sample_disc  # noqa: E402


def raw_rays_per_second(scene: Scene, rays: int, repeats: int) -> dict:
    """Closest-hit rays/s of Embree alone on the scene, cast directly and
    through embreex, rays from the lamp into the sphere's cone, the batch
    split over 2 threads as the engine splits it (casts.py)."""
    sphere = Sphere.around(scene.objects[1].mesh.vertices)
    (aim,) = aims(scene.lights[0], [sphere], sphere)
    origins, dirs = aim.rays(sample_disc(1.0, np.random.default_rng(0).random((rays, 2))))
    batch = casts.Batch(tuple(range(len(scene.objects))), np.ascontiguousarray(origins), np.ascontiguousarray(dirs),
                        None, False)
    replay = casts.Replay(scene.objects, [batch])
    try:
        return {way: rays / replay.seconds(way, repeats=repeats) for way in ("direct1", "embreex")}
    finally:
        replay.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--photons", type=int, default=1_000_000)
    args = parser.parse_args()

    scene = benchmark_scene()
    raw_rates = raw_rays_per_second(scene, 2_000_000, args.repeats)
    raw = raw_rates["direct1"]

    # glass and mirror runs alternate, so a change in the machine's load hits both
    runs, mirror_runs = [], []
    for _ in range(args.repeats):
        runs.append(render(scene, RenderSettings(lamp_rays=args.photons, spp=1, density="adaptive")).stats)
        mirror_runs.append(render(benchmark_scene(Reflector(0.9)), RenderSettings(lamp_rays=args.photons, spp=1, density="adaptive")).stats)

    # a camera move with the map cache: only the eye pass runs again
    cache = MapCache()
    render(scene, RenderSettings(lamp_rays=args.photons, spp=1, density="adaptive"), cache=cache)
    scene.camera.matrix[0, 3] += 0.5
    clock = time.perf_counter()
    render(scene, RenderSettings(lamp_rays=args.photons, spp=1, density="adaptive"), cache=cache)
    cached_rerender = time.perf_counter() - clock
    photon = min(runs, key=lambda s: s["seconds"]["lamp_pass"])
    eye = min(runs, key=lambda s: s["seconds"]["eye"])

    paths_per_s = photon["lamp_rays"] / photon["seconds"]["lamp_pass"]
    photon_rays_per_s = photon["rays_lamp_pass"] / photon["seconds"]["lamp_pass"]
    eye_rays_per_s = eye["rays_eye_pass"] / eye["seconds"]["eye"]
    mirror = min(mirror_runs, key=lambda s: s["seconds"]["lamp_pass"])
    mirror_rays_per_s = mirror["rays_lamp_pass"] / mirror["seconds"]["lamp_pass"]
    figures = {
        "scene": "smooth glass UV sphere, 65,536 triangles, over a floor; point lamp; 640x480, 1 spp",
        "raw_embree_rays_per_s": raw,
        "embreex_rays_per_s": raw_rates["embreex"],
        "photons": photon["lamp_rays"],
        "photon_pass_s": photon["seconds"]["lamp_pass"],
        "photon_paths_per_s": paths_per_s,
        "photon_pass_rays_per_s": photon_rays_per_s,
        "photon_pass_fraction_of_raw": photon_rays_per_s / raw,
        "eye_pass_s": eye["seconds"]["eye"],
        "eye_pass_rays": eye["rays_eye_pass"],
        "eye_pass_rays_per_s": eye_rays_per_s,
        "eye_pass_fraction_of_raw": eye_rays_per_s / raw,
        "reflector_photon_pass_s": mirror["seconds"]["lamp_pass"],
        "reflector_photon_paths_per_s": mirror["lamp_rays"] / mirror["seconds"]["lamp_pass"],
        "reflector_photon_pass_rays_per_s": mirror_rays_per_s,
        "reflector_rays_per_photon": mirror["rays_lamp_pass"] / mirror["lamp_rays"],
        "glass_rays_per_photon": photon["rays_lamp_pass"] / photon["lamp_rays"],
        "reflector_over_glass_rays_per_s": mirror_rays_per_s / photon_rays_per_s,
        "bvh_s": photon["seconds"]["bvh"],
        "rerender_after_camera_move_s": cached_rerender,
    }
    record.write("speed", figures)
    report = record.read("speed")
    print(f"{report['date']}, {report['machine']}")
    print(f"Embree alone (2 threads)  {raw / 1e6:6.2f} M rays/s, through embreex {raw_rates['embreex'] / 1e6:.2f}")
    print(f"photon pass               {paths_per_s / 1e6:6.2f} M paths/s, {photon_rays_per_s / 1e6:.2f} M rays/s "
          f"({100 * photon_rays_per_s / raw:.0f}% of raw), {photon['seconds']['lamp_pass']:.2f} s for "
          f"{photon['lamp_rays']:,} photons")
    print(f"photon pass, mirror ball  {report['reflector_photon_paths_per_s'] / 1e6:6.2f} M paths/s, "
          f"{mirror_rays_per_s / 1e6:.2f} M rays/s ({100 * mirror_rays_per_s / photon_rays_per_s:.0f}% of the glass's "
          f"per ray; {report['reflector_rays_per_photon']:.2f} rays per photon against "
          f"{report['glass_rays_per_photon']:.2f})")
    print(f"eye pass 640x480 1 spp    {eye['seconds']['eye']:6.2f} s, {eye_rays_per_s / 1e6:.2f} M rays/s "
          f"({100 * eye_rays_per_s / raw:.0f}% of raw)")
    print(f"BVH build                 {photon['seconds']['bvh']:6.2f} s")
    print(f"re-render, camera moved   {cached_rerender:6.2f} s (maps from the cache)")


if __name__ == "__main__":
    main()
