"""docs/compositing.md's set-up, built in bpy: a Cycles render with its own
caustics off, plus the Caustic pass of the add-on's multilayer EXR, added
in the compositor. The composite is the sum of the two, pixel for pixel."""

import os

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from test_animation import file_pixels


def add_caustic_pass(scene, caustic_file):
    """Render Layers' Image + the Caustic pass of `caustic_file` -> the composite, as the doc shows."""
    tree = scenes.compositor_tree(scene, "Caustics")
    nodes, links = tree.nodes, tree.links
    render_layers = nodes.new('CompositorNodeRLayers')
    caustics = nodes.new('CompositorNodeImage')
    caustics.image = bpy.data.images.load(str(caustic_file))
    if bpy.app.version >= (5, 0, 0):
        add = nodes.new('ShaderNodeMix')
        add.data_type, add.blend_type = 'RGBA', 'ADD'
        socket = {s.identifier: s for s in (*add.inputs, *add.outputs)}
        socket['Factor_Float'].default_value = 1.0
        a, b, result = socket['A_Color'], socket['B_Color'], socket['Result_Color']
        tree.interface.new_socket(name="Image", in_out='OUTPUT', socket_type='NodeSocketColor')
        output = nodes.new('NodeGroupOutput')
    else:
        add = nodes.new('CompositorNodeMixRGB')
        add.blend_type = 'ADD'
        add.inputs[0].default_value = 1.0
        a, b, result = add.inputs[1], add.inputs[2], add.outputs[0]
        output = nodes.new('CompositorNodeComposite')
    links.new(render_layers.outputs['Image'], a)
    links.new(caustics.outputs['Caustic'], b)
    links.new(result, output.inputs[0])


def cycles_exr(scene, path, compositing):
    scene.render.use_compositing = compositing
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return file_pixels(path)


def test_the_caustic_pass_adds_to_a_cycles_render_in_the_compositor(tmp_path):
    scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
    scene = bpy.context.scene
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = 'MULTI_LAYER_IMAGE'
    else:
        settings.file_format = 'OPEN_EXR_MULTILAYER'
    settings.color_depth = '32'
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "caustics_####"), frame_start=1,
                                            frame_end=1) == {'FINISHED'}
    caustic = scenes.pixels_of("Caustic Render Caustic")[..., :3]
    assert caustic.max() > 1.0

    scene.render.engine = 'CYCLES'
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = 'CPU', 4, False
    scene.cycles.caustics_refractive = scene.cycles.caustics_reflective = False
    if hasattr(settings, "media_type"):
        settings.media_type = 'IMAGE'
    settings.file_format, settings.color_depth = 'OPEN_EXR', '32'
    scene.render.use_file_extension = False
    cycles = cycles_exr(scene, tmp_path / "cycles.exr", compositing=False)
    add_caustic_pass(scene, tmp_path / "caustics_0001.exr")
    composite = cycles_exr(scene, tmp_path / "composite.exr", compositing=True)
    assert os.path.getsize(tmp_path / "composite.exr") > 0
    np.testing.assert_allclose(composite[..., :3], cycles[..., :3] + caustic, rtol=1e-5, atol=1e-6)
    assert composite[..., :3].max() == pytest.approx((cycles[..., :3] + caustic).max(), rel=1e-5)
