"""A glass ball's caustic on a varnished, a lacquered and a partly metallic
floor: the Principled BSDF's Coat and Metallic, by the add-on and by Cycles.

    .venv/bin/python benchmarks/coated_floor.py [--cycles-samples 1024] [--side-by-side pair.png]

A glass ball (radius 0.5 m, IOR 1.5) 0.1 m above a Principled floor (Base
Color 0.8, Roughness 0.5) under a sun of angle 15 degrees, 30 degrees from
the vertical, in a black world; seen from the front at 160x120. The floor:
plain; under a clear coat (Coat Weight 1, Coat Roughness 0.1); under a
varnish (Coat Weight 1, Coat Roughness 0.2, Coat Tint amber); Metallic 0.3
of a gold Base Color. The sun is wide so that Cycles converges on the
caustic. The add-on renders at its defaults (Beam, 40,000 light rays,
4 samples).

Cycles renders each on the CPU with one diffuse bounce (the floor's light
through the glass: its caustic), 8 glossy and transmission bounces,
refractive and reflective caustics on, no clamp, box filter, no denoising,
at --cycles-samples (blender_scenes.cycles_caustics); a second render of
another seed gives its own noise. Cycles' floor also reflects the ball in
its coat and gloss, which the add-on's receivers do not (docs/limits.md):
the image's figures carry that, the caustic's hardly.

Recorded per floor: the image's mean against the reference, its relative
L2 error, those over the caustic (the pixels outside the ball's silhouette
where the add-on's caustic pass holds a tenth of its peak there), and the
time. Writes benchmarks/results/coated_floor.json.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

import blender_scenes as scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks import record  # noqa: E402
from benchmarks.against_cycles import figures, reference_noise, write_pair  # noqa: E402

PIXX, PIXY = 160, 120
RADIUS, LIFT = 0.5, 0.1
SUN_ANGLE, SUN_TILT = 15.0, 30.0
AMBER = (0.9, 0.65, 0.35)
FLOORS = {
    "plain": {},
    "a clear coat, Coat Roughness 0.1": {"Coat Weight": 1.0, "Coat Roughness": 0.1},
    "an amber varnish, Coat Roughness 0.2": {"Coat Weight": 1.0, "Coat Roughness": 0.2, "Coat Tint": AMBER},
    "Metallic 0.3 of a gold Base Color": {"Metallic": 0.3, "Base Color": (1.0, 0.78, 0.34)},
}


def ball_on_floor(inputs: dict) -> None:
    """The floor of Principled `inputs` (name: value), the ball, the sun and the camera."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    floor = scenes.principled_material("Floor", roughness=0.5)
    shader = next(n for n in floor.node_tree.nodes if n.bl_idname == 'ShaderNodeBsdfPrincipled')
    for name, value in inputs.items():
        shader.inputs[name].default_value = (*value, 1.0) if isinstance(value, tuple) else value
    scenes.add_plane(10.0, floor)
    scenes.add_sphere(RADIUS, (0.0, 0.0, RADIUS + LIFT), scenes.glass_material(), segments=128, rings=64)
    light = bpy.data.lights.new("Sun", 'SUN')
    light.energy, light.angle = 3.0, math.radians(SUN_ANGLE)
    sun = bpy.data.objects.new("Sun", light)
    sun.rotation_euler = Vector((-math.sin(math.radians(SUN_TILT)), 0.0, math.cos(math.radians(SUN_TILT)))
                                ).to_track_quat('Z', 'Y').to_euler()
    bpy.context.scene.collection.objects.link(sun)
    scenes.add_camera((0.6, -3.2, 2.2), target=(0.4, 0.0, 0.2), lens=40.0)
    scenes.set_resolution(PIXX, PIXY)


def ball_pixels() -> np.ndarray:
    """(PIXY, PIXX) bool: the pixels whose view ray meets the ball, 1 cm wider."""
    origin, dirs = scenes.pixel_rays(PIXX, PIXY)
    dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
    to_centre = np.array([0.0, 0.0, RADIUS + LIFT]) - origin
    along = dirs @ to_centre
    return np.sum(to_centre ** 2) - along ** 2 <= (RADIUS + 0.01) ** 2


def cycles(inputs: dict, samples: int, seed: int, folder: str) -> tuple[np.ndarray, float]:
    """Cycles with the caustic's bounces (blender_scenes.cycles_caustics): (image, seconds)."""
    ball_on_floor(inputs)
    return scenes.timed_cycles_caustics(folder, samples, seed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-samples", type=int, default=1024)
    parser.add_argument("--side-by-side", help="a PNG of the add-on's varnished floor beside the reference")
    args = parser.parse_args()
    conftest.registered_addon()
    results, references = {}, {}
    with tempfile.TemporaryDirectory() as folder:
        for name, inputs in FLOORS.items():
            ball_on_floor(inputs)
            image, caustic_pass, seconds = scenes.warm_caustic_render()
            caustic_pass = caustic_pass.sum(axis=-1) * ~ball_pixels()
            caustic = caustic_pass >= 0.1 * caustic_pass.max()
            reference, reference_s = cycles(inputs, args.cycles_samples, 0, folder)
            second, _ = cycles(inputs, args.cycles_samples, 1, folder)
            results[name] = {"ours": figures(image, seconds, reference, caustic),
                             "cycles": {"samples": args.cycles_samples, "seconds": reference_s,
                                        **reference_noise(reference, second, caustic)},
                             "caustic_pixels": int(caustic.sum())}
            references[name] = (image, reference)
    path = record.write("coated_floor", {
        "scene": f"glass ball (IOR 1.5) on a Principled floor under a {SUN_ANGLE:g} degree sun, black world, "
                 f"{PIXX}x{PIXY}",
        "floors": results})
    print(f"wrote {path}")
    for name, r in results.items():
        f, c = r["ours"], r["cycles"]
        print(f"{name}: mean x{f['mean_ratio']:.3f}, L2 {f['relative_l2']:.1%}, caustic mean "
              f"x{f['caustic_mean_ratio']:.3f}, caustic L2 {f['caustic_relative_l2']:.1%} (Cycles' own noise "
              f"{c['caustic_relative_l2_noise']:.1%}), {f['seconds']:.2f} s against {c['seconds']:.1f} s")
    if args.side_by_side:
        write_pair(args.side_by_side, *references["an amber varnish, Coat Roughness 0.2"])


if __name__ == "__main__":
    main()
