"""Textured floors rendered by the add-on and by Cycles with direct light
only: an image on the UV map, on Generated coordinates through a Mapping
node, and on Object coordinates through a Color Ramp and a Mix, which the
add-on reads, and a Checker, a Noise and a Box-projected image, which Cycles
bakes for it, each within 5% relative L2 of Cycles' luminance. A bake
multiplies the caustic by the same texture; what the add-on can neither
read nor have baked is named."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from test_lamps_vs_cycles import add_lamp, ours, pole_scene

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def socket(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def floor_tree():
    """The floor's node tree and its shader (the factory Diffuse or Principled)."""
    tree = bpy.data.materials["Floor"].node_tree
    shader = next(n for n in tree.nodes if n.bl_idname in ('ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfPrincipled'))
    return tree, shader


def random_image(name="Tiles", size=16, seed=3, byte=False):
    rng = np.random.default_rng(seed)
    pixels = np.ones((size, size, 4), dtype=np.float32)
    pixels[..., :3] = rng.uniform(0.05, 0.95, (size, size, 3))
    image = bpy.data.images.new(name, size, size, float_buffer=not byte)
    image.pixels.foreach_set(pixels.ravel())
    return image


def on_uv_map():
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.image = random_image(byte=True)
    tree.links.new(texture.outputs['Color'], shader.inputs[0])


def on_generated_coordinates_tiled():
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.image, texture.interpolation = random_image(size=8), 'Closest'
    coordinates, mapping = tree.nodes.new('ShaderNodeTexCoord'), tree.nodes.new('ShaderNodeMapping')
    mapping.inputs['Scale'].default_value = (2.0, 3.0, 1.0)
    mapping.inputs['Rotation'].default_value = (0.0, 0.0, math.radians(20.0))
    tree.links.new(coordinates.outputs['Generated'], mapping.inputs['Vector'])
    tree.links.new(mapping.outputs['Vector'], texture.inputs['Vector'])
    tree.links.new(texture.outputs['Color'], shader.inputs[0])


def on_object_coordinates_through_a_ramp_and_a_mix():
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.image, texture.extension = random_image(size=12), 'MIRROR'
    coordinates = tree.nodes.new('ShaderNodeTexCoord')
    tree.links.new(coordinates.outputs['Object'], texture.inputs['Vector'])
    ramp = tree.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (0.1, 0.2, 0.6, 1.0)
    ramp.color_ramp.elements[1].color = (0.9, 0.8, 0.3, 1.0)
    mix = tree.nodes.new('ShaderNodeMix')
    mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
    socket(mix.inputs, 'Factor_Float').default_value = 0.7
    socket(mix.inputs, 'B_Color').default_value = (1.0, 0.6, 0.8, 1.0)
    tree.links.new(texture.outputs['Color'], ramp.inputs['Fac'])
    tree.links.new(ramp.outputs['Color'], socket(mix.inputs, 'A_Color'))
    tree.links.new(socket(mix.outputs, 'Result_Color'), shader.inputs[0])


CHECKER_COLORS = ((0.8, 0.2, 0.1, 1.0), (0.1, 0.3, 0.7, 1.0))


def checker():
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexChecker')
    texture.inputs['Scale'].default_value = 6.0
    for name, color in zip(("Color1", "Color2"), CHECKER_COLORS):
        texture.inputs[name].default_value = color
    tree.links.new(texture.outputs['Color'], shader.inputs[0])
    return texture


def noise_through_a_ramp():
    tree, shader = floor_tree()
    noise, ramp = tree.nodes.new('ShaderNodeTexNoise'), tree.nodes.new('ShaderNodeValToRGB')
    noise.inputs['Scale'].default_value = 8.0
    ramp.color_ramp.interpolation = 'B_SPLINE'
    ramp.color_ramp.elements[0].color = (0.05, 0.1, 0.3, 1.0)
    tree.links.new(noise.outputs['Fac'], ramp.inputs['Fac'])
    tree.links.new(ramp.outputs['Color'], shader.inputs[0])


def image_in_box_projection():
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.image, texture.projection = random_image(size=8), 'BOX'
    coordinates = tree.nodes.new('ShaderNodeTexCoord')
    tree.links.new(coordinates.outputs['Object'], texture.inputs['Vector'])
    tree.links.new(texture.outputs['Color'], shader.inputs[0])


FLOORS = {"image on the UV map": on_uv_map, "generated coordinates, tiled and turned": on_generated_coordinates_tiled,
          "object coordinates through a ramp and a mix": on_object_coordinates_through_a_ramp_and_a_mix,
          "checker, baked": checker, "noise through a b-spline ramp, baked": noise_through_a_ramp,
          "image in box projection, baked": image_in_box_projection}


@pytest.mark.parametrize("floor", FLOORS)
def test_a_textured_floor_is_lit_as_cycles_lights_it(floor, tmp_path):
    pole_scene(with_pole=False)
    bpy.data.objects["Floor"].scale = (0.2, 0.2, 1.0)   # 4 m of texture across the 3 m view
    add_lamp('POINT', energy=300.0, shadow_soft_size=0.0)
    FLOORS[floor]()
    bpy.context.scene.caustic.spp = 16
    mine, theirs = ours() @ LUMINANCE, scenes.cycles_render(str(tmp_path))[..., :3] @ LUMINANCE
    error = np.linalg.norm(mine - theirs) / np.linalg.norm(theirs)
    print(f"{floor}: relative L2 of luminance {100 * error:.2f}%")
    assert error < 0.05


def test_a_bake_shades_the_caustic_with_the_texture():
    parts = scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.image = random_image()
    tree.links.new(texture.outputs['Color'], shader.inputs[0])
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    baked = next(n for n in tree.nodes if n.bl_idname == 'ShaderNodeGroup')
    assert baked.inputs['Albedo'].links[0].from_socket == texture.outputs['Color']
    assert parts["floor"].name == "Floor"


def floor_texture(addon):
    """The engine texture the floor's colour is read as."""
    scene = addon.export.read_scene(bpy.context).scene
    return next(o for o in scene.objects if o.name == "Floor").material.texture


def datablocks():
    return {kind: sorted(block.name_full for block in getattr(bpy.data, kind))
            for kind in ("scenes", "objects", "meshes", "materials", "images", "node_groups", "shape_keys")}


def test_cycles_bakes_a_checker_to_its_mean_colour_and_leaves_the_users_data_as_it_was(addon):
    """A Checker of scale 6 on the floor's Generated coordinates has as many
    squares of each colour: the bake's mean is theirs. The bake is Cycles'
    of copies, which are all removed (the mesh's shape keys' too); the
    floor, its mesh and material, the selection and the active object stay
    as they were."""
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    texture = checker()
    floor = bpy.data.objects["Floor"]
    floor.shape_key_add(name="Basis")
    tree = floor.active_material.node_tree
    before = (datablocks(), addon.export.node_fingerprint.fingerprint(tree), len(floor.data.uv_layers),
              [o.name for o in bpy.context.selected_objects], bpy.context.view_layer.objects.active)
    baked = floor_texture(addon)
    assert baked.pixels.shape == (1024, 1024, 4)
    np.testing.assert_allclose(baked.pixels[..., :3].mean(axis=(0, 1)), np.mean(CHECKER_COLORS, axis=0)[:3],
                               rtol=0.01)
    assert before == (datablocks(), addon.export.node_fingerprint.fingerprint(tree), len(floor.data.uv_layers),
                      [o.name for o in bpy.context.selected_objects], bpy.context.view_layer.objects.active)
    assert floor_texture(addon).pixels is baked.pixels, "the same nodes on the same mesh are baked once"
    texture.inputs["Color1"].default_value = (1.0, 1.0, 1.0, 1.0)
    np.testing.assert_allclose(floor_texture(addon).pixels[..., 0].mean(), 0.55, rtol=0.01)


def test_what_cycles_cannot_bake_is_named(reports):
    """A bake needs a UV map, inside the 0-1 square, whose faces do not
    overlap: where the floor's has none, the warning names the node and
    says what to do, and the render goes on with the unconnected colour."""
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    tree, shader = floor_tree()
    noise = tree.nodes.new('ShaderNodeTexNoise')
    noise.name = "Grain"
    tree.links.new(noise.outputs['Color'], shader.inputs[0])
    reports()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert "Grain" not in reports()
    floor = bpy.data.objects["Floor"].data
    uvs = np.empty(2 * len(floor.loops))
    floor.uv_layers[0].data.foreach_get("uv", uvs)
    floor.uv_layers[0].data.foreach_set("uv", 2.0 * uvs)
    floor.update()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert ("'Floor': its color comes from 'Grain', a Noise Texture node, which Cycles can bake only onto a UV "
            "map inside the 0-1 square, and UV map 'UVMap' leaves it: unwrap the object without overlaps; the "
            "unconnected value is used") in reports()
    floor.uv_layers.remove(floor.uv_layers[0])
    floor.update()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert ("'Floor': its color comes from 'Grain', a Noise Texture node, which Cycles bakes onto a UV map, and "
            "the mesh has none: add one (UV > Unwrap)") in reports()


def test_a_missing_image_and_a_missing_uv_map_are_named(reports):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    tree, shader = floor_tree()
    texture = tree.nodes.new('ShaderNodeTexImage')
    texture.name = "Wood"
    texture.image = bpy.data.images.new("Oak", 4, 4)
    texture.image.source, texture.image.filepath = 'FILE', "//no/such/oak.png"
    tree.links.new(texture.outputs['Color'], shader.inputs[0])
    reports()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert "comes from 'Wood', whose image 'Oak' cannot be read" in reports()
    texture.image = random_image()
    floor = bpy.data.objects["Floor"].data
    floor.uv_layers.remove(floor.uv_layers[0])
    floor.update()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert "'Floor': its color comes from 'Wood', whose UV map 'active' the mesh does not have" in reports()
