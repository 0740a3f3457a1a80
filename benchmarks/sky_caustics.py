"""The sky's light through glass, in the maps: a glass ball on a white floor
under an HDRI sky with a bright window in it and no sun, by the add-on and
by Cycles.

    .venv/bin/python benchmarks/sky_caustics.py [--cycles-samples 2048] [--side-by-side pair.png]

The scene: a smooth glass ball (radius 0.5) on a 20 m white floor, seen
from the front at 120x90, under an HDRI of 128x64 pixels: a sky of radiance
0.6 at the horizon to 1.0 at the zenith, grey ground 0.2, and a window
of radiance 8 spanning 24 x 12 degrees at 40 degrees up, too wide to be
taken out as a sun. The add-on traces the sky as 256 suns
(emission/sky_lamps.py), whose caustic lands in the floor's map: the
window's soft focus beside the ball and the sky's light through it. Cycles
renders it as Compare with Cycles sets it up: one diffuse bounce, the
floor black to the paths that bounced off it once, Filter Glossy 0, box
filter, no denoising; its render of --cycles-samples is the reference, and
a second one of another seed gives its own noise.

Recorded: the add-on at its defaults (Beam, 40,000 light rays, 4 samples)
and at 200,000 light rays, and Cycles at 64 and 256 samples: the image's
mean against the reference's, the relative L2 error over the image and
over the caustic (the pixels where the add-on's caustic pass holds at
least a tenth of its brightest), and the time (the add-on's second render,
its kernels and BVH warm).
Writes benchmarks/results/sky_caustics.json.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks.against_cycles import record_against_cycles  # noqa: E402

PIXX, PIXY = 120, 90
OURS = {"defaults (40,000 light rays)": 40_000, "200,000 light rays": 200_000}
CYCLES_SAMPLES = [64, 256]


def sky_with_a_window(width: int = 128, height: int = 64) -> np.ndarray:
    """(height, width, 4) RGBA rows from the top, in Cycles' equirectangular
    mapping: the sky, the ground and the window the docstring describes."""
    elevation = 90.0 - (np.arange(height) + 0.5) / height * 180.0
    azimuth = ((np.arange(width) + 0.5) / width - 0.5) * 360.0
    sky = np.where(elevation > 0, 0.6 + 0.4 * np.sin(np.radians(np.maximum(elevation, 0.0))), 0.2)
    pixels = np.ones((height, width, 4), dtype=np.float32)
    pixels[..., :3] = sky[:, None, None]
    window = (np.abs(elevation - 40.0) < 6.0)[:, None] & (np.abs(azimuth - 150.0) < 12.0)[None, :]
    pixels[window, :3] = 8.0
    return pixels


def glass_ball_under_a_sky() -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scenes.add_plane(20.0, scenes.diffuse_material())
    scenes.add_sphere(0.5, (0.0, 0.0, 0.5), scenes.glass_material(), segments=96, rings=48)
    bpy.ops.object.shade_smooth()
    _, tree, background = scenes.world_nodes()
    pixels = sky_with_a_window()
    image = bpy.data.images.new("Sky.hdr", pixels.shape[1], pixels.shape[0], float_buffer=True)
    image.pixels.foreach_set(pixels[::-1].ravel())
    environment = tree.nodes.new('ShaderNodeTexEnvironment')
    environment.image = image
    tree.links.new(environment.outputs['Color'], background.inputs['Color'])
    scenes.add_camera((0.0, -3.5, 1.8), target=(0.0, 0.0, 0.35), lens=40.0)
    scenes.set_resolution(PIXX, PIXY)


def ours(lamp_rays: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(image, caustic pass, seconds) of the add-on's render with `lamp_rays`."""
    bpy.context.scene.caustic.lamp_rays = lamp_rays
    return scenes.warm_caustic_render()


def cycles(samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    """Cycles as Compare with Cycles sets it up (main), with `samples` of
    `seed`: (image, seconds)."""
    settings = bpy.context.scene.cycles
    settings.device, settings.samples, settings.seed, settings.use_denoising = 'CPU', samples, seed, False
    settings.pixel_filter_type, settings.filter_width, settings.use_adaptive_sampling = 'BOX', 1.0, False
    clock = time.perf_counter()
    image = scenes.rendered_pixels(folder)[..., :3]
    return image, time.perf_counter() - clock


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=2048)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's render at its defaults beside the reference")
    args = parser.parse_args()
    addon = conftest.registered_addon()
    glass_ball_under_a_sky()
    renders = {name: ours(rays) for name, rays in OURS.items()}
    scene = bpy.context.scene
    addon.comparison.whitted.black_after_a_diffuse_bounce(bpy.data.materials["Floor"])
    addon.comparison.whitted.whitted_settings(addon.export.overrides.Overrides(), scene, scene.caustic.max_depth)
    scene.render.engine = 'CYCLES'
    record_against_cycles(
        "sky_caustics", f"glass ball (radius 0.5) on a white floor under an HDRI sky with a window and no sun, "
                        f"{PIXX}x{PIXY}",
        renders, "defaults (40,000 light rays)", cycles, args.cycles_samples, CYCLES_SAMPLES, args.side_by_side)


if __name__ == "__main__":
    main()
