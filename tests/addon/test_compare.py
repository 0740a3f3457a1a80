"""caustic.compare_cycles: Cycles renders the same view with shadow caustics,
the error is measured, and every render setting is left as it was."""

import math

import bpy
import numpy as np

import blender_scenes as scenes
from snapshot import rna


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
    scenes.ring_scene(32, 24, lamp_rays=50_000)
    bpy.context.scene.caustic.cycles_samples = 4
    reports()
    assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
    assert "Cycles (MNEE) cannot render caustics cast by reflectors ('Ring')" in reports()
