"""The sidebar speaks Blender: Blender's labels, the paper's names in the
tooltips, and settings that are Blender's own underneath."""

import bpy

import blender_scenes as scenes


def test_the_camera_panel_gives_the_papers_names_in_its_tooltip():
    description = bpy.types.CAUSTIC_PT_camera.bl_description
    for name in ("Resolution X", "pixx", "pixy", "Field of View", "FOV", "screen size S"):
        assert name in description
    assert bpy.types.Camera.bl_rna.properties["angle"].name == "Field of View"


def test_map_scale_is_a_length():
    prop = bpy.types.Scene.bl_rna.properties["caustic"].fixed_type.properties["map_scale"]
    assert (prop.subtype, prop.unit, prop.name) == ('DISTANCE', 'LENGTH', "Map Scale")


def test_the_traced_count_says_what_refinement_added():
    scenes.ball_lens_scene(32, 24, lamp_rays=10_000, segments=32, rings=16)
    props = bpy.context.scene.caustic
    props.density, props.beam_refinement = 'BEAM', 2
    bpy.ops.caustic.render()
    assert props.last_refined > 0
    assert props.last_lamp_rays - props.last_refined == 10_000
    props.beam_refinement = 0
    bpy.ops.caustic.render()
    assert props.last_refined == 0 and props.last_lamp_rays == 10_000
