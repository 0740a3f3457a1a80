"""The sky's light through glass, read from Blender's world and carried by
the maps (emission/sky_lamps.py): the white furnace balances in a render,
and a bake holds the light the glass lets through."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

PIXELS = 24


def index_matched_ball_in_a_white_world(height: float) -> None:
    """A glass ball of IOR 1 (radius 0.5, centre `height` m up) over a 20 m
    white floor in a world of radiance 1, no lights; an orthographic camera
    looks straight down at the 3 m square of floor under it."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scenes.add_plane(20.0, scenes.diffuse_material(color=(1.0, 1.0, 1.0)))
    scenes.add_sphere(0.5, (0.0, 0.0, height), scenes.glass_material(ior=1.0), segments=96, rings=48)
    bpy.ops.object.shade_smooth()
    scenes.world_nodes()[2].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    camera = scenes.add_camera((0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))
    camera.data.type, camera.data.ortho_scale = 'ORTHO', 3.0
    camera.rotation_euler = (0.0, 0.0, 0.0)
    scenes.set_resolution(PIXELS, PIXELS)


def test_a_white_floor_under_index_matched_glass_in_a_white_world_is_white(addon):
    """Every direction the glass hides from the world's shadow rays comes
    back through the maps, and nothing twice: the floor's radiance is the
    world's, 1, in the mean and in blocks of 4 x 4 pixels."""
    index_matched_ball_in_a_white_world(1.0)
    bpy.context.scene.caustic.world_samples = 32
    assert bpy.ops.caustic.render() == {'FINISHED'}
    image = scenes.pixels_of("Caustic Render")[..., 0].astype(np.float64)
    through = scenes.pixels_of("Caustic Render Caustic")[..., 0].astype(np.float64)
    assert through.max() > 0.2
    assert image.mean() == pytest.approx(1.0, rel=0.01)
    np.testing.assert_allclose(image.reshape(6, 4, 6, 4).mean(axis=(1, 3)), 1.0, rtol=0.04)


def test_a_bake_holds_the_skys_light_through_the_glass(addon):
    """With no light in the scene, the floor's baked map holds what the
    ball lets through of the sky, as much as the glass hides from it: a
    sphere of radius R whose centre is D away and H above a point hides
    irradiance pi (R / D)^2 (H / D) there. Over the 20 m floor, the map's
    flux is that irradiance's, and its peak lies under the ball."""
    index_matched_ball_in_a_white_world(1.0)
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    image = bpy.data.images["Caustic Map Floor"]
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    irradiance = pixels.reshape(h, w, 4)[..., 0].astype(np.float64)
    ticks = (np.arange(2000) + 0.5) / 2000 * 20.0 - 10.0
    distance = np.sqrt(ticks[:, None] ** 2 + ticks[None, :] ** 2 + 1.0)
    hidden = (math.pi * (0.5 / distance) ** 2 / distance).sum() * (20.0 / 2000) ** 2
    assert irradiance.sum() * (20.0 / w) * (20.0 / h) == pytest.approx(hidden, rel=0.02)
    peak = np.unravel_index(irradiance.argmax(), irradiance.shape)
    assert abs(peak[0] + 0.5 - h / 2) * 20.0 / h < 0.2 and abs(peak[1] + 0.5 - w / 2) * 20.0 / w < 0.2
