"""Files the add-on writes are written whole or not at all: each of Blender's
image formats is checked by its structure before it replaces anything (a
full disk cuts Blender's PNG, WebP and Targa files short without an
error), the format is the one the file name's extension names, and the
image the add-on writes into is its own, never the user's."""

import os
import shutil
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

import blender_scenes as scenes


def file_formats():
    """(format, settings) of every image format this Blender writes, with the codecs and depths that change its layout."""
    settings = bpy.context.scene.render.image_settings
    enum = settings.bl_rna.properties
    formats = [item.identifier for item in enum["file_format"].enum_items
               if item.identifier not in {'FFMPEG', 'OPEN_EXR_MULTILAYER', 'AVI_JPEG', 'AVI_RAW'}]
    cases = [(name, {}) for name in formats]
    cases += [('OPEN_EXR', {"color_depth": depth, "exr_codec": codec.identifier})
              for codec in enum["exr_codec"].enum_items for depth in ('16', '32')]
    cases += [('TIFF', {"tiff_codec": codec.identifier}) for codec in enum["tiff_codec"].enum_items]
    cases += [('PNG', {"color_depth": '16', "color_mode": 'RGBA'}), ('JPEG2000', {"jpeg2k_codec": 'J2K'})]
    return cases


def test_every_format_blender_writes_is_whole_and_a_cut_one_is_refused(addon, tmp_path):
    check_whole, incomplete = addon.caustic_addon.cli.files.check_whole, addon.caustic_addon.cli.files.IncompleteFile
    rng = np.random.default_rng(7)
    image = addon.writeback.images.write_image("noise", rng.random((48, 64, 4)).astype(np.float32) * 4.0,
                                               pack=False)
    scene = bpy.context.scene
    settings = scene.render.image_settings
    for file_format, options in file_formats():
        settings.file_format = file_format
        try:
            for name, value in options.items():
                setattr(settings, name, value)
        except TypeError:  # a codec this depth does not take (B44 is for half floats)
            continue
        path = tmp_path / f"{file_format}-{'-'.join(options.values())}"
        addon.writeback.output.save_frame(scene, "ViewLayer", image, None, str(path))
        data = path.read_bytes()
        check_whole(path, file_format)
        for cut in sorted({16, len(data) // 2, len(data) - 100, len(data) - 2, len(data) - 1} - {0}):
            (tmp_path / "cut").write_bytes(data[:cut])
            with pytest.raises(incomplete, match="not whole|empty"):
                check_whole(tmp_path / "cut", file_format)
        loaded = bpy.data.images.load(str(path))
        assert tuple(loaded.size) == (64, 48), path.name
        bpy.data.images.remove(loaded)
    assert not [name for name in os.listdir(tmp_path) if name.endswith(".part")]


def png_16(parts=None):
    settings = bpy.context.scene.render.image_settings
    settings.file_format, settings.color_depth, settings.color_mode = 'PNG', '16', 'RGBA'


def moving_glass():
    parts = scenes.ball_lens_scene(64, 48, lamp_rays=3000, segments=16, rings=8)
    scene = bpy.context.scene
    scene.caustic.spp = 1
    scene.frame_start, scene.frame_end = 1, 3
    for frame, x in ((1, -0.2), (3, 0.2)):
        parts["ball"].location.x = x
        parts["ball"].keyframe_insert("location", frame=frame)
    png_16()
    return parts


def test_a_full_disk_keeps_the_png_frames_written_and_says_so(tmp_path, small_disk, fill_disk):
    """The disk has room for half a frame when frames 1-3 are rendered over frame 1 (issue 40)."""
    moving_glass()
    assert bpy.ops.caustic.render_animation(filepath=str(tmp_path / "f_####"), frame_end=1) == {'FINISHED'}
    size = (tmp_path / "f_0001.png").stat().st_size
    disk = small_disk(4 * size)
    shutil.copy(tmp_path / "f_0001.png", disk / "f_0001.png")
    fill_disk(disk, size // 2)
    with pytest.raises(RuntimeError, match=r"Frame 1 could not write '.*f_0001\.png': the PNG file written is not "
                                           r"whole: .*its disk is full .*; 0 of 3 frames written"):
        bpy.ops.caustic.render_animation(filepath=str(disk / "f_####"))
    assert sorted(os.listdir(disk)) == ["f_0001.png", "filler"]
    assert (disk / "f_0001.png").read_bytes() == (tmp_path / "f_0001.png").read_bytes()


def test_a_full_disk_keeps_the_still_it_would_replace(tmp_path, small_disk, fill_disk):
    scenes.ball_lens_scene(64, 48, lamp_rays=3000, segments=16, rings=8)
    png_16()
    assert bpy.ops.caustic.render(filepath=str(tmp_path / "still.png")) == {'FINISHED'}
    good = (tmp_path / "still.png").read_bytes()
    disk = small_disk(4 * len(good))
    (disk / "still.png").write_bytes(good)
    fill_disk(disk, len(good) // 2)
    with pytest.raises(RuntimeError, match=r"Rendered into \"Caustic Render\" but could not write '.*still\.png': "
                                           r"the PNG file written is not whole"):
        bpy.ops.caustic.render(filepath=str(disk / "still.png"))
    assert sorted(os.listdir(disk)) == ["filler", "still.png"]
    assert (disk / "still.png").read_bytes() == good


@pytest.mark.parametrize("name, magic", [("still.exr", b"v/1\x01"), ("still.jpg", b"\xff\xd8"),
                                         ("still.tif", b"II*\x00"), ("still_#.exr", b"v/1\x01")])
def test_the_file_name_s_extension_names_the_format_written(tmp_path, name, magic):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    png_16()
    assert bpy.ops.caustic.render(filepath=str(tmp_path / name)) == {'FINISHED'}
    written = name.replace("#", str(bpy.context.scene.frame_current))
    assert os.listdir(tmp_path) == [written]
    assert (tmp_path / written).read_bytes().startswith(magic)
    assert bpy.context.scene.render.image_settings.file_format == 'PNG'
    assert bpy.context.scene.render.image_settings.color_depth == '16'
    if name.endswith(".exr"):
        loaded = bpy.data.images.load(str(tmp_path / written))
        pixels = np.empty(32 * 24 * 4, dtype=np.float32)
        loaded.pixels.foreach_get(pixels)
        assert np.array_equal(pixels.reshape(24, 32, 4)[::-1], scenes.pixels_of("Caustic Render"))


def test_a_user_s_image_of_the_result_s_name_is_left_alone(reports):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    mine = bpy.data.images.new("Caustic Render", 4, 4)
    mine.generated_color = (0.2, 0.4, 0.6, 1.0)
    before = scenes.pixels_of("Caustic Render")
    reports()
    for _ in range(2):
        assert bpy.ops.caustic.render() == {'FINISHED'}
        assert 'light rays into "Caustic Render.001"' in reports()
    assert {image.name for image in bpy.data.images if image.name.startswith("Caustic Render")} == {
        "Caustic Render", "Caustic Render.001", "Caustic Render Ambient", "Caustic Render Caustic",
        "Caustic Render Direct"}
    assert tuple(mine.size) == (4, 4) and np.array_equal(scenes.pixels_of("Caustic Render"), before)
    assert scenes.pixels_of("Caustic Render.001").shape == (24, 32, 4)


def test_a_new_resolution_goes_into_the_same_image(reports):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    scenes.set_resolution(40, 30)
    reports()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    assert 'into "Caustic Render"' in reports()
    assert "Caustic Render.001" not in bpy.data.images
    assert scenes.pixels_of("Caustic Render").shape == (30, 40, 4)


def test_the_multilayer_exr_is_compressed_and_read_back_exactly(addon, tmp_path):
    rng = np.random.default_rng(2)
    direct = rng.random((30, 40, 3)).astype(np.float32) * 9.0
    caustic = np.zeros_like(direct)
    caustic[10:20, 5:15] = 40.0
    ambient = np.full_like(direct, 0.05)
    passes = {"direct": direct, "caustic": caustic, "ambient": ambient}
    image = np.ones((30, 40, 4), dtype=np.float32)
    image[..., :3] = direct + caustic + ambient
    result = SimpleNamespace(image=image, passes=passes)
    settings = bpy.context.scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = 'MULTI_LAYER_IMAGE'
    else:
        settings.file_format = 'OPEN_EXR_MULTILAYER'
    path = tmp_path / "ml.exr"
    addon.writeback.output.save_frame(bpy.context.scene, "ViewLayer", None, result, str(path))
    channels = addon.caustic_addon.cli.image_io.read_exr_channels(path)
    assert np.array_equal(channels["ViewLayer.Caustic.G"], passes["caustic"][..., 1])
    assert path.stat().st_size < 0.6 * 30 * 40 * 13 * 4  # float32 uncompressed
    loaded = bpy.data.images.load(str(path))
    assert len(loaded.pixels) == 0 and loaded.type == 'MULTILAYER'  # the pixels asked for load the layers
    node = scenes.compositor_tree(bpy.context.scene, "Compositing").nodes.new('CompositorNodeImage')
    node.image = loaded
    assert {"Combined", "Direct", "Caustic", "Ambient"} <= {socket.name for socket in node.outputs}


def test_a_format_this_blender_cannot_write_is_refused_naming_both(tmp_path):
    scenes.ball_lens_scene(32, 24, lamp_rays=2000, segments=16, rings=8)
    png_16()
    formats = {item.identifier for item in
               bpy.context.scene.render.image_settings.bl_rna.properties["file_format"].enum_items}
    if 'AVIF' in formats:
        assert bpy.ops.caustic.render(filepath=str(tmp_path / "still.avif")) == {'FINISHED'}
        assert (tmp_path / "still.avif").read_bytes()[4:8] == b"ftyp"
    else:
        with pytest.raises(RuntimeError, match=r"'still\.avif' names the AVIF format, which this Blender cannot "
                                               r"write; the scene's output format is PNG"):
            bpy.ops.caustic.render(filepath=str(tmp_path / "still.avif"))
        assert os.listdir(tmp_path) == []
    assert bpy.context.scene.render.image_settings.file_format == 'PNG'
