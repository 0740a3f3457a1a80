"""caustic.compare_cycles: Cycles renders the same view, its caustics
path-traced from lamps with a size and by MNEE from lamps without; the
error is measured where the reference holds the caustic, and where it does
not the report says so with the share it lacks; every render setting is
left as it was."""

import math
import time

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from snapshot import material_state, rna


def render_state():
    """Every RNA property of the render settings, Cycles' settings, and the
    objects' and lamps' Cycles settings."""
    scene = bpy.context.scene
    return {
        "render": rna(scene.render),
        "cycles": rna(scene.cycles),
        "view_settings": rna(scene.view_settings),
        "objects": {ob.name: rna(ob.cycles) for ob in bpy.data.objects},
        "visibility": {ob.name: (ob.visible_camera, ob.visible_shadow, ob.hide_render) for ob in bpy.data.objects},
        "lights": {light.name: rna(light.cycles) for light in bpy.data.lights},
        "world": rna(scene.world.cycles) if scene.world is not None else None,
        "materials": {material.name: material_state(material) for material in bpy.data.materials},
        "images": sorted(image.name for image in bpy.data.images),
    }


def test_compare_restores_every_setting_and_stores_the_images():
    scenes.ball_lens_scene(64, 48, lamp_rays=50_000)
    scene = bpy.context.scene
    # Settings a user might have that the comparison has to change and put back.
    scene.render.engine = 'BLENDER_WORKBENCH'
    scene.render.filepath = "//renders/frame_"
    scene.render.image_settings.file_format = 'PNG'
    scene.render.image_settings.color_depth = '16'
    scene.render.image_settings.color_mode = 'RGB'
    scene.render.film_transparent = True
    scene.render.use_border = True
    scene.cycles.samples = 7
    scene.cycles.use_denoising = True
    scene.cycles.filter_width = 2.5
    scene.caustic.cycles_samples = 16
    before = render_state()

    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}

    after = render_state()
    images = set(after.pop("images")) - set(before.pop("images"))
    assert images == {"Caustic Render", "Caustic Render Direct", "Caustic Render Caustic", "Caustic Render Ambient",
                      "Cycles Reference", "Difference"}
    assert after == before
    ours = np.array(bpy.data.images["Caustic Render"].pixels[:]).reshape(48, 64, 4)
    reference = np.array(bpy.data.images["Cycles Reference"].pixels[:]).reshape(48, 64, 4)
    difference = np.array(bpy.data.images["Difference"].pixels[:]).reshape(48, 64, 4)
    assert np.allclose(difference[..., :3], np.abs(ours - reference)[..., :3], atol=1e-5)
    assert reference[..., :3].max() > 0.1 and tuple(bpy.data.images["Cycles Reference"].size) == (64, 48)

    # a point lamp through smooth glass: the reference is MNEE's, and no error is measured over the caustics
    props = bpy.context.window_manager.caustic
    assert props.cycles_seconds > 0 and props.last_seconds > 0
    assert props.cycles_reference == 'MNEE' and math.isnan(props.cycles_relative_l2) and props.cycles_psnr_outside
    assert math.isfinite(props.cycles_psnr)


def test_compare_says_cycles_cannot_render_a_mirrors_caustic(reports):
    """A smooth mirror's caustic from a point lamp is missing from Cycles'
    reference, and the warning says so; a rough one's Cycles path-traces
    (it samples the lamp at the mirror), and it says nothing."""
    scenes.ring_scene(32, 24, lamp_rays=50_000)
    bpy.context.scene.caustic.cycles_samples = 4
    reports()
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    said = reports()
    assert ("Cycles cannot path-trace the caustics of lamps without a size, 'Lamp' (Radius 0): off the smooth "
            "reflectors 'Ring' it has none (MNEE cannot solve for mirrors)" in said)
    # Cycles' reference holds none of it: what it has over the caustics, less its render without caustics, is noise
    assert "of the caustic render's caustic light: it lacks" in said
    assert bpy.context.window_manager.caustic.cycles_caustic_ratio > 10.0
    bpy.data.materials["Chrome"].node_tree.nodes["Glossy BSDF"].inputs["Roughness"].default_value = 0.3
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    assert "lacks" not in reports() and bpy.context.window_manager.caustic.cycles_reference == 'PATH_TRACED'


def tick_to_the_end(runner):
    """What the modal operator's timer does: tick until the run is over."""
    deadline = time.monotonic() + 120.0
    while runner.tick() and time.monotonic() < deadline:
        time.sleep(0.01)


def user_scene(lamp_rays):
    scenes.ball_lens_scene(32, 24, lamp_rays=lamp_rays, segments=32, rings=16)
    scene = bpy.context.scene
    # Blender fills in an image format's colour spaces when a format is first set: set one, as a user has
    scene.render.image_settings.file_format = 'PNG'
    scene.caustic.cycles_samples = 4
    return scene.caustic


def test_compare_runs_step_by_step_as_the_modal_operator_does(addon):
    """The caustics on a worker thread, then Cycles started as F12 starts it
    (in the background Blender renders it before the call returns), then
    the images; every setting as it was."""
    user_scene(20_000)
    before = render_state()
    comparison = addon.comparison.run.Comparison(bpy.context)
    runner = comparison.runner
    assert runner.tick() and runner.step == "caustics" and runner.job is comparison.caustics
    tick_to_the_end(runner)
    assert runner.done == ["caustics", "cycles", "cycles without caustics"]
    assert runner.error is None and not runner.cancelled
    after = render_state()
    assert set(after.pop("images")) - set(before.pop("images")) >= {"Caustic Render", "Cycles Reference",
                                                                     "Difference"}
    assert after == before
    assert scenes.pixels_of("Cycles Reference")[..., :3].max() > 0.1
    assert bpy.context.window_manager.caustic.cycles_seconds > 0


@pytest.mark.parametrize("stopped_in", ["caustics", "cycles"])
def test_esc_leaves_no_half_result_and_every_setting_as_it_was(addon, stopped_in):
    """Esc in either half: nothing is written (no Caustic Render without its
    reference), the figures stay, the settings Cycles needed are put back."""
    props = user_scene(3_000_000 if stopped_in == "caustics" else 20_000)
    props = bpy.context.window_manager.caustic
    before, figures = render_state(), (props.cycles_seconds, props.last_seconds)
    runner = addon.comparison.run.Comparison(bpy.context).runner
    runner.tick()
    while runner.step != stopped_in:
        runner.tick()
        time.sleep(0.01)
    runner.stop()
    tick_to_the_end(runner)
    assert runner.cancelled and runner.error is None and runner.done == ([] if stopped_in == "caustics" else
                                                                         ["caustics"])
    assert render_state() == before and (props.cycles_seconds, props.last_seconds) == figures


def test_compare_with_bake_while_rendering_on_bakes_nothing():
    """The reference is Cycles' own light: Bake While Rendering stays out of its render."""
    scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
    scene = bpy.context.scene
    scene.caustic.cycles_samples, scene.caustic.use_bake_on_render = 4, True
    floor = material_state(bpy.data.objects["Floor"].active_material)
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    assert scene.caustic.use_bake_on_render and not bpy.data.node_groups
    assert material_state(bpy.data.objects["Floor"].active_material) == floor
    assert not any(image.name.startswith("Caustic Map") for image in bpy.data.images)


def sized_lamp_scene(radius=0.2, samples=1024):
    """The half-scale ball lens under a sphere lamp of `radius`, the camera
    close over the caustic (about 200 of its 64 x 48 pixels)."""
    parts = scenes.ball_lens_scene(64, 48, lamp_rays=100_000)
    parts["lamp"].data.shadow_soft_size = radius
    camera = parts["camera"]
    camera.data.lens, camera.location = 60.0, (0.0, -1.6, 1.1)
    camera.rotation_euler = (-camera.location).to_track_quat('-Z', 'Y').to_euler()
    bpy.context.scene.caustic.cycles_samples = samples
    return parts


def compare(addon, caustic_scale=1.0):
    """Compare step by step, the caustic render's caustic pass scaled by
    `caustic_scale` (and its image with it) before the figures are taken."""
    comparison = addon.comparison.run.Comparison(bpy.context)
    runner = comparison.runner
    while runner.step == "caustics" and runner.tick():
        time.sleep(0.01)
    result = comparison.caustics.result
    result.image[..., :3] += (caustic_scale - 1.0) * result.passes["caustic"]
    result.passes["caustic"] *= caustic_scale
    tick_to_the_end(runner)
    assert runner.error is None and not runner.cancelled
    return comparison


def without_noise(props):
    """The relative L2 over the caustics with the reference's own noise taken out, squared."""
    return props.cycles_relative_l2 ** 2 - props.cycles_noise ** 2


def test_a_sized_lamps_caustic_is_path_traced_and_a_wrong_caustic_measures_wrong(addon):
    """A sphere lamp through a glass ball: Cycles path-traces the caustic,
    so its reference is far brighter there than its render without
    caustics, and holds as much caustic light as the caustic render within
    its noise. Half the caustic, or a wrong IOR, makes the error over the
    caustics grow well past the reference's noise (and the PSNR is then
    over the whole image), where MNEE's reference (a quarter of the
    caustic) rewarded a dimmer caustic."""
    sized_lamp_scene()
    props = bpy.context.window_manager.caustic
    right = compare(addon)
    assert props.cycles_reference == 'PATH_TRACED' and not right.sources.mnee
    region = addon.comparison.metrics.caustic_region(right.caustics.result.passes["caustic"])
    reference = scenes.pixels_of("Cycles Reference")[..., :3].sum(axis=-1)[region].sum()
    without = right.references["cycles without caustics"][..., :3].sum(axis=-1)[region].sum()
    figures = (props.cycles_relative_l2, props.cycles_noise, props.cycles_caustic_ratio, props.cycles_caustic_noise)
    print("right: relative L2 %.3f, noise %.3f, caustic light %.3f +- %.3f" % figures)
    assert reference > 5.0 * without
    assert abs(props.cycles_caustic_ratio - 1.0) < 4.0 * props.cycles_caustic_noise + 0.05
    assert without_noise(props) < 0.1 ** 2
    right_error = without_noise(props)

    compare(addon, caustic_scale=0.5)
    print("half: relative L2 %.3f, noise %.3f, caustic light %.3f +- %.3f" % (
        props.cycles_relative_l2, props.cycles_noise, props.cycles_caustic_ratio, props.cycles_caustic_noise))
    assert abs(props.cycles_caustic_ratio - 0.5) < 4.0 * props.cycles_caustic_noise + 0.03
    assert without_noise(props) > right_error + 0.3 ** 2 and not props.cycles_psnr_outside

    bpy.data.objects["Ball"].caustic.use_ior, bpy.data.objects["Ball"].caustic.ior = True, 1.3
    compare(addon)
    print("IOR 1.3: relative L2 %.3f, noise %.3f, caustic light %.3f +- %.3f" % (
        props.cycles_relative_l2, props.cycles_noise, props.cycles_caustic_ratio, props.cycles_caustic_noise))
    assert without_noise(props) > right_error + 0.3 ** 2 and not props.cycles_psnr_outside


def test_a_noisy_reference_is_said_to_be_too_noisy_to_judge_the_caustics(reports):
    """At 4 samples the path-traced caustic is mostly noise: the report says
    so, and its PSNR leaves the caustics out."""
    sized_lamp_scene(samples=4)
    reports()
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    said = reports()
    assert "The Cycles Reference is too noisy to judge the caustics" in said
    assert "raise Cycles Samples (now 4)" in said and "outside the caustics" in said
    assert bpy.context.window_manager.caustic.cycles_psnr_outside


def test_a_point_lamps_compare_says_its_reference_lacks_the_caustic_with_the_share(reports):
    """A point lamp (Radius 0) through a glass ball: only MNEE renders its
    caustic, and the report names the lamp and the ball and gives the share
    of the caustic it holds (MNEE's Newton solver finds one path of the
    several that reach a point inside the fold: a quarter to a third of
    the light, benchmarks/cycles_accuracy.py); no error over the caustics."""
    sized_lamp_scene(radius=0.0, samples=256)
    reports()
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    said = reports()
    props = bpy.context.window_manager.caustic
    held = 1.0 / props.cycles_caustic_ratio
    print(f"MNEE holds {held:.3f} of the caustic render's caustic light")
    assert props.cycles_reference == 'MNEE' and 0.1 < held < 0.6
    assert ("The Cycles Reference lacks part of the caustic. Cycles cannot path-trace the caustics of lamps "
            "without a size, 'Lamp' (Radius 0): through 'Ball' its reference has only MNEE's shadow caustics"
            in said)
    assert (f"Over the caustics it holds {held:.0%} of the caustic render's caustic light: it lacks "
            f"{1 - held:.0%}" in said)
    assert "relative L2" not in said and "PSNR" in said and "outside the caustics" in said
    assert math.isnan(props.cycles_relative_l2)
