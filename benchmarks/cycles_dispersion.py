"""What Cycles does with a Principled BSDF's dispersion, and the engine's
spectrum against it and against the closed form, on
benchmarks/scenes/prism.py's prism.

    .venv/bin/python benchmarks/cycles_dispersion.py [--samples 256]

Blender 5.3's Principled BSDF has OpenPBR's Transmission Dispersion Scale
(0..1) and Abbe Number; the Cycles source this project mirrors has no
dispersion code, so this measures what Cycles renders. Rather than its noisy
caustic, Cycles renders the view back through the prism: a camera below the
exit face looks up through it at a world that is black but for a thin stripe
(STRIPE wide) in the direction the sun comes from. By reciprocity a pixel is
lit where light from the sun leaves the prism along the pixel's ray
reversed, so a lit pixel's angle is the exit angle of some wavelength's
light (prism.exit_angle), and its colour says which wavelength. For each
(scale, Abbe number):

- the Cauchy fit: each lit pixel's index n from its angle (prism.exit_angle
  inverted), its wavelength from its colour (the nearest hue of the CIE 1931
  functions in linear Rec.709, signed; between 470 and 580 nm, FIT_NM),
  and n = A + B / lambda^2 fitted through them, weighted by brightness:
  the Abbe number (n_d - 1) / (n_F - n_C) and n_d that Cycles renders, and
  how far the colour's wavelength is from the fit's (RMS nm);
- each channel's centroid exit angle, Cycles' against the closed form of
  the same colour model (prism.exit_angle over 360-830 nm, each wavelength
  weighted by its signed Rec.709 colour), and the engine's six bands
  (clipped colour weights; the engine's caustic matches that closed form,
  tests/engine/test_dispersion.py) at the Abbe number the add-on reads.

Also the engine's own render of the prism's spectrum on the floor: each
channel's centroid against the closed form (prism.centroids).
Writes benchmarks/results/cycles_dispersion.json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

import bpy  # noqa: E402
from mathutils import Matrix  # noqa: E402

from benchmarks import record  # noqa: E402
from benchmarks.scenes import prism  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.optics.dispersion import LAMBDA_C, LAMBDA_D, LAMBDA_F, cauchy_ior  # noqa: E402
from caustic_addon.optics.spectrum import XYZ_TO_REC709, bands, cie_xyz  # noqa: E402

STRIPE = math.radians(0.05)  # half-width of the world's stripe of light
FOV, WIDTH, HEIGHT = math.radians(10.0), 500, 8
CAMERA_BELOW = 1.5  # metres below the prism's lowest point
# (Transmission Dispersion Scale, Abbe Number)
CASES = ((0.0, 20.0), (1.0, 20.0), (1.0, 40.0), (0.5, 20.0), (0.25, 10.0), (1.0, 0.0))
# where a colour's hue pins its wavelength down: beyond, hue changes slowly
# (violet, red) and the fit's Abbe number drifts (2.5% low from 440-600 nm)
FIT_NM = (470.0, 580.0)


def _glass(scale: float, abbe: float):
    material = bpy.data.materials.new("Glass")
    nodes = material.node_tree.nodes
    shader = nodes["Principled BSDF"]
    shader.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    shader.inputs["Transmission Weight"].default_value = 1.0
    shader.inputs["Roughness"].default_value = 0.0
    shader.inputs["IOR"].default_value = prism.IOR
    shader.inputs["Transmission Dispersion Scale"].default_value = scale
    shader.inputs["Transmission Dispersion Abbe Number"].default_value = abbe
    return material


def _stripe_world():
    """Black but for directions within STRIPE of the sun's, in the x-z plane."""
    world = bpy.data.worlds.new("Stripe")
    nodes, links = world.node_tree.nodes, world.node_tree.links
    nodes.clear()
    split = nodes.new('ShaderNodeSeparateXYZ')
    links.new(nodes.new('ShaderNodeTexCoord').outputs['Generated'], split.inputs[0])
    angle = nodes.new('ShaderNodeMath')
    angle.operation = 'ARCTAN2'
    links.new(split.outputs['Z'], angle.inputs[0])
    links.new(split.outputs['X'], angle.inputs[1])
    near = nodes.new('ShaderNodeMath')
    near.operation = 'COMPARE'
    sun = prism.sun_direction()
    near.inputs[1].default_value = math.atan2(-sun[1], -sun[0])
    near.inputs[2].default_value = STRIPE
    links.new(angle.outputs[0], near.inputs[0])
    background = nodes.new('ShaderNodeBackground')
    links.new(near.outputs[0], background.inputs['Strength'])
    links.new(background.outputs[0], nodes.new('ShaderNodeOutputWorld').inputs['Surface'])
    return world


def build(scale: float, abbe: float) -> None:
    """An empty file with the prism of `scale` and `abbe`, the stripe world
    and the camera below the exit face, looking straight up (its image x
    along the scene's x)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mesh_data = prism.prism_mesh()
    mesh = bpy.data.meshes.new("Prism")
    mesh.from_pydata(mesh_data.vertices.tolist(), [], mesh_data.triangles.tolist())
    mesh.materials.append(_glass(scale, abbe))
    body = bpy.data.objects.new("Prism", mesh)
    scene.collection.objects.link(body)
    scene.world = _stripe_world()
    _, right, apex = prism.outline()
    camera = bpy.data.cameras.new("Camera")
    camera.sensor_fit, camera.angle = 'HORIZONTAL', FOV
    eye = bpy.data.objects.new("Camera", camera)
    matrix = np.diag([1.0, -1.0, -1.0, 1.0])
    matrix[:3, 3] = (0.5 * (right[0] + apex[0]), 0.0, prism.DROP - CAMERA_BELOW)
    eye.matrix_world = Matrix(matrix.tolist())
    scene.collection.objects.link(eye)
    scene.camera = eye
    render_settings, cycles = scene.render, scene.cycles
    render_settings.engine = 'CYCLES'
    render_settings.resolution_x, render_settings.resolution_y = WIDTH, HEIGHT
    render_settings.resolution_percentage = 100
    render_settings.use_file_extension = False
    render_settings.image_settings.file_format = 'OPEN_EXR'
    render_settings.image_settings.color_depth = '32'
    render_settings.threads_mode, render_settings.threads = 'FIXED', 2
    scene.view_settings.view_transform = 'Standard'
    cycles.device = 'CPU'
    cycles.use_denoising = cycles.use_adaptive_sampling = False
    cycles.pixel_filter_type, cycles.filter_width = 'BOX', 1.0
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.max_bounces = cycles.transmission_bounces = 16


def cycles_columns(samples: int, folder: str) -> tuple[np.ndarray, float]:
    """((WIDTH,3) the image's mean linear RGB per column, seconds)."""
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.render.filepath = os.path.join(folder, "prism.exr")
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - start
    image = bpy.data.images.load(scene.render.filepath)
    pixels = np.empty(WIDTH * HEIGHT * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    os.remove(scene.render.filepath)
    return pixels.reshape(HEIGHT, WIDTH, 4)[:, :, :3].mean(axis=0).astype(np.float64), seconds


def column_exit_angles() -> np.ndarray:
    """(WIDTH,) exit angle (radians) of the light each column sees: its ray reversed."""
    focal = 0.5 * WIDTH / math.tan(0.5 * FOV)
    return -np.arctan((np.arange(WIDTH) + 0.5 - 0.5 * WIDTH) / focal)


def signed_colours(wavelengths: np.ndarray) -> np.ndarray:
    """(n,3) linear Rec.709 of the CIE 1931 functions, negative parts kept."""
    return cie_xyz(wavelengths) @ XYZ_TO_REC709.T


def cauchy_fit(columns: np.ndarray) -> dict:
    """Cauchy's law fitted through the lit columns: their index from their
    angle, their wavelength from their colour (FIT_NM only)."""
    table = np.linspace(1.40, 1.65, 5001)
    angles = np.array([prism.exit_angle(n) for n in table])  # decreasing in n
    index = np.interp(column_exit_angles(), angles[::-1], table[::-1])
    grid = np.arange(380.0, 780.01, 0.25)
    hues = signed_colours(grid)
    hues /= np.linalg.norm(hues, axis=1)[:, None]
    brightness = np.linalg.norm(columns, axis=1)
    wavelength = grid[np.argmax((columns / np.maximum(brightness, 1e-30)[:, None]) @ hues.T, axis=1)]
    used = (brightness > 0.2 * brightness.max()) & (wavelength >= FIT_NM[0]) & (wavelength <= FIT_NM[1])
    if used.sum() < 10:
        return dict(columns=int(used.sum()))
    design = np.c_[np.ones(used.sum()), wavelength[used] ** -2.0]
    sqrt_w = np.sqrt(brightness[used])
    (a, b), *_ = np.linalg.lstsq(design * sqrt_w[:, None], index[used] * sqrt_w, rcond=None)
    n_d = a + b / LAMBDA_D ** 2
    from_index = np.sqrt(b / (index[used] - a))
    return dict(columns=int(used.sum()), abbe=round(float((n_d - 1) / (b * (LAMBDA_F ** -2 - LAMBDA_C ** -2))), 3),
                ior_d=round(float(n_d), 5),
                rms_nm=round(float(np.sqrt(np.average((from_index - wavelength[used]) ** 2,
                                                      weights=brightness[used]))), 2))


def centroid_degrees(angles: np.ndarray, weights: np.ndarray) -> list[float]:
    """(3,) each channel's weighted mean of `angles (n,)`, degrees."""
    return np.degrees((weights * angles[:, None]).sum(axis=0) / weights.sum(axis=0)).round(4).tolist()


def closed_forms(abbe: float) -> dict:
    """Each channel's centroid exit angle (degrees): Cycles' colour model
    (signed, 360-830 nm) and the engine's six bands."""
    lam = np.arange(360.0, 830.01, 0.5)
    angle = np.array([prism.exit_angle(float(n)) for n in cauchy_ior(prism.IOR, abbe, lam)])
    six = bands(6)
    band_angle = np.array([prism.exit_angle(float(n)) for n in cauchy_ior(prism.IOR, abbe, six.wavelengths)])
    return dict(signed_cie=centroid_degrees(angle, signed_colours(lam)),
                engine_bands=centroid_degrees(band_angle, six.weights))


def engine_floor(abbe: float) -> dict:
    """The engine's render of the spectrum on the floor, each channel's
    centroid x against the closed form (mm)."""
    floor = render(prism.scene(abbe), RenderSettings(lamp_rays=120_000, density="beam", spp=1, max_depth=2))
    floor = floor.maps["Floor"]
    x, y = (a.ravel() for a in np.meshgrid(np.linspace(0.0, 1.3, 2601), np.linspace(-1.0, 1.0, 21)))
    irradiance = floor.irradiance_at(floor.chart.coords(None, None, None, np.c_[x, y, np.zeros(len(x))]))
    measured = (irradiance * x[:, None]).sum(axis=0) / irradiance.sum(axis=0)
    six = bands(6)
    exact = prism.centroids(abbe, six.wavelengths, six.weights)
    return dict(measured_mm=(1000 * measured).round(2).tolist(), exact_mm=(1000 * exact).round(2).tolist(),
                red_blue_spread_mm=dict(measured=round(1000 * float(measured[0] - measured[2]), 2),
                                        exact=round(1000 * float(exact[0] - exact[2]), 2)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=256)
    args = parser.parse_args()
    folder = tempfile.mkdtemp()
    cases = []
    for scale, abbe in CASES:
        build(scale, abbe)
        columns, seconds = cycles_columns(args.samples, folder)
        expected = abbe / scale if scale > 0 and abbe > 0 else math.inf
        angles = column_exit_angles()
        measured = centroid_degrees(angles, columns)
        case = dict(scale=scale, abbe_number=abbe, expected_abbe=expected if math.isfinite(expected) else None,
                    seconds=round(seconds, 2), cycles_fit=cauchy_fit(columns) if math.isfinite(expected) else None,
                    centroid_exit_deg=dict(cycles=measured),
                    cycles_red_blue_deg=round(measured[0] - measured[2], 4))
        if math.isfinite(expected):
            case["centroid_exit_deg"].update(closed_forms(expected))
            case["engine_red_blue_deg"] = round(case["centroid_exit_deg"]["engine_bands"][0]
                                                - case["centroid_exit_deg"]["engine_bands"][2], 4)
        print(json.dumps(case), flush=True)
        cases.append(case)
    result = dict(blender=bpy.app.version_string, samples=args.samples, prism=dict(apex_deg=math.degrees(prism.APEX),
                                                   incidence_deg=math.degrees(prism.INCIDENCE), ior=prism.IOR),
                  cases=cases, engine_floor_abbe_20=engine_floor(20.0))
    record.write("cycles_dispersion", result)
    print(json.dumps(result["engine_floor_abbe_20"]))


if __name__ == "__main__":
    main()
