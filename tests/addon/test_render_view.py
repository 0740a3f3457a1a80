"""The scene read as a render sees it (export/render_view.py): Blender's
render depsgraph, through a render engine registered for a moment, with
everything changed for it put back; without a camera, the viewport's
depsgraph and a warning naming what differs."""

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from snapshot import snapshot_file


def subdivided_scene():
    """The ball lens scene, the ball under a Subdivision Surface at
    viewport 0 / render 2, and a glass hidden in the viewport."""
    parts = scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    subdivide = parts["ball"].modifiers.new("Subdivide", 'SUBSURF')
    subdivide.levels, subdivide.render_levels = 0, 2
    hidden = scenes.add_sphere(0.2, (1.0, 0.0, 0.4), scenes.glass_material("Hidden glass"), name="Hidden",
                               segments=8, rings=4)
    hidden.hide_viewport = True
    bpy.context.view_layer.update()
    return parts


def test_the_read_leaves_the_file_the_scene_settings_and_an_earlier_render_as_they_were(addon, tmp_path):
    subdivided_scene()
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = 1
    bpy.ops.render.render()
    earlier = str(tmp_path / "earlier.exr")
    scene.render.image_settings.file_format = 'OPEN_EXR'
    bpy.data.images["Render Result"].save_render(earlier, scene=scene)
    before = snapshot_file()
    read = addon.export.read_scene(bpy.context)
    addon.export.read_scene(bpy.context)
    assert {o.name for o in read.scene.objects} == {"Floor", "Ball", "Hidden"}
    after = snapshot_file()
    # The Render Result gains one slot, for reads, and keeps the earlier render in its own.
    slots = [slot["name"] for slot in after["images"]["Render Result"].pop("render_slots")]
    assert slots == [slot["name"] for slot in before["images"]["Render Result"].pop("render_slots")] + [
        "Caustics: scene read"]
    # Blender frees the Render Result's display buffers when it renders; they come back from the slot.
    after["images"]["Render Result"].pop("has_data"), before["images"]["Render Result"].pop("has_data")
    assert after == before
    assert scene.render.engine == 'CYCLES' and bpy.data.images["Render Result"].render_slots.active_index == 0
    # The reading engine is gone again: no scene can be set to it.
    assert not hasattr(bpy.types, "CAUSTIC_RE_scene_reader")
    with pytest.raises(TypeError):
        scene.render.engine = 'CAUSTIC_SCENE_READER'
    again = str(tmp_path / "again.exr")
    bpy.data.images["Render Result"].save_render(again, scene=scene)
    first, second = (bpy.data.images.load(path) for path in (earlier, again))
    assert np.array_equal(np.array(first.pixels[:]), np.array(second.pixels[:]))


def test_no_render_result_is_left_behind(addon):
    subdivided_scene()
    before = snapshot_file()
    addon.export.read_scene(bpy.context)
    assert "Render Result" not in bpy.data.images
    assert snapshot_file() == before


def test_undo_after_a_render_brings_back_the_scene_as_it_was():
    parts = subdivided_scene()
    bpy.ops.ed.undo_push(message="Scene")
    assert bpy.ops.caustic.render('EXEC_DEFAULT', True) == {'FINISHED'}
    parts["ball"].location.x += 0.25
    bpy.ops.ed.undo_push(message="Move")
    before = snapshot_file()
    assert bpy.ops.ed.undo() == {'FINISHED'}
    assert bpy.data.objects["Ball"].location.x == 0.0
    assert bpy.ops.ed.redo() == {'FINISHED'}
    assert snapshot_file() == before
    modifier = bpy.data.objects["Ball"].modifiers["Subdivide"]
    assert (modifier.levels, modifier.render_levels) == (0, 2) and bpy.data.objects["Hidden"].hide_viewport


def test_without_a_camera_the_viewport_is_read_and_what_a_render_would_differ_in_is_named(addon):
    subdivided_scene()
    bpy.context.scene.camera = None
    read = addon.export.read_scene(bpy.context, with_camera=False)
    assert {o.name for o in read.scene.objects} == {"Floor", "Ball"}
    assert len(next(o for o in read.scene.objects if o.name == "Ball").mesh.triangles) == 16 * 8 * 2 - 2 * 16
    assert ("The scene has no camera, so Blender cannot evaluate it as it renders: it was read as the viewport "
            "shows it, which differs for 'Ball' (modifier 'Subdivide', at its viewport settings), 'Hidden' "
            "(hidden in the viewport, so left out)") in read.warnings


def test_a_view_layer_disabled_for_rendering_is_read_as_the_viewport_shows_it_and_named(addon):
    subdivided_scene()
    bpy.context.view_layer.use = False
    read = addon.export.read_scene(bpy.context)
    assert {o.name for o in read.scene.objects} == {"Floor", "Ball"}
    assert ("The view layer 'ViewLayer' is disabled for rendering (Use for Rendering), so Blender cannot evaluate "
            "it as it renders: it was read as the viewport shows it, which differs for 'Ball' (modifier "
            "'Subdivide', at its viewport settings), 'Hidden' (hidden in the viewport, so left out)") in read.warnings
    assert not bpy.context.view_layer.use


def test_adaptive_subdivision_is_read_at_the_render_levels_and_named(addon):
    parts = subdivided_scene()
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    modifier = parts["ball"].modifiers["Subdivide"]
    if hasattr(modifier, "use_adaptive_subdivision"):  # Blender 5: the modifier's
        modifier.use_adaptive_subdivision = True
    else:  # before: the object's, with the Experimental feature set
        scene.cycles.feature_set = 'EXPERIMENTAL'
        parts["ball"].cycles.use_adaptive_subdivision = True
    read = addon.export.read_scene(bpy.context)
    assert ("'Ball': Cycles subdivides it adaptively when it renders; the caustic render uses its Subdivision "
            "Surface's Render levels") in read.warnings
    quads, fans = 16 * (8 - 2), 2 * 16
    ball = next(o for o in read.scene.objects if o.name == "Ball")
    assert len(ball.mesh.triangles) == 2 * (4 ** 2 * quads + 3 * 4 * fans)
    assert scene.render.engine == 'CYCLES'
