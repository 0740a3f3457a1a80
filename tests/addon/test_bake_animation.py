"""caustic.bake_animation: a map per frame as an EXR sequence that the
receiver's material follows, so a render of any frame shows that frame's
caustic; unbake names the files it leaves. EEVEE cannot render in the bpy
module on these machines (no GPU: it fails with EGL errors, or crawls in
software OpenGL for minutes), so Cycles renders the baked material here:
both engines read the same Image Texture through the same image user."""

import os

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from snapshot import material_state, snapshot_file
from test_animation import file_pixels, maps_held_at_each_lamp_pass
from test_render import cycles_render


def sliding_ball(tmp_path):
    """A glass ball sliding 0.8 m along y over frames 1-3 above a floor, the
    lamp off to -x so the caustic falls clear of the ball as the camera sees
    it from +x; saved in tmp_path."""
    floor = scenes.add_plane(6.0, scenes.diffuse_material())
    ball = scenes.add_sphere(0.5, (0.0, 0.0, 0.75), scenes.glass_material(), segments=32, rings=16)
    lamp = scenes.add_point_light((-2.0, 0.0, 3.0), 1000.0)
    scenes.add_camera((4.0, 0.0, 3.0), target=(0.6, 0.0, 0.0), lens=30.0)
    scenes.set_resolution(48, 36)
    scene = bpy.context.scene
    scene.caustic.lamp_rays, scene.caustic.map_scale, scene.caustic.use_auto_map_scale = 5_000, 0.04, False
    scene.frame_start, scene.frame_end = 1, 3
    for frame, y in ((1, -0.4), (3, 0.4)):
        ball.location.y = y
        ball.keyframe_insert("location", frame=frame)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    return dict(floor=floor, ball=ball, lamp=lamp)


def peak(image):
    return np.unravel_index(image[..., :3].sum(axis=-1).argmax(), image.shape[:2])


def test_a_render_of_frame_2_shows_frame_2s_caustic(tmp_path, reports):
    parts = sliding_ball(tmp_path)
    scene = bpy.context.scene
    floor_before = material_state(parts["floor"].active_material)
    assert bpy.ops.caustic.bake_animation() == {'FINISHED'}
    folder = tmp_path / "caustic_bake"
    assert sorted(os.listdir(folder)) == ["Floor_0001.exr", "Floor_0002.exr", "Floor_0003.exr"]
    image = bpy.data.images["Caustic Map Floor"]
    assert image.source == 'SEQUENCE' and image.filepath == "//caustic_bake/Floor_0001.exr"
    assert image.packed_file is None and scene.frame_current == 1

    caustics = {}
    for frame in (1, 2):
        scene.frame_set(frame)
        assert bpy.ops.caustic.render() == {'FINISHED'}
        caustics[frame] = scenes.pixels_of("Caustic Render Caustic")
    assert abs(peak(caustics[1])[1] - peak(caustics[2])[1]) >= 4

    parts["ball"].hide_render = parts["lamp"].hide_render = True
    scene.frame_set(2)
    baked = cycles_render(str(tmp_path), samples=16)
    row, col = peak(caustics[2])
    assert abs(peak(baked)[0] - row) <= 1 and abs(peak(baked)[1] - col) <= 1
    window = np.s_[row - 3:row + 4, col - 3:col + 4]
    ratio = baked[window][..., :3].sum() / caustics[2][window][..., :3].sum()
    print(f"frame 2 baked in Cycles / caustic pass of frame 2 around its peak: {ratio:.3f}")
    assert abs(ratio - 1.0) < 0.15

    reports()
    assert bpy.ops.caustic.unbake() == {'FINISHED'}
    assert (f"The baked frames stay on disk: 3 files in '{folder}' (Floor_0001.exr to Floor_0003.exr)"
            in reports())
    assert material_state(parts["floor"].active_material) == floor_before
    assert "Caustic Map Floor" not in bpy.data.images and not bpy.data.node_groups
    assert sorted(os.listdir(folder)) == ["Floor_0001.exr", "Floor_0002.exr", "Floor_0003.exr"]


def test_a_moving_receiver_is_named(tmp_path):
    parts = sliding_ball(tmp_path)
    parts["floor"].location.z = 0.0
    parts["floor"].keyframe_insert("location", frame=1)
    parts["floor"].location.z = 0.1
    parts["floor"].keyframe_insert("location", frame=3)
    with pytest.raises(RuntimeError, match="Frame 2: receiver 'Floor' moved or changed shape since frame 1"):
        bpy.ops.caustic.bake_animation()


def test_an_unsaved_file_needs_a_folder(tmp_path):
    sliding_ball(tmp_path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scenes.ball_lens_scene(16, 12, lamp_rays=2000, segments=16, rings=8)
    bpy.context.scene.caustic.map_scale, bpy.context.scene.caustic.use_auto_map_scale = 0.05, False
    bpy.context.view_layer.update()
    before = snapshot_file()
    with pytest.raises(RuntimeError, match="The output path '//caustic_bake/' is relative to the .blend file"):
        bpy.ops.caustic.bake_animation()
    assert snapshot_file() == before
    assert bpy.ops.caustic.bake_animation(directory=str(tmp_path / "baked"), frame_start=1, frame_end=2) == {
        'FINISHED'}
    assert sorted(os.listdir(tmp_path / "baked")) == ["Floor_0001.exr", "Floor_0002.exr"]


def cycles_frames(tmp_path, name, frames):
    """Cycles (CPU, 4 samples, float EXR) renders of `frames`, as `blender -b -a` renders them: (frame -> pixels)."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = 'CPU', 4, False
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '32'
    scene.render.filepath = str(tmp_path / name / "f_#")
    scene.frame_start, scene.frame_end = frames[0], frames[-1]
    bpy.ops.render.render(animation=True)
    return {frame: file_pixels(tmp_path / name / f"f_{frame}.exr") for frame in frames}


@pytest.mark.parametrize("switch", ["use_bake_on_render", "use_live"])
def test_bake_while_rendering_gives_each_frame_its_own_caustic(tmp_path, switch):
    """A Cycles animation render with Bake While Rendering, or Live, on
    equals the render of a Bake Animation's sequence, frame by frame, and
    differs from frame 1's bake held still."""
    sliding_ball(tmp_path)
    scene = bpy.context.scene
    assert bpy.ops.caustic.bake_animation() == {'FINISHED'}
    sequence = cycles_frames(tmp_path, "sequence", [2, 3])
    bpy.ops.caustic.unbake()
    scene.frame_set(1)
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    held = cycles_frames(tmp_path, "held", [2])
    bpy.ops.caustic.unbake()

    setattr(scene.caustic, switch, True)
    scene.frame_set(1)
    live = cycles_frames(tmp_path, "live", [2, 3])
    for frame in (2, 3):
        np.testing.assert_allclose(live[frame], sequence[frame], rtol=1e-4, atol=1e-5)
    assert np.abs(held[2] - sequence[2])[..., :3].max() > 0.1
    # the last frame's bake stays in the material, as Bake Caustics leaves it
    assert bpy.data.images["Caustic Map Floor"].source != 'SEQUENCE'


def test_only_the_first_frame_s_maps_are_held_while_a_frame_traces(tmp_path, addon, monkeypatch):
    """The bake keeps the first frame's map of each receiver (a later
    frame's chart is checked against it) and no other: the last frame
    baked kept its maps until the next was traced (the bug
    test_animation's test names)."""
    sliding_ball(tmp_path)
    held = maps_held_at_each_lamp_pass(addon.jobs.MAP_CACHE, monkeypatch, bpy.ops.caustic.bake_animation)
    assert held == [0, 1, 1]
