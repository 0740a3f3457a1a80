"""The sidebar speaks Blender: Blender's labels, one-sentence tooltips, the
paper's names where it has them, and settings that are Blender's own
underneath; a run's figures stay out of the .blend."""

import re

import bpy

import blender_scenes as scenes

# Blender's words since 2.80, and American spelling; the paper's own names stay
NOT_BLENDERS_SPELLING = re.compile(r"\b(Lamps?|lamps?|Colours?|colours?|Eye Pass|Photon Pass)\b")


def the_addons_words():
    """(where, text) of every label and tooltip the add-on registers: its
    properties' names, descriptions and enum items, its operators', panels'
    and menus' labels and descriptions."""
    groups = [bpy.types.Scene.bl_rna.properties["caustic"].fixed_type,
              bpy.types.Object.bl_rna.properties["caustic"].fixed_type,
              bpy.types.WindowManager.bl_rna.properties["caustic"].fixed_type]
    for group in groups:
        for prop in group.properties:
            if prop.identifier in {"rna_type", "name"}:
                continue
            yield f"{group.identifier}.{prop.identifier}", prop.name
            yield f"{group.identifier}.{prop.identifier}", prop.description
            for item in getattr(prop, "enum_items", ()):
                yield f"{prop.identifier}:{item.identifier}", item.name
                yield f"{prop.identifier}:{item.identifier}", item.description
    for name in dir(bpy.types):
        if name.startswith(("CAUSTIC_OT_", "CAUSTIC_PT_", "CAUSTIC_MT_")):
            cls = getattr(bpy.types, name)
            yield name, getattr(cls, "bl_label", "")
            yield name, getattr(cls, "bl_description", "") or ""


def test_every_label_and_tooltip_is_in_blenders_words_and_short():
    words = list(the_addons_words())
    assert len(words) > 80
    for where, text in words:
        assert not NOT_BLENDERS_SPELLING.search(text.replace("the paper's lamp", "")), (where, text)
        assert len(text) <= 120, (where, len(text), text)
        assert not re.search(r"\d+(\.\d+)? ?(s|%) ", text + " "), (where, text)


def test_the_camera_panel_gives_the_papers_names_in_its_tooltip():
    description = bpy.types.CAUSTIC_PT_camera.bl_description
    for name in ("pixx", "pixy", "FOV"):
        assert name in description
    assert bpy.types.Camera.bl_rna.properties["angle"].name == "Field of View"


def test_the_ior_cannot_be_set_to_what_the_render_refuses():
    ior = bpy.types.Object.bl_rna.properties["caustic"].fixed_type.properties["ior"]
    assert ior.hard_min > 0.0


def test_dispersion_is_a_toggle_that_keeps_older_abbe_numbers():
    """A script or an older file sets an Abbe number alone: that is
    dispersion on. The toggle turns it off and back on to the same number,
    and on at 40 where the object never had one."""
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    ball = bpy.data.objects["Ball"]
    bpy.context.view_layer.objects.active = ball
    settings = ball.caustic
    assert settings.abbe == 0.0
    assert bpy.ops.caustic.toggle_dispersion() == {'FINISHED'}
    assert settings.abbe == 40.0
    settings.abbe = 20.0
    assert bpy.ops.caustic.toggle_dispersion() == {'FINISHED'}
    assert settings.abbe == 0.0
    assert bpy.ops.caustic.toggle_dispersion() == {'FINISHED'}
    assert settings.abbe == 20.0


def test_a_runs_figures_are_not_saved_in_the_blend(tmp_path):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    run = bpy.context.window_manager.caustic
    assert run.last_seconds > 0 and run.last_lamp_rays == 2000
    path = str(tmp_path / "saved.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    run.last_seconds, run.last_lamp_rays = 0.0, 0
    bpy.ops.wm.open_mainfile(filepath=path)
    assert bpy.context.window_manager.caustic.last_lamp_rays == 0
    assert "last_seconds" not in bpy.context.scene.caustic.bl_rna.properties


def test_map_scale_is_a_length():
    prop = bpy.types.Scene.bl_rna.properties["caustic"].fixed_type.properties["map_scale"]
    assert (prop.subtype, prop.unit, prop.name) == ('DISTANCE', 'LENGTH', "Map Scale")


def test_the_traced_count_says_what_refinement_added():
    scenes.ball_lens_scene(32, 24, lamp_rays=10_000, segments=32, rings=16)
    props, run = bpy.context.scene.caustic, bpy.context.window_manager.caustic
    props.density, props.beam_refinement = 'BEAM', 2
    bpy.ops.caustic.render()
    assert run.last_refined > 0
    assert run.last_lamp_rays - run.last_refined == 10_000
    props.beam_refinement = 0
    bpy.ops.caustic.render()
    assert run.last_refined == 0 and run.last_lamp_rays == 10_000
