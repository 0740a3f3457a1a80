"""caustic.render_animation: a frame range to files named by Blender's
output-path rules, each the render of its frame; Esc-free stops, map reuse,
undo, and the inputs it refuses."""

import os
import weakref

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from snapshot import snapshot_file


def moving_glass(width=24, height=18):
    """The ball lens with its ball sliding along x over frames 1-3."""
    parts = scenes.ball_lens_scene(width, height, lamp_rays=3000, segments=16, rings=8)
    scene = bpy.context.scene
    scene.caustic.spp = 1
    scene.frame_start, scene.frame_end = 1, 3
    ball = parts["ball"]
    for frame, x in ((1, -0.2), (3, 0.2)):
        ball.location.x = x
        ball.keyframe_insert("location", frame=frame)
    exr_output()
    return parts


def exr_output(multilayer=False):
    settings = bpy.context.scene.render.image_settings
    if multilayer and hasattr(settings, "media_type"):
        settings.media_type = 'MULTI_LAYER_IMAGE'
    else:
        settings.file_format = 'OPEN_EXR_MULTILAYER' if multilayer else 'OPEN_EXR'
    settings.color_depth = '32'


def file_pixels(path):
    """(h,w,4) float32, top row first, of the image file at `path`."""
    image = bpy.data.images.load(str(path))
    try:
        w, h = image.size
        pixels = np.empty(w * h * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        return pixels.reshape(h, w, 4)[::-1]
    finally:
        bpy.data.images.remove(image)


def test_each_frame_goes_to_its_file_and_equals_a_render_of_that_frame(tmp_path):
    moving_glass()
    scene = bpy.context.scene
    scene.frame_set(2)
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "glass_###")) == {'FINISHED'}
    assert sorted(os.listdir(tmp_path)) == ["glass_001.exr", "glass_002.exr", "glass_003.exr"]
    assert scene.frame_current == 2
    frames = {f: file_pixels(tmp_path / f"glass_{f:03d}.exr") for f in (1, 2, 3)}
    assert not np.array_equal(frames[1], frames[3])
    for frame, pixels in frames.items():
        scene.frame_set(frame)
        assert bpy.ops.caustic.render(filepath=str(tmp_path / "single" / "still_#")) == {'FINISHED'}
        assert np.array_equal(file_pixels(tmp_path / "single" / f"still_{frame}.exr"), pixels), frame


def test_the_scene_output_path_and_range_and_a_given_range(tmp_path):
    moving_glass()
    scene = bpy.context.scene
    scene.render.filepath = str(tmp_path / "out") + "/"
    scene.frame_end = 2
    assert bpy.ops.caustic.render_animation() == {'FINISHED'}
    assert sorted(os.listdir(tmp_path / "out")) == ["0001.exr", "0002.exr"]
    assert bpy.ops.caustic.render_animation(frame_start=3, frame_end=3) == {'FINISHED'}
    assert sorted(os.listdir(tmp_path / "out")) == ["0001.exr", "0002.exr", "0003.exr"]


def test_relative_path_of_a_saved_file_and_the_still_render_with_hashes(tmp_path):
    moving_glass()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    assert bpy.ops.caustic.render_animation(filepath="//frames/f_##", frame_end=1) == {'FINISHED'}
    assert os.listdir(tmp_path / "frames") == ["f_01.exr"]
    bpy.context.scene.frame_set(3)
    assert bpy.ops.caustic.render(filepath="//still_####.exr") == {'FINISHED'}
    assert (tmp_path / "still_0003.exr").is_file()


def test_unchanged_frames_reuse_the_maps_and_a_static_scene_gives_identical_frames(tmp_path, reports, addon):
    addon.jobs.MAP_CACHE.clear()
    parts = moving_glass()
    parts["ball"].animation_data_clear()
    camera = parts["camera"]
    for frame, z in ((1, 3.5), (3, 3.0)):  # only the camera moves
        camera.location.z = z
        camera.keyframe_insert("location", frame=frame)
    reports()
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "cam_#")) == {'FINISHED'}
    assert "maps reused on 2" in reports()
    camera.animation_data_clear()
    addon.jobs.MAP_CACHE.clear()
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "still_#")) == {'FINISHED'}
    assert "maps reused on 2" in reports()
    first = (tmp_path / "still_1.exr").read_bytes()
    assert all((tmp_path / f"still_{f}.exr").read_bytes() == first for f in (2, 3))
    # Beams are deterministic: the maps traced again give the same frame, bit for bit.
    addon.jobs.MAP_CACHE.clear()
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "again_#"), frame_end=1) == {'FINISHED'}
    assert (tmp_path / "again_1.exr").read_bytes() == first


def maps_held_at_each_lamp_pass(cache, monkeypatch, run) -> list[int]:
    """How many maps of earlier frames are alive as each frame's lamp pass
    starts (MapCache.make_room), over `run()`."""
    cache.clear()
    put, make_room = cache.put, cache.make_room
    traced, held = [], []

    def keep_track(key, value):
        traced.extend(weakref.ref(imap) for imap in value[0].values())
        put(key, value)

    def count_held(key):
        make_room(key)
        held.append(sum(ref() is not None for ref in traced))

    monkeypatch.setattr(cache, "put", keep_track)
    monkeypatch.setattr(cache, "make_room", count_held)
    run()
    return held


def test_no_frame_s_maps_are_held_while_the_next_frame_traces_its_own(tmp_path, addon, monkeypatch):
    """Bug: the last frame written kept its result whole for the run's
    closing report, maps too, so each frame's maps were held while the
    next one traced its own (85 MB of the pool's peak, and the second
    frame's page faults)."""
    moving_glass()
    held = maps_held_at_each_lamp_pass(addon.jobs.MAP_CACHE, monkeypatch, lambda: bpy.ops.caustic.render_animation(
        filepath=str(tmp_path / "f_#")))
    assert held == [0, 0, 0]


def test_undo_after_render_animation_keeps_the_frames(tmp_path):
    parts = moving_glass()
    bpy.ops.ed.undo_push(message="Scene")
    assert bpy.ops.caustic.render_animation('EXEC_DEFAULT', True, filepath=str(tmp_path / "u_#")) == {'FINISHED'}
    files = {name: (tmp_path / name).read_bytes() for name in os.listdir(tmp_path)}
    last = scenes.pixels_of("Caustic Render")
    assert len(files) == 3 and np.array_equal(last, file_pixels(tmp_path / "u_3.exr"))
    passes = [scenes.pixels_of(f"Caustic Render {name}")[..., :3] for name in ("Direct", "Caustic", "Ambient")]
    np.testing.assert_allclose(passes[0] + passes[1] + passes[2], last[..., :3], rtol=1e-6, atol=1e-7)
    parts["floor"].location.x += 0.25
    bpy.ops.ed.undo_push(message="Move")
    assert bpy.ops.ed.undo() == {'FINISHED'}
    assert {name: (tmp_path / name).read_bytes() for name in os.listdir(tmp_path)} == files
    assert np.array_equal(scenes.pixels_of("Caustic Render"), last)


def test_multilayer_exr_holds_the_image_and_its_passes(tmp_path):
    moving_glass()
    exr_output(multilayer=True)
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "ml_#"), frame_end=1) == {'FINISHED'}
    assert os.listdir(tmp_path) == ["ml_1.exr"]
    image = bpy.data.images.load(str(tmp_path / "ml_1.exr"))
    assert tuple(image.size) == (0, 0) and image.type == 'MULTILAYER'
    node = scenes.compositor_tree(bpy.context.scene, "Compositing").nodes.new('CompositorNodeImage')
    node.image = image
    assert {"Combined", "Direct", "Caustic", "Ambient"} <= {socket.name for socket in node.outputs}


@pytest.mark.parametrize("spoil, message", [
    (lambda tmp: dict(frame_start=5, frame_end=2), "The frame range 5 to 2 runs backwards"),
    (lambda tmp: dict(frame_start=5, frame_end=4), "The frame range 5 to 4 is empty"),
    (lambda tmp: dict(filepath=str(tmp / "f_#"), frame_start=8, frame_end=12),
     "has 1 '#' for the frame number, but frame 10 has 2 digits"),
    (lambda tmp: dict(filepath=str(tmp / "f") + "_", frame_start=9999, frame_end=10000),
     "has 4 '#' for the frame number, but frame 10000 has 5 digits"),
    (lambda tmp: dict(filepath=str(tmp / "a_file" / "f_#")), "Cannot write the frames into the folder"),
    (lambda tmp: dict(filepath="//f_#"), "relative to the .blend file, which is not saved yet"),
], ids=["backwards", "empty", "padding", "default padding", "unwritable folder", "unsaved relative path"])
def test_bad_output_is_refused_and_changes_nothing(tmp_path, spoil, message):
    moving_glass()
    (tmp_path / "a_file").write_text("not a folder")
    bpy.context.view_layer.update()
    before, files = snapshot_file(), sorted(os.listdir(tmp_path))
    with pytest.raises(RuntimeError, match=message.replace("(", r"\(").replace(")", r"\)")):
        bpy.ops.caustic.render_animation(**spoil(tmp_path))
    assert snapshot_file() == before
    assert sorted(os.listdir(tmp_path)) == files


def test_a_movie_format_is_refused(tmp_path):
    moving_glass()
    settings = bpy.context.scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = 'VIDEO'
    else:
        settings.file_format = 'FFMPEG'
    with pytest.raises(RuntimeError, match="The output format is a movie"):
        bpy.ops.caustic.render_animation(filepath=str(tmp_path / "f_#"))
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("multilayer", [False, True], ids=["Blender's EXR writer", "multilayer EXR"])
def test_a_disk_that_fills_up_keeps_the_frames_written_whole(tmp_path, small_disk, multilayer):
    """A disk with room for two and a half frames: the third does not fit."""
    moving_glass(64, 48)
    exr_output(multilayer)
    bpy.context.scene.render.image_settings.exr_codec = 'NONE'
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "f_#"), frame_end=2) == {'FINISHED'}
    second = scenes.pixels_of("Caustic Render")
    disk = small_disk(int(2.5 * (tmp_path / "f_1.exr").stat().st_size))
    with pytest.raises(RuntimeError, match=r"Frame 3 could not write '.*f_3\.exr': No space left on device; "
                                           r"2 of 3 frames written \(frames 1-2"):
        bpy.ops.caustic.render_animation(filepath=str(disk / "f_#"))
    assert sorted(os.listdir(disk)) == ["f_1.exr", "f_2.exr"]
    for name in ("f_1.exr", "f_2.exr"):
        assert (disk / name).read_bytes() == (tmp_path / name).read_bytes()
    # the image shows the last frame written, not the one that did not fit
    assert np.array_equal(scenes.pixels_of("Caustic Render"), second)
