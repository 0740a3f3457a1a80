"""caustic.render on real Blender scenes, checked against geometry and against Cycles."""

import math
import os
import threading

import bpy
import numpy as np
import pytest
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

import blender_scenes as scenes


def pixel_at(point):
    """(row from the top, column) of the pixel the scene camera sees `point` in."""
    scene = bpy.context.scene
    x, y, _ = world_to_camera_view(scene, scene.camera, Vector(point))
    return int((1.0 - y) * scene.render.resolution_y), int(x * scene.render.resolution_x)


def line_clears_sphere(start, end, centre, radius):
    """Whether the segment start-end passes outside the sphere."""
    start, end, centre = (np.asarray(v, dtype=float) for v in (start, end, centre))
    d = end - start
    t = np.clip(np.dot(centre - start, d) / np.dot(d, d), 0.0, 1.0)
    return np.linalg.norm(start + t * d - centre) > radius


@pytest.mark.parametrize("density, lamp_rays", [('ADAPTIVE', 100_000), ('BEAM', 40_000)],
                         ids=["adaptive", "beam-the-default"])
def test_caustic_under_the_ball_and_dark_shadow_ring(density, lamp_rays):
    parts = scenes.ball_lens_scene(160, 120, lamp_rays=lamp_rays)
    bpy.context.scene.caustic.density = density
    assert bpy.ops.caustic.render() == {'FINISHED'}
    image = scenes.pixels_of("Caustic Render")
    assert image.shape == (120, 160, 4)

    ball, lamp, camera = parts["ball"], parts["lamp"], parts["camera"]
    radius, centre = 0.5, np.array(ball.location)
    lamp_z = lamp.location.z
    # The shadow disc on the floor: the cone from the lamp tangent to the ball.
    shadow_radius = lamp_z * math.tan(math.asin(radius / (lamp_z - centre[2])))
    angles = np.radians(np.arange(0, 360, 20))

    def visible_points(r):
        points = [(r * math.cos(a), r * math.sin(a), 0.0) for a in angles]
        return [p for p in points if line_clears_sphere(camera.location, p, centre, 1.1 * radius)]

    ring, lit = visible_points(0.75 * shadow_radius), visible_points(1.5 * shadow_radius)
    assert len(ring) >= 3 and len(lit) >= 3
    assert line_clears_sphere(camera.location, (0, 0, 0), centre, radius)

    def brightness(points):
        return np.mean([image[pixel_at(p)][:3].mean() for p in points])

    caustic, shadow_ring, unshadowed = brightness([(0.0, 0.0, 0.0)]), brightness(ring), brightness(lit)
    print(f"caustic {caustic:.3g}, shadow ring {shadow_ring:.3g}, unshadowed floor {unshadowed:.3g}")
    assert caustic > 5.0 * unshadowed
    assert shadow_ring < 0.5 * unshadowed
    assert np.all(np.isfinite(image)) and np.all(image[..., 3] == 1.0)


def test_output_image_is_float_linear_at_the_render_resolution():
    scenes.ball_lens_scene(100, 80, lamp_rays=20_000, segments=32, rings=16)
    bpy.context.scene.render.resolution_percentage = 50
    bpy.ops.caustic.render()
    image = bpy.data.images["Caustic Render"]
    assert tuple(image.size) == (50, 40)
    assert image.is_float
    assert image.colorspace_settings.name == "Linear Rec.709"
    props = bpy.context.window_manager.caustic
    assert props.last_lamp_rays == 20_000 and props.last_seconds > 0 and props.progress == 1.0


def cycles_render(tmp_path, samples):
    """(h,w,4) top row first: Cycles on the CPU, box filter of one pixel, no denoiser, via an EXR."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = 'BOX'
    scene.cycles.filter_width = 1.0
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.render.filepath = os.path.join(tmp_path, "cycles.exr")
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(h, w, 4)[::-1]


def test_direct_light_on_a_diffuse_floor_matches_cycles(tmp_path):
    """Lamp units: a point lamp of P W on a Lambertian floor of albedo 0.8, no glass."""
    scenes.add_plane(4.0, scenes.diffuse_material(color=(0.8, 0.6, 0.4)))
    lamp = scenes.add_point_light((0.6, -0.4, 2.0), 300.0)
    lamp.data.color = (1.0, 0.9, 0.8)
    scenes.add_camera((0.0, -2.5, 3.0), target=(0.0, 0.0, 0.0), lens=40.0)
    scenes.set_resolution(64, 48)
    bpy.context.scene.caustic.spp = 16
    assert bpy.ops.caustic.render() == {'FINISHED'}
    ours = scenes.pixels_of("Caustic Render")
    reference = cycles_render(str(tmp_path), samples=64)

    # The floor's inner pixels: fully covered in Cycles, and their neighbours too.
    covered = reference[..., 3] > 0.999
    inner = covered.copy()
    inner[1:-1, 1:-1] &= covered[:-2, 1:-1] & covered[2:, 1:-1] & covered[1:-1, :-2] & covered[1:-1, 2:]
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    assert inner.sum() > 0.3 * inner.size
    ratio = ours[..., :3][inner].mean(axis=0) / reference[..., :3][inner].mean(axis=0)
    print("direct light, caustic render / Cycles per channel:", ratio)
    assert np.all(np.abs(ratio - 1.0) < 0.02)


def test_glossy_ring_casts_a_visible_caustic():
    """The same ring rendered as a mirror (Glossy BSDF, auto) and as a diffuse
    receiver: direct light, computed exactly, is the same on the floor; the
    mirror adds its caustic around the cusp at x = -0.136."""
    parts = scenes.ring_scene()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    mirror = scenes.pixels_of("Caustic Render")[..., :3].mean(axis=2)
    parts["ring"].caustic.role = 'RECEIVER'
    assert bpy.ops.caustic.render() == {'FINISHED'}
    matte = scenes.pixels_of("Caustic Render")[..., :3].mean(axis=2)

    row, col = pixel_at((-0.136, 0.0, 0.0))
    patch = np.s_[row - 2:row + 3, col - 2:col + 3]
    assert mirror[patch].max() > 2.0 * matte[patch].max()
    far_row, far_col = pixel_at((1.2, 0.8, 0.0))
    assert mirror[far_row, far_col] == pytest.approx(matte[far_row, far_col], rel=1e-4)
    assert matte[far_row, far_col] > 0.0


def caustic_across_x(xs):
    """Render, and return the image's RGB at floor points (x, 0, 0) for `xs`."""
    assert bpy.ops.caustic.render() == {'FINISHED'}
    image = scenes.pixels_of("Caustic Render")
    return np.array([image[pixel_at((x, 0.0, 0.0))][:3] for x in xs])


def test_dispersion_colours_the_caustic_rim():
    """The floor is short of the paraxial focus, so the caustic is a spot
    near the axis inside the ring where marginal rays cross. Blue, refracted
    more, focuses nearer the glass and gathers into the centre; red is left
    spread out to the rim. Without dispersion every pixel is grey (R = B to
    rounding: one band is traced). Seen from low down across the caustic."""
    parts = scenes.ball_lens_scene(160, 120, lamp_rays=1_000_000)
    bpy.context.scene.caustic.spp = 1
    scenes.add_camera((0.0, -2.0, 0.3), target=(0.0, 0.0, 0.0), lens=100.0)
    xs = np.linspace(-0.08, 0.08, 33)
    plain = caustic_across_x(xs)
    lit = plain[:, 1] > 0.05 * plain[:, 1].max()
    assert lit.sum() >= 9
    np.testing.assert_allclose(plain[lit, 0], plain[lit, 2], rtol=1e-5)

    parts["ball"].caustic.abbe = 10.0
    spectral = caustic_across_x(xs)
    rim = lit & (np.abs(xs) > 0.6 * np.abs(xs[lit]).max())
    centre = lit & (np.abs(xs) < 0.2 * np.abs(xs[lit]).max())
    red_to_blue = {name: spectral[where, 0].sum() / spectral[where, 2].sum()
                   for name, where in (("rim", rim), ("centre", centre))}
    print("red / blue:", red_to_blue)
    assert red_to_blue["centre"] < 0.8 and red_to_blue["rim"] > 1.5


def test_the_passes_are_images_of_their_own_that_sum_to_the_render():
    scenes.ball_lens_scene(32, 24, lamp_rays=5_000, segments=16, rings=8)
    bpy.context.scene.caustic.ambient = (0.05, 0.05, 0.05)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    passes = {name: scenes.pixels_of(f"Caustic Render {name}") for name in ("Direct", "Caustic", "Ambient")}
    for name, pixels in passes.items():
        assert pixels[..., :3].max() > 0.0, name
        assert bpy.data.images[f"Caustic Render {name}"].packed_file is not None
    total = passes["Direct"] + passes["Caustic"] + passes["Ambient"]
    np.testing.assert_allclose(total[..., :3], scenes.pixels_of("Caustic Render")[..., :3], rtol=1e-5, atol=1e-7)


def test_a_render_started_while_the_kernels_compile_says_so(addon, reports):
    """The kernels compile on a thread when the add-on is enabled; a render
    started before it ends says that it waits for a one-time compile, and
    then renders."""
    scenes.ball_lens_scene(32, 24, lamp_rays=2_000)
    compile_going_on = threading.Event()
    thread = threading.Thread(target=compile_going_on.wait)
    thread.start()
    kept, addon.jobs.kernels._warming = addon.jobs.kernels._warming, thread
    try:
        reports()
        assert bpy.ops.caustic.render() == {'FINISHED'}
        assert "compiling the engine's kernels, once" in reports()
    finally:
        compile_going_on.set()
        thread.join()
        addon.jobs.kernels._warming = kept
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert "compiling" not in reports()
