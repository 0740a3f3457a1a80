"""Lamps seen by eye rays, by the add-on and by Cycles: each lamp with a
size seen straight on once its Camera visibility is ticked, and an area
lamp's glints in a glass ball, as reflection and through the glass."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from test_lamps_vs_cycles import CASES, ours, pole_scene, setup

SEEN_CASES = [case for case in CASES if CASES[case][0] != 'SUN' and "radius 0 " not in case]


@pytest.mark.parametrize("case", SEEN_CASES)
def test_a_lamp_seen_by_the_camera_is_as_bright_as_in_cycles(case, tmp_path):
    """The floor from above with the lamp between it and the camera, turned
    to face the camera: the image's mean, the lamp's light included, within
    2% of Cycles'."""
    pole_scene(with_pole=False)
    setup(case)
    lamp = bpy.data.objects["Lamp"]
    lamp.rotation_euler = (math.pi, 0.0, 0.0)
    hidden = ours().mean()
    lamp.visible_camera = True
    mine, theirs = ours(), scenes.cycles_render(str(tmp_path), samples=256)[..., :3]
    print(f"{case}: ours / Cycles {mine.mean() / theirs.mean():.4f}, the lamp's share {1 - hidden / mine.mean():.1%}")
    assert hidden < 0.5 * mine.mean()
    assert mine.mean() == pytest.approx(theirs.mean(), rel=0.02)


@pytest.mark.parametrize("seen_by", ["glossy and transmission", "glossy", "none"])
def test_a_glass_balls_glints_are_as_bright_as_in_cycles(seen_by, tmp_path):
    """Cycles with 8 glossy and transmission bounces, neither clamped nor
    blurred: the image's mean within 5%, with the lamp's Glossy and
    Transmission visibility as given. The glints are 2 or 3 pixels across,
    so both renderers take samples enough to find them (at the add-on's
    default 4 a pixel, its mean is 8% above its converged one)."""
    lamp = scenes.glass_ball_under_a_softbox()
    lamp.visible_glossy = "glossy" in seen_by
    lamp.visible_transmission = "transmission" in seen_by
    settings = bpy.context.scene.caustic
    settings.spp, settings.edge_samples = 16, 64
    mine = ours()
    cycles = bpy.context.scene.cycles
    cycles.sample_clamp_indirect, cycles.blur_glossy = 0.0, 0.0
    theirs = scenes.cycles_render(str(tmp_path), samples=1024, specular_bounces=8)[..., :3]
    print(f"seen by {seen_by}: ours {mine.mean():.5f}, Cycles {theirs.mean():.5f}")
    if seen_by == "none":
        assert mine.max() == 0.0 and theirs.max() < 0.05
    else:
        assert mine.max() > 10.0
        assert mine.mean() == pytest.approx(theirs.mean(), rel=0.05)


def test_a_lamp_hidden_from_glossy_and_transmission_rays_lights_no_rough_glass(tmp_path):
    """Cycles' next-event estimation honours a lamp's Glossy and
    Transmission visibility too: under the hidden lamp, a rough glass ball
    (roughness 0.1) has no highlight in either renderer."""
    lamp = scenes.glass_ball_under_a_softbox()
    lamp.visible_glossy = lamp.visible_transmission = False
    glass = next(n for n in bpy.data.materials["Glass"].node_tree.nodes if n.bl_idname == 'ShaderNodeBsdfGlass')
    glass.inputs["Roughness"].default_value = 0.1
    mine = ours()
    theirs = scenes.cycles_render(str(tmp_path), samples=64, specular_bounces=8)[..., :3]
    assert mine.max() == 0.0 and theirs.max() == 0.0
