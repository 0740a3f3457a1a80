"""A rough glass ball's caustic, rendered by the add-on and path-traced by
Cycles: its width grows with Roughness as Cycles' does, and matches it.

The half-scale ball lens (blender_scenes.ball_lens_scene) under a small
sphere lamp (radius 0.05 m, Soft Falloff off: Cycles' path tracing reaches
a point lamp through rough glass only by the light sampling at the glass's
last vertex, which the sphere's own hits help), its Glass BSDF of Roughness
0.3 and 0.6 (Multiscatter GGX), in a black world. Cycles: MNEE off, Filter
Glossy 0 (its default would roughen the glass further after the floor's
bounce), 12 glass bounces after the floor's, as the engine's max_depth, 64
samples. The width is the radius within which three quarters of the
caustic's flux in the lamp's shadow lands, from rings of the pixels' floor
radii (which the engine's own camera rays give); the add-on renders at its
defaults but 20,000 lamp rays: in beam mode the lamp sends photons, since
it lights a rough caster."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

PIXELS = (96, 72)
RADIUS = 0.05
SAMPLES = 64


def rough_ball(roughness: float):
    """The scene, the ball's glass of `roughness`."""
    parts = scenes.ball_lens_scene(*PIXELS, lamp_rays=20_000)
    bpy.context.scene.caustic.density = 'BEAM'
    parts["camera"].data.lens = 80.0
    parts["camera"].location = (0.0, -3.0, 2.6)
    parts["camera"].rotation_euler = (math.radians(49.0), 0.0, 0.0)
    parts["ball"].active_material.node_tree.nodes["Glass BSDF"].inputs["Roughness"].default_value = roughness
    parts["floor"].active_material.node_tree.nodes["Diffuse BSDF"].inputs["Color"].default_value = (1, 1, 1, 1)
    lamp = parts["lamp"].data
    lamp.shadow_soft_size = RADIUS
    if hasattr(lamp, "use_soft_falloff"):
        lamp.use_soft_falloff = False
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    if world.node_tree is not None and "Background" in world.node_tree.nodes:
        world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bpy.context.scene.world = world


def floor_radius(addon) -> tuple[np.ndarray, np.ndarray]:
    """(in the shadow (h,w) bool: the pixel's centre sees the floor within
    the ball's shadow; the distance of what it sees from the axis (h,w), m)."""
    engine = addon.caustic_addon
    from importlib import import_module
    eye_rays = import_module(engine.__name__ + ".passes.camera_rays").eye_rays
    Accelerator = import_module(engine.__name__ + ".tracing.accelerator").Accelerator
    scene = addon.export.read_scene(bpy.context).scene
    cam = scene.camera
    pixel = np.arange(cam.pixx * cam.pixy)
    origins, dirs = eye_rays(cam, pixel, np.full((len(pixel), 2), 0.5))
    accel = Accelerator(scene.objects, scene.extent(), 2)
    hits = accel.intersect(origins, dirs)
    accel.close()
    floor = next(i for i, o in enumerate(scene.objects) if o.name == "Floor")
    r = np.hypot(hits.points[:, 0], hits.points[:, 1])
    shadow = 3.0 * math.tan(math.asin(0.5 / 2.25))
    return ((hits.obj == floor) & (r < 0.9 * shadow)).reshape(cam.pixy, cam.pixx), r.reshape(cam.pixy, cam.pixx)


def flux_radius(image: np.ndarray, region: np.ndarray, radius: np.ndarray, share=0.75, ring=0.02) -> float:
    """The radius within which `share` of the flux over the region lands:
    each ring's mean pixel (red) times the ring's area, summed outward."""
    index = (radius[region] / ring).astype(np.int64)
    mean = np.bincount(index, weights=image[..., 0][region]) / np.maximum(np.bincount(index), 1)
    flux = np.cumsum(mean * math.pi * ring ** 2 * (2 * np.arange(len(mean)) + 1))
    at = int(np.searchsorted(flux, share * flux[-1]))
    below = flux[at - 1] if at else 0.0
    return ring * (at + (share * flux[-1] - below) / (flux[at] - below))


def cycles(folder: str) -> np.ndarray:
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    c = scene.cycles
    c.device, c.samples, c.use_denoising, c.seed = 'CPU', SAMPLES, False, 1
    c.use_adaptive_sampling = False
    c.pixel_filter_type, c.filter_width = 'BOX', 1.0
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.max_bounces, c.transmission_bounces, c.glossy_bounces, c.diffuse_bounces = 13, 12, 12, 1
    return scenes.rendered_pixels(folder)[..., :3]


def test_a_rough_balls_caustic_widens_with_roughness_as_in_cycles(addon, tmp_path):
    widths = {}
    for roughness in (0.3, 0.6):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        rough_ball(roughness)
        region, radius = floor_radius(addon)
        assert region.sum() > 100
        assert bpy.ops.caustic.render() == {'FINISHED'}
        ours = scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64)
        theirs = cycles(str(tmp_path))
        widths[roughness] = (flux_radius(ours, region, radius), flux_radius(theirs, region, radius))
    print("75% flux radius, ours / Cycles:", {r: tuple(round(w, 4) for w in pair) for r, pair in widths.items()})
    for ours, theirs in widths.values():
        assert ours == pytest.approx(theirs, rel=0.04)
    assert widths[0.6][1] > 1.3 * widths[0.3][1] and widths[0.6][0] > 1.3 * widths[0.3][0]
