"""Textured floors rendered by the add-on and by Cycles with direct light
only: an image on the UV map, on Generated coordinates through a Mapping
node, and on Object coordinates through a Color Ramp and a Mix, each within
5% relative L2 of Cycles' luminance. A bake multiplies the caustic by the
same texture; a texture the add-on cannot read is named."""

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


FLOORS = {"image on the UV map": on_uv_map, "generated coordinates, tiled and turned": on_generated_coordinates_tiled,
          "object coordinates through a ramp and a mix": on_object_coordinates_through_a_ramp_and_a_mix}


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


def test_a_node_it_cannot_read_is_named(reports):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    tree, shader = floor_tree()
    noise = tree.nodes.new('ShaderNodeTexNoise')
    noise.name = "Grain"
    tree.links.new(noise.outputs['Color'], shader.inputs[0])
    reports()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert "material 'Floor': its" in reports() and "comes from 'Grain', a Noise Texture node" in reports.last


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
