"""Every Blender lamp, with its size, emitting meshes and the world, rendered by the add-on
and by Cycles with no bounces (direct light only, what a Whitted eye pass
computes) over a white floor with a pole on it, seen from straight above:
the mean irradiance within 2% of Cycles, and the pole's shadow and penumbra
within 8% of the unshadowed light (RMS), at the add-on's default samples."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

PIXELS = 40
HALF = 1.5


def pole_scene(with_pole=True):
    """A 20 m floor of albedo 0.8, a 0.15 m square pole 1.2 m tall at x = 0.3,
    and an orthographic camera 3 m across looking straight down."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scenes.add_plane(20.0, scenes.diffuse_material())
    if with_pole:
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.3, 0.0, 0.6), scale=(0.15, 0.15, 1.2))
        bpy.context.object.data.materials.append(scenes.diffuse_material("Pole"))
        bpy.context.object.caustic.role = 'RECEIVER'
    camera = scenes.add_camera((0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0))
    camera.data.type, camera.data.ortho_scale = 'ORTHO', 2 * HALF
    camera.rotation_euler = (0.0, 0.0, 0.0)
    scenes.set_resolution(PIXELS, PIXELS)
    bpy.context.scene.caustic.lamp_rays = 1000


def add_lamp(kind, **settings):
    light = bpy.data.lights.new("Lamp", kind)
    for name, value in settings.items():
        setattr(light, name, value)
    lamp = bpy.data.objects.new("Lamp", light)
    lamp.location = (0.0, 0.0, 2.5)
    bpy.context.scene.collection.objects.link(lamp)
    return lamp


CASES = {
    "point, radius 0 (the control)": ('POINT', dict(energy=300.0, shadow_soft_size=0.0)),
    "point, radius 0.5, soft falloff": ('POINT', dict(energy=300.0, shadow_soft_size=0.5)),
    "point, radius 0.5, a sphere": ('POINT', dict(energy=300.0, shadow_soft_size=0.5, use_soft_falloff=False)),
    "spot, radius 0.3": ('SPOT', dict(energy=300.0, shadow_soft_size=0.3, spot_size=math.radians(100.0),
                                      spot_blend=0.3)),
    "sun, angle 15 degrees": ('SUN', dict(energy=3.0, angle=math.radians(15.0))),
    "area, square": ('AREA', dict(energy=300.0, shape='SQUARE', size=0.8)),
    "area, rectangle": ('AREA', dict(energy=300.0, shape='RECTANGLE', size=1.0, size_y=0.4)),
    "area, disk": ('AREA', dict(energy=300.0, shape='DISK', size=0.8)),
    "area, ellipse": ('AREA', dict(energy=300.0, shape='ELLIPSE', size=1.0, size_y=0.5)),
    "area, spread 60 degrees": ('AREA', dict(energy=300.0, shape='SQUARE', size=0.8, spread=math.radians(60.0))),
}


def setup(case):
    kind, settings = CASES[case]
    lamp = add_lamp(kind, **settings)
    if kind == 'SUN':
        lamp.rotation_euler = (0.0, math.radians(25.0), 0.0)


def ours() -> np.ndarray:
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64)


def compare(tmp_path, build):
    """(mean ratio ours / Cycles, RMS difference over the shadow and
    penumbra / the unshadowed light there) of the scene `build` makes."""
    pole_scene(with_pole=False)
    build()
    open_floor = ours()
    pole_scene()
    build()
    mine, theirs = ours(), scenes.cycles_render(str(tmp_path))[..., :3]
    shadow = (open_floor - mine)[..., 0] > 0.02 * open_floor[..., 0]
    assert shadow.sum() > 20
    rms = np.sqrt(np.mean((mine - theirs)[shadow] ** 2)) / open_floor[shadow].mean()
    return mine.mean() / theirs.mean(), rms


@pytest.mark.parametrize("case", CASES)
def test_a_lamp_lights_the_floor_and_shades_the_pole_as_cycles_does(case, tmp_path):
    ratio, rms = compare(tmp_path, lambda: setup(case))
    print(f"{case}: ours / Cycles {ratio:.4f}, shadow RMS {100 * rms:.1f}% of the unshadowed light")
    assert ratio == pytest.approx(1.0, abs=0.02)
    assert rms < 0.08


def emitting_plane():
    """A 0.8 m plane of Emission strength 20 at the lamps' height: a softbox built as a mesh."""
    plane = scenes.add_plane(0.8, scenes.emission_material(strength=20.0), name="Softbox")
    plane.location.z = 2.5
    plane.visible_camera = False


def emitting_sphere():
    """A glowing ball, 0.3 m across and 2 m up, of Emission strength 20 and a
    warm colour, at 32 Light Samples: its far half lies in its own shadow, so
    half of its samples bring nothing (at the default 8 the shadow's RMS was
    10.7%)."""
    ball = scenes.add_sphere(0.3, (0.0, 0.0, 2.0), scenes.emission_material(strength=20.0, color=(1.0, 0.6, 0.3)),
                             name="Glow", segments=24, rings=12)
    ball.visible_camera = False
    bpy.context.scene.caustic.lamp_samples = 32


EMITTERS = {"emitting plane (a softbox)": emitting_plane, "emitting sphere": emitting_sphere}


@pytest.mark.parametrize("emitter", EMITTERS)
def test_an_emitting_mesh_lights_the_floor_and_shades_the_pole_as_cycles_does(emitter, tmp_path):
    """An Emission shader on a mesh lights the scene as a lamp, from both
    sides of its faces, as Cycles' mesh lights do."""
    ratio, rms = compare(tmp_path, EMITTERS[emitter])
    print(f"{emitter}: ours / Cycles {ratio:.4f}, shadow RMS {100 * rms:.1f}% of the unshadowed light")
    assert ratio == pytest.approx(1.0, abs=0.02)
    assert rms < 0.08


def grey_world():
    _, _, background = scenes.world_nodes()
    background.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1.0)
    bpy.context.scene.render.film_transparent = True


def sky_world():
    """Blender's default Sky Texture (Nishita in 4.2 to 4.5, its successor
    in 5.0+), the sun 35 degrees up: Cycles bakes it for the add-on."""
    _, tree, background = scenes.world_nodes()
    sky = tree.nodes.new('ShaderNodeTexSky')
    sky.sun_elevation, sky.sun_rotation = math.radians(35.0), math.radians(60.0)
    tree.links.new(sky.outputs['Color'], background.inputs['Color'])
    background.inputs['Strength'].default_value = 0.05


def turned_hdri_world():
    """An HDRI, black but for a bright band, turned 90 degrees by a Mapping
    node: baked, since the add-on reads only an unturned image itself."""
    _, tree, background = scenes.world_nodes()
    h, w = 64, 128
    pixels = np.full((h, w, 4), 0.2, dtype=np.float32)
    pixels[12:20, 40:56, :3] = 40.0
    image = bpy.data.images.new("Sky.hdr", w, h, float_buffer=True)
    image.pixels.foreach_set(pixels[::-1].ravel())
    environment = tree.nodes.new('ShaderNodeTexEnvironment')
    environment.image = image
    coordinates, mapping = tree.nodes.new('ShaderNodeTexCoord'), tree.nodes.new('ShaderNodeMapping')
    mapping.inputs['Rotation'].default_value = (0.0, 0.0, math.radians(90.0))
    tree.links.new(coordinates.outputs['Generated'], mapping.inputs['Vector'])
    tree.links.new(mapping.outputs['Vector'], environment.inputs['Vector'])
    tree.links.new(environment.outputs['Color'], background.inputs['Color'])


WORLDS = {"grey": grey_world, "sky texture": sky_world, "turned HDRI": turned_hdri_world}


@pytest.mark.parametrize("world", WORLDS)
def test_the_worlds_light_shades_the_pole_as_cycles_does(world, tmp_path, request):
    if world == "turned HDRI":
        request.getfixturevalue("coarse_world_bakes")
    ratio, rms = compare(tmp_path, WORLDS[world])
    print(f"{world} world: ours / Cycles {ratio:.4f}, shadow RMS {100 * rms:.1f}%")
    assert ratio == pytest.approx(1.0, abs=0.02)
    assert rms < 0.08
