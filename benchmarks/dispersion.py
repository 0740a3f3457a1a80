"""What dispersion and coloured glass cost, and how exact they are against
Beer-Lambert's closed form and a dispersion-free render.

    .venv/bin/python benchmarks/dispersion.py [--repeats 2]

1. Cost: speed.py's scene (benchmarks/scenes/glass_sphere.py: a smooth
   65k-triangle glass sphere, a point lamp, 1M photons, adaptive) at 320x240, with no dispersion and with an
   Abbe number of 20 in 6 bands; and the same with beams (100k paths).
   Each figure is the best of `repeats` runs.
2. Accuracy: a coloured slab (benchmarks/scenes/slab.py: L = 0.2 m, colour
   (0.8, 0.5, 0.2) at 0.2 m, n = 1.5) under a vertical sun, floor irradiance against Beer-Lambert with
   Fresnel and internal reflections; and the white point, a dispersion-free
   spectral render against the plain one.
3. A picture: a glass ball (V = 15) in a sun, its floor just short of the
   paraxial focus, seen obliquely:
   benchmarks/results/dispersion.png.

Writes benchmarks/results/dispersion.json.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from benchmarks.scenes import slab  # noqa: E402
from benchmarks.scenes.glass_sphere import scene as benchmark_scene  # noqa: E402
from caustic_addon import (Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight,  # noqa: E402
                           render, shapes)
from caustic_addon.cli.image_io import write_image  # noqa: E402

RESULTS = record.RESULTS


def best_seconds(scene: Scene, settings: RenderSettings, repeats: int) -> dict:
    runs = []
    for _ in range(repeats):
        clock = time.perf_counter()
        result = render(scene, settings)
        runs.append(dict(total=time.perf_counter() - clock, **result.stats["seconds"]))
    return {key: round(min(r[key] for r in runs), 3) for key in runs[0]}


def cost(repeats: int) -> dict:
    out = {}
    for density, photons in (("adaptive", 1_000_000), ("beam", 100_000)):
        for abbe in (math.inf, 20.0):
            scene = benchmark_scene()
            scene.camera.pixx, scene.camera.pixy = 320, 240
            scene.objects[1].material.abbe = abbe
            settings = RenderSettings(lamp_rays=photons, density=density, spp=1)
            out[f"{density}, abbe {abbe}"] = best_seconds(scene, settings, repeats)
    return out


def top_camera(half_width: float, pixels: int) -> Camera:
    matrix = np.eye(4)
    matrix[2, 3] = 20.0
    return Camera(matrix, pixx=pixels, pixy=pixels, kind="ORTHO", ortho_scale=2 * half_width)


def slab_error() -> dict:
    measured, exact = slab.measured_irradiance(1_000_000), slab.exact_irradiance()
    return {"measured_w_m2": measured.round(3).tolist(), "exact_w_m2": exact.round(3).tolist(),
            "relative_error": (measured / exact - 1).round(5).tolist()}


def white_point() -> dict:
    def ball(abbe):
        return Scene([Object("Floor", shapes.plane(8.0), Diffuse(albedo=1.0)),
                      Object("Glass", shapes.uv_sphere(1.0, (0, 0, 1.5), 128, 64), Dielectric(1.5, abbe=abbe))],
                     [SunLight((0, 0, -1), 1000.0)], top_camera(2.0, 8))
    settings = RenderSettings(lamp_rays=1_000_000, spp=1, density="adaptive")
    plain = np.array(render(ball(math.inf), settings).stats["flux_landed_w"])
    spectral = np.array(render(ball(1e12), settings).stats["flux_landed_w"])
    return {"flux_landed_plain_w": plain.round(4).tolist(), "flux_landed_spectral_w": spectral.round(4).tolist(),
            "relative_difference": (spectral / plain - 1).round(5).tolist()}


def picture() -> str:
    """The caustic under the ball, seen obliquely past it; direct light is
    left out so the caustic's colours show, and k = 256 photons per estimate
    keep the bands' colour noise near 1.2 / sqrt(256) = 8%."""
    scene = Scene([Object("Floor", shapes.plane(2.0), Diffuse(albedo=0.8)),
                   Object("Glass", shapes.uv_sphere(1.0, (0, 0, 1.45), 256, 128), Dielectric(1.5, abbe=15.0))],
                  [SunLight((0, 0, -1), 1000.0)],
                  Camera.look_at((0, -2.2, 1.0), (0, 0, 0), pixx=480, pixy=270, fov=math.radians(12.0)))
    result = render(scene, RenderSettings(lamp_rays=4_000_000, spp=4, k_nearest=256, density="adaptive"))
    caustic = result.passes["caustic"]
    image = np.ones(caustic.shape[:2] + (4,), dtype=np.float32)
    luminance = caustic @ np.array([0.2126, 0.7152, 0.0722])
    scale = np.percentile(luminance, 90)
    image[..., :3] = caustic / (scale + luminance)[..., None]  # Reinhard on luminance: hue kept
    path = RESULTS / "dispersion.png"
    write_image(path, image)
    return str(path.relative_to(RESULTS.parent.parent))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    figures = {"cost_seconds": cost(args.repeats), "slab": slab_error(), "white_point": white_point(),
               "picture": picture()}
    print(json.dumps(figures, indent=2))
    record.write("dispersion", figures)


if __name__ == "__main__":
    main()
