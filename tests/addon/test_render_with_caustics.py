"""Render > Render Image / Render Animation with Caustics: the frame (or
the range, as an image sequence) is baked, then Blender's own render runs,
so Cycles (or EEVEE) shows the caustic of the frame it renders. Invoked, as
the menu does: in the background Blender's render then runs before the
call returns. EEVEE cannot render in the bpy module here (see
test_bake_animation), so Cycles renders."""

import os
import sys

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from test_animation import file_pixels
from test_bake_animation import peak, sliding_ball


def cycles_settings(output):
    """Cycles on the CPU at 16 samples, direct light only, float EXR to `output`."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.use_denoising = 'CPU', 16, False
    cycles.max_bounces = cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = 0
    cycles.pixel_filter_type, cycles.filter_width = 'BOX', 1.0
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '32'
    scene.render.filepath = output


def caustic_pass(frame):
    bpy.context.scene.frame_set(frame)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return scenes.pixels_of("Caustic Render Caustic")


def assert_shows(added, caustic):
    """The light a bake added to a Cycles render lies where the caustic pass has it, as strong."""
    row, col = peak(caustic)
    assert abs(peak(added)[0] - row) <= 1 and abs(peak(added)[1] - col) <= 1
    window = np.s_[row - 3:row + 4, col - 3:col + 4]
    ratio = added[window][..., :3].sum() / caustic[window][..., :3].sum()
    print(f"added by the bake in Cycles / caustic pass around its peak: {ratio:.3f}")
    assert abs(ratio - 1.0) < 0.15


def test_render_image_with_caustics_shows_the_current_frames_caustic(tmp_path):
    sliding_ball(tmp_path)
    scene = bpy.context.scene
    caustics = {frame: caustic_pass(frame) for frame in (1, 2)}
    assert abs(peak(caustics[1])[1] - peak(caustics[2])[1]) >= 4
    cycles_settings(str(tmp_path / "still.exr"))
    bpy.ops.render.render(write_still=True)
    plain = file_pixels(tmp_path / "still.exr")
    os.remove(tmp_path / "still.exr")

    assert bpy.ops.caustic.render_image_with_caustics('INVOKE_DEFAULT', write_still=True) == {'FINISHED'}
    assert scene.frame_current == 2 and bpy.data.images["Caustic Map Floor"].packed_file is not None
    assert_shows(file_pixels(tmp_path / "still.exr") - plain, caustics[2])


def test_render_animation_with_caustics_shows_each_frames_caustic(tmp_path):
    sliding_ball(tmp_path)
    scene = bpy.context.scene
    caustics = {frame: caustic_pass(frame) for frame in (2, 3)}
    scene.frame_set(1)
    cycles_settings(str(tmp_path / "plain" / "f_#.exr"))
    scene.frame_start = 2
    bpy.ops.render.render(animation=True)
    scene.frame_start = 1

    scene.render.filepath = str(tmp_path / "baked" / "f_#.exr")
    # Bake While Rendering stays out of a render whose frames are baked: it would repack frame 1 as a still
    scene.caustic.use_bake_on_render = True
    assert bpy.ops.caustic.render_animation_with_caustics('INVOKE_DEFAULT') == {'FINISHED'}
    assert sorted(os.listdir(tmp_path / "baked")) == ["f_1.exr", "f_2.exr", "f_3.exr"]
    assert sorted(os.listdir(tmp_path / "caustic_bake")) == ["Floor_0001.exr", "Floor_0002.exr", "Floor_0003.exr"]
    assert bpy.data.images["Caustic Map Floor"].source == 'SEQUENCE' and scene.frame_current == 1
    for frame in (2, 3):
        added = file_pixels(tmp_path / "baked" / f"f_{frame}.exr") - file_pixels(tmp_path / "plain" / f"f_{frame}.exr")
        assert_shows(added, caustics[frame])


def test_render_animation_with_caustics_of_a_range_of_its_own(tmp_path):
    """Blender 5 renders a given range; Blender 4's Render operator takes none, and the refusal says so."""
    sliding_ball(tmp_path)
    scene = bpy.context.scene
    cycles_settings(str(tmp_path / "out" / "f_#.exr"))
    scene.cycles.samples = 1
    if "frame_start" in bpy.ops.render.render.get_rna_type().properties:
        assert bpy.ops.caustic.render_animation_with_caustics(frame_start=3, frame_end=3) == {'FINISHED'}
        assert os.listdir(tmp_path / "out") == ["f_3.exr"]
        assert os.listdir(tmp_path / "caustic_bake") == ["Floor_0003.exr"]
    else:
        with pytest.raises(RuntimeError, match="renders an animation over the scene's frame range only"):
            bpy.ops.caustic.render_animation_with_caustics(frame_start=3, frame_end=3)
        assert not (tmp_path / "caustic_bake").exists() and not bpy.data.node_groups


def test_the_render_menu_has_both_entries(addon):
    assert addon.panels.render_menu.draw_render_menu in bpy.types.TOPBAR_MT_render._dyn_ui_initialize()


@pytest.fixture
def blender_keys():
    """The Screen key map as the interface merges it, with Blender's own
    F12 items (from its default key map's data, km_screen) in the default
    key configuration: the bpy module starts with none, and Blender 4.2's
    crashes at exit once the whole default key map is loaded."""
    folder = os.path.join(os.path.dirname(bpy.utils.preset_find("Blender", "keyconfig")), "keymap_data")
    sys.path.insert(0, folder)
    try:
        import blender_default
    finally:
        sys.path.remove(folder)
    _, _, screen = blender_default.km_screen(blender_default.Params())
    keyconfigs = bpy.context.window_manager.keyconfigs
    keymap = keyconfigs.default.keymaps.new("Screen", space_type='EMPTY')
    added = []
    for idname, event, extra in screen["items"]:
        if event.get("type") == 'F12' and not event.get("alt"):
            item = keymap.keymap_items.new(idname, event["type"], event["value"], ctrl=event.get("ctrl", False))
            for name, value in extra["properties"]:
                setattr(item.properties, name, value)
            added.append(item)
    keyconfigs.update()
    yield keyconfigs.user.keymaps["Screen"]
    for item in added:
        keymap.keymap_items.remove(item)
    keyconfigs.update()


@pytest.mark.parametrize("ctrl, ours", [(False, "caustic.render_image_with_caustics"),
                                        (True, "caustic.render_animation_with_caustics")])
def test_f12_and_ctrl_f12_come_to_the_caustic_renders_first(addon, blender_keys, ctrl, ours):
    hits = [item for item in blender_keys.keymap_items
            if item.type == 'F12' and item.ctrl == ctrl and not (item.alt or item.shift)]
    assert [item.idname for item in hits] == [ours, "render.render"]
    assert hits[0].properties.from_shortcut and hits[1].properties.animation == ctrl


@pytest.mark.parametrize("operator", ["render_image_with_caustics", "render_animation_with_caustics"])
def test_the_keys_pass_on_to_blenders_render_in_a_scene_without_caustics_in_renders(tmp_path, operator):
    sliding_ball(tmp_path)
    call = getattr(bpy.ops.caustic, operator)
    assert call('INVOKE_DEFAULT', from_shortcut=True) == {'PASS_THROUGH'}
    assert not bpy.data.node_groups and not (tmp_path / "caustic_bake").exists()


def test_f12_with_live_bakes_until_live_has_refined(addon, tmp_path):
    """With Live on, F12 passes on to Blender's render once Live's images
    hold the frame's full caustic, and bakes first while Live previews."""
    from test_live import pump

    sliding_ball(tmp_path)
    scene = bpy.context.scene
    cycles_settings(str(tmp_path / "still.exr"))
    scene.cycles.samples = 1
    bpy.context.view_layer.update()
    session = addon.live.session
    try:
        assert bpy.ops.caustic.toggle_live() == {'FINISHED'}
        assert not session.shows_final(scene)
        assert bpy.ops.caustic.render_image_with_caustics('INVOKE_DEFAULT', from_shortcut=True) == {'FINISHED'}
        pump(session)
        assert session.shows_final(scene)
        assert bpy.ops.caustic.render_image_with_caustics('INVOKE_DEFAULT', from_shortcut=True) == {'PASS_THROUGH'}
        assert bpy.ops.caustic.render_animation_with_caustics('INVOKE_DEFAULT', from_shortcut=True) == {'FINISHED'}
        assert bpy.data.images["Caustic Map Floor"].source == 'SEQUENCE'
    finally:
        session.stop()
