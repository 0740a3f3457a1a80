"""caustic.compare_cycles: Cycles renders the same view with shadow caustics,
the error is measured, and every render setting is left as it was."""

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

    props = scene.caustic
    print(f"caustics {props.last_seconds:.2f} s, Cycles {props.cycles_seconds:.2f} s, "
          f"relative L2 {props.cycles_relative_l2:.3f}, PSNR {props.cycles_psnr:.1f} dB")
    assert props.cycles_seconds > 0 and props.last_seconds > 0
    assert math.isfinite(props.cycles_relative_l2) and props.cycles_relative_l2 > 0
    assert math.isfinite(props.cycles_psnr)


def test_compare_says_cycles_cannot_render_a_mirrors_caustic(reports):
    """A smooth mirror's caustic is missing from Cycles' reference, and the
    warning says so; a rough one's Cycles path-traces, and it says nothing."""
    scenes.ring_scene(32, 24, lamp_rays=50_000)
    bpy.context.scene.caustic.cycles_samples = 4
    reports()
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    assert "Cycles (MNEE) cannot render caustics cast by smooth reflectors ('Ring')" in reports()
    bpy.data.materials["Chrome"].node_tree.nodes["Glossy BSDF"].inputs["Roughness"].default_value = 0.3
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    assert "reflectors" not in reports()


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
    assert runner.done == ["caustics", "cycles"] and runner.error is None and not runner.cancelled
    after = render_state()
    assert set(after.pop("images")) - set(before.pop("images")) >= {"Caustic Render", "Cycles Reference",
                                                                     "Difference"}
    assert after == before
    assert scenes.pixels_of("Cycles Reference")[..., :3].max() > 0.1
    assert bpy.context.scene.caustic.cycles_seconds > 0


@pytest.mark.parametrize("stopped_in", ["caustics", "cycles"])
def test_esc_leaves_no_half_result_and_every_setting_as_it_was(addon, stopped_in):
    """Esc in either half: nothing is written (no Caustic Render without its
    reference), the figures stay, the settings Cycles needed are put back."""
    props = user_scene(3_000_000 if stopped_in == "caustics" else 20_000)
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
