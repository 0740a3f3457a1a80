"""A world the add-on cannot read itself (a Sky Texture, a turned HDRI),
baked by Cycles into a lat-long image: in the engine's mapping, following
the world's changes, leaving the file as it was, and saying what it cannot
do."""

import math

import addon_utils
import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from caustic_addon import World
from caustic_addon.emission.environment import Environment, uv_to_directions


def sky_world(elevation=35.0, rotation=0.0):
    world, tree, background = scenes.world_nodes("Sky")
    sky = tree.nodes.new('ShaderNodeTexSky')
    sky.sun_elevation, sky.sun_rotation = math.radians(elevation), math.radians(rotation)
    tree.links.new(sky.outputs['Color'], background.inputs['Color'])
    return world, sky


def read_world(addon):
    return addon.export.read_scene(bpy.context, with_camera=False)


def brightest_direction(environment: np.ndarray) -> np.ndarray:
    h, w = environment.shape[:2]
    row, col = np.unravel_index(environment.sum(axis=2).argmax(), (h, w))
    return uv_to_directions(np.array([[(col + 0.5) / w, (row + 0.5) / h]]))[0]


@pytest.mark.parametrize("elevation, rotation", [(35.0, 0.0), (35.0, 60.0), (60.0, -120.0)])
def test_the_skys_sun_is_baked_where_its_node_puts_it(addon, elevation, rotation, request):
    """Blender's sun direction: (cos e sin r, cos e cos r, sin e) for
    elevation e and rotation r, within a bake pixel: 0.18 degrees in the
    add-on's bake, 0.7 in the coarse bakes the turned suns are checked in."""
    coarse = rotation != 0.0
    if coarse:
        request.getfixturevalue("coarse_world_bakes")
    scenes.add_plane(4.0, scenes.diffuse_material())
    sky_world(elevation, rotation)
    baked = read_world(addon).scene.world
    e, r = math.radians(elevation), math.radians(rotation)
    sun = np.array([math.cos(e) * math.sin(r), math.cos(e) * math.cos(r), math.sin(e)])
    assert math.degrees(math.acos(min(1.0, brightest_direction(baked.environment) @ sun))) < (0.7 if coarse else 0.2)


def test_a_turned_environment_is_baked_as_its_mapping_turns_it(addon, coarse_world_bakes):
    """A Mapping node turning the coordinates by R looks the image up at
    R d for a direction d: the bake holds the unturned image's light from
    R d, within a few percent for a smooth image."""
    scenes.add_plane(4.0, scenes.diffuse_material())
    _, tree, background = scenes.world_nodes("Sky")
    h, w = 32, 64
    u, v = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    pixels = np.ones((h, w, 4), dtype=np.float32)
    pixels[..., 0] = 1.0 + 0.5 * np.cos(2 * math.pi * u)
    pixels[..., 1] = 1.0 + 0.5 * np.sin(2 * math.pi * u) * np.sin(math.pi * v)
    image = bpy.data.images.new("Smooth", w, h, float_buffer=True)
    image.pixels.foreach_set(pixels[::-1].ravel())
    environment = tree.nodes.new('ShaderNodeTexEnvironment')
    environment.image = image
    coordinates, mapping = tree.nodes.new('ShaderNodeTexCoord'), tree.nodes.new('ShaderNodeMapping')
    mapping.inputs['Rotation'].default_value = (0.0, 0.0, math.radians(90.0))
    tree.links.new(coordinates.outputs['Generated'], mapping.inputs['Vector'])
    tree.links.new(mapping.outputs['Vector'], environment.inputs['Vector'])
    tree.links.new(environment.outputs['Color'], background.inputs['Color'])
    baked = read_world(addon).scene.world.environment
    bh, bw = baked.shape[:2]
    rows, cols = np.meshgrid(np.arange(0, bh, 16), np.arange(0, bw, 16), indexing="ij")
    dirs = uv_to_directions(np.stack([(cols.ravel() + 0.5) / bw, (rows.ravel() + 0.5) / bh], axis=1))
    turned = dirs @ np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).T
    expected = Environment(World(1.0, pixels[..., :3].astype(np.float64))).radiance(turned)
    np.testing.assert_allclose(baked[rows.ravel(), cols.ravel()], expected, rtol=0.03)


def test_a_changed_sky_is_baked_again(addon, coarse_world_bakes):
    scenes.add_plane(4.0, scenes.diffuse_material())
    _, sky = sky_world(35.0)
    first = brightest_direction(read_world(addon).scene.world.environment)
    sky.sun_elevation = math.radians(60.0)
    second = brightest_direction(read_world(addon).scene.world.environment)
    assert math.degrees(math.asin(first[2])) == pytest.approx(35.0, abs=0.7)
    assert math.degrees(math.asin(second[2])) == pytest.approx(60.0, abs=0.7)


def test_baking_leaves_the_file_as_it_was(addon, coarse_world_bakes):
    """No scene, camera, object or image is left behind, the user's scene
    keeps its render settings, and a world hidden from the camera stays so
    (the bake shows it to its own camera for a while)."""
    scenes.add_plane(4.0, scenes.diffuse_material())
    world, _ = sky_world()
    world.cycles_visibility.camera = False
    scene = bpy.context.scene
    scene.render.filepath, scene.render.resolution_x = "//frames/", 321
    engine = scene.render.engine

    def names():
        return {kind: sorted(getattr(bpy.data, kind).keys())
                for kind in ("scenes", "cameras", "objects", "images", "worlds", "meshes")}

    before = names()
    assert not read_world(addon).scene.world.is_black
    assert names() == before
    assert world.cycles_visibility.camera is False
    assert (scene.render.filepath, scene.render.resolution_x, scene.render.engine) == ("//frames/", 321, engine)


def test_a_light_path_trick_is_named(addon, coarse_world_bakes):
    scenes.add_plane(4.0, scenes.diffuse_material())
    _, tree, background = scenes.world_nodes("Sky")
    path, mix = tree.nodes.new('ShaderNodeLightPath'), tree.nodes.new('ShaderNodeMixRGB')
    path.name = "Camera Only"
    tree.links.new(path.outputs['Is Camera Ray'], mix.inputs[0])
    tree.links.new(mix.outputs[0], background.inputs['Color'])
    warnings = read_world(addon).warnings
    assert any("world 'Sky': its Light Path node 'Camera Only'" in w for w in warnings)


@pytest.fixture
def cycles_off():
    addon_utils.disable("cycles", default_set=True)
    yield
    addon_utils.enable("cycles", default_set=True)


def test_without_cycles_a_sky_is_black_and_named_and_the_comparison_says_why(addon, cycles_off):
    scenes.add_plane(4.0, scenes.diffuse_material())
    scenes.add_point_light((0.0, 0.0, 2.0), 100.0)
    sky_world()
    result = read_world(addon)
    assert result.scene.world.is_black
    assert any("world 'Sky': its nodes need Cycles to bake them, and the Cycles add-on is disabled" in w
               for w in result.warnings)
    with pytest.raises(RuntimeError, match="Compare with Cycles needs the Cycles add-on"):
        bpy.ops.caustic.compare_cycles()
