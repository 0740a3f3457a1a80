"""A Principled BSDF floor, rendered by the add-on and by Cycles with no
bounces (direct light only), seen at an angle where the highlight of a
point lamp, of a lamp with a size, or of a bright patch of the world,
shows: the diffuse base under a GGX specular layer, as Cycles' Principled
BSDF builds them.

Bounds: the image's mean within 3% of Cycles (the issue's bar; the add-on
is within 0.1%, and without the layer's share of the base it is 6-10% too
bright, without the lobe 15-22% too dark); across the highlight, the RMS
of the pixels' difference under 2% of Cycles' mean there, and its
brightest pixel within a pixel of Cycles'. The RMS bound is what
16 stratified samples per pixel leave of a highlight 2 pixels wide
(roughness 0.1: 1.1% RMS against Cycles, 0.9% between the add-on's own 16
and 64 samples); a lobe of alpha = Roughness instead of Roughness^2 is
off by 28-238% there. The default 4 samples alias that highlight (41%)."""

import math
import os

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from test_lamps_vs_cycles import ours

WIDTH, HEIGHT = 64, 48
SPP = 16


def principled_floor(roughness, ior=1.5, level=0.5, tint=(1.0, 1.0, 1.0), distribution='MULTI_GGX',
                     base=(0.3, 0.3, 0.3), metallic=0.0, coat=None):
    """A 20 m Principled floor, a camera 2 m up looking down across it
    and a point lamp beyond its mirror point, so the highlight lies in
    the view's lower middle; `coat` the Coat inputs by their names after
    "Coat " (Weight, Roughness, IOR, Tint)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    material = bpy.data.materials.new("Floor")
    if material.node_tree is None:
        material.use_nodes = True
    shader = material.node_tree.nodes["Principled BSDF"]
    shader.distribution = distribution
    shader.inputs["Base Color"].default_value = (*base, 1.0)
    shader.inputs["Roughness"].default_value = roughness
    shader.inputs["IOR"].default_value = ior
    shader.inputs["Specular IOR Level"].default_value = level
    shader.inputs["Specular Tint"].default_value = (*tint, 1.0)
    shader.inputs["Metallic"].default_value = metallic
    for name, value in (coat or {}).items():
        shader.inputs[f"Coat {name}"].default_value = (*value, 1.0) if name == "Tint" else value
    scenes.add_plane(20.0, material)
    scenes.add_camera((0.0, -3.0, 2.0), target=(0.0, 0.5, 0.0), lens=30.0)
    scenes.set_resolution(WIDTH, HEIGHT)
    bpy.context.scene.caustic.lamp_rays = 1000
    bpy.context.scene.caustic.spp = SPP
    return shader


def lamp():
    scenes.add_point_light((0.0, 1.5, 1.5), 300.0)


def sized_lamp(kind, **settings):
    """A lamp of `kind` with a size where `lamp` stands; a sun 30 degrees up
    toward +Y, where the view's centre mirrors."""
    light = bpy.data.lights.new("Lamp", kind)
    for name, value in settings.items():
        setattr(light, name, value)
    ob = bpy.data.objects.new("Lamp", light)
    ob.location = (0.0, 1.5, 1.5)
    if kind == 'SUN':
        ob.rotation_euler = (math.radians(-60.0), 0.0, 0.0)
    bpy.context.scene.collection.objects.link(ob)


def relative(mine, theirs, region):
    """(mean ratio ours / Cycles over the image, RMS difference over
    `region` (h,w) bool / Cycles' mean there)."""
    rms = np.sqrt(np.mean((mine - theirs)[region] ** 2)) / theirs[region].mean()
    return mine.mean() / theirs.mean(), rms


def highlight(build_lit):
    """(h,w) bool: where the specular layer brings at least a quarter of
    the light, from the add-on's render with and without it."""
    shader = build_lit()
    with_layer = ours()
    shader.inputs["IOR"].default_value = 1.0
    without = ours()
    shader.inputs["IOR"].default_value = 1.5
    region = (with_layer - without)[..., 1] > 0.25 * with_layer[..., 1]
    assert region.sum() > 12
    return region


def peak(image, region):
    """(row, column) of the brightest pixel of `image (h,w,3)` in `region`."""
    luminance = np.where(region, image[..., 1], -np.inf)
    return np.unravel_index(np.argmax(luminance), luminance.shape)


def compare_highlight(build, tmp_path, label, spp=SPP):
    """Assert the image's mean within 3% of Cycles, the highlight's RMS
    within 2% of Cycles' mean there, and its brightest pixel within a
    pixel of Cycles', the add-on at `spp` samples per pixel."""
    region = highlight(build)
    bpy.context.scene.caustic.spp = spp
    mine, theirs = ours(), scenes.cycles_render(str(tmp_path))[..., :3]
    ratio, rms = relative(mine, theirs, region)
    ours_at, cycles_at = peak(mine, region), peak(theirs, region)
    print(f"{label}: ours / Cycles {ratio:.4f}, highlight RMS {100 * rms:.2f}% ({region.sum()} pixels), "
          f"peak at {ours_at} against {cycles_at}")
    assert ratio == pytest.approx(1.0, abs=0.03)
    assert rms < 0.02
    assert abs(ours_at[0] - cycles_at[0]) <= 1 and abs(ours_at[1] - cycles_at[1]) <= 1


@pytest.mark.parametrize("roughness", [0.1, 0.3, 0.6])
def test_a_principled_floor_shows_the_lamps_highlight_as_cycles_does(roughness, tmp_path):
    def build():
        shader = principled_floor(roughness)
        lamp()
        return shader

    compare_highlight(build, tmp_path, f"roughness {roughness}")


SIZED_LAMPS = {
    "point, radius 0.3": ('POINT', dict(energy=300.0, shadow_soft_size=0.3)),
    "area, square 0.8 m": ('AREA', dict(energy=300.0, shape='SQUARE', size=0.8)),
    "sun, angle 10 degrees": ('SUN', dict(energy=3.0, angle=math.radians(10.0))),
}


@pytest.mark.parametrize("case", SIZED_LAMPS)
def test_a_lamp_with_a_size_shows_its_highlight_as_cycles_does(case, tmp_path):
    """Roughness 0.3, lit by a lamp the eye pass samples over its area
    (emission/lamp_samples.py), at 64 samples per pixel: at 16 the lamp's
    samples leave 1.7-2.1% RMS in the highlight (against the add-on's own
    128), at 64 about 1%; Cycles' 512 leave 0.5-0.9% (against its 4096)."""
    def build():
        shader = principled_floor(0.3)
        sized_lamp(SIZED_LAMPS[case][0], **SIZED_LAMPS[case][1])
        return shader

    compare_highlight(build, tmp_path, case, spp=64)


INPUTS = {
    "Specular IOR Level 1, a coloured Specular Tint": dict(level=1.0, tint=(1.0, 0.5, 0.2)),
    "IOR 1.33, GGX (no multiple scattering)": dict(ior=1.33, distribution='GGX'),
    "Specular IOR Level 0: no layer": dict(level=0.0),
    "a white base, Roughness 0.8": dict(roughness=0.8, base=(1.0, 1.0, 1.0)),
    "Metallic 0.4 of a coloured base, a coloured Specular Tint": dict(metallic=0.4, base=(0.9, 0.6, 0.2),
                                                                     tint=(1.0, 0.7, 0.5)),
    "a clear coat, Coat Roughness 0.25": dict(coat={"Weight": 1.0, "Roughness": 0.25}),
    "half a tinted coat of IOR 1.8 over Metallic 0.3": dict(metallic=0.3, coat={
        "Weight": 0.5, "Roughness": 0.4, "IOR": 1.8, "Tint": (0.9, 0.6, 0.3)}),
}


@pytest.mark.parametrize("case", INPUTS)
def test_the_specular_inputs_shade_as_cycles_does(case, tmp_path):
    settings = dict(roughness=0.3) | INPUTS[case]
    principled_floor(**settings)
    lamp()
    mine, theirs = ours(), scenes.cycles_render(str(tmp_path))[..., :3]
    channels = mine.reshape(-1, 3).mean(axis=0) / theirs.reshape(-1, 3).mean(axis=0)
    rms = np.sqrt(np.mean((mine - theirs) ** 2)) / theirs.mean()
    print(f"{case}: ours / Cycles per channel {np.round(channels, 4)}, RMS {100 * rms:.2f}%")
    assert channels == pytest.approx(np.ones(3), abs=0.03)
    assert rms < 0.02


def bright_patch_world(folder):
    """A world of radiance 0.2 with a patch of 20, 10 degrees across,
    where the floor's highlight mirrors the camera (azimuth +Y, 20-40
    degrees up): an equirectangular EXR in `folder`, which the add-on
    reads itself. Closest interpolation: the add-on lights with each
    pixel's own value, and Cycles' Linear look-up lights the floor 4% less
    under this patch (its diffuse part alone)."""
    _, tree, background = scenes.world_nodes()
    h, w = 90, 180
    pixels = np.full((h, w, 4), 0.2, dtype=np.float32)
    pixels[25:35, 40:50, :3] = 20.0
    image = bpy.data.images.new("Patch", w, h, float_buffer=True)
    image.pixels.foreach_set(pixels[::-1].ravel())
    image.filepath_raw, image.file_format = os.path.join(folder, "patch.exr"), 'OPEN_EXR'
    image.save()
    environment = tree.nodes.new('ShaderNodeTexEnvironment')
    environment.image, environment.interpolation = bpy.data.images.load(image.filepath_raw), 'Closest'

    tree.links.new(environment.outputs['Color'], background.inputs['Color'])


@pytest.mark.parametrize("roughness", [0.1, 0.3])
def test_the_worlds_light_on_a_principled_floor_is_as_cycles(roughness, tmp_path):
    principled_floor(roughness)
    bright_patch_world(str(tmp_path))
    mine, theirs = ours(), scenes.cycles_render(str(tmp_path))[..., :3]
    ratio = mine.mean() / theirs.mean()
    rms = np.sqrt(np.mean((mine - theirs) ** 2)) / theirs.mean()
    print(f"roughness {roughness} under a bright patch: ours / Cycles {ratio:.4f}, RMS {100 * rms:.2f}%")
    assert ratio == pytest.approx(1.0, abs=0.03)
    assert rms < 0.05
