"""Rendered frames as files, by Blender's rules for its output path:
`//` is the .blend's folder, the last run of `#` in the file name is the
frame number with that many digits at least (four are appended when there
is none), and the extension and format are the scene's (Output
Properties); scene.render.frame_path applies all three. OpenEXR MultiLayer
files hold the image and each pass.

Each frame is written through the engine's `write_whole`: to a temporary
file beside its final name, checked whole by its format's structure (some
of Blender's writers, PNG's among them, say nothing when the disk fills
up), and renamed, so a write that fails leaves no half frame: a frame on
disk is either the old file or the whole new one.

A file name whose extension names another image format than the scene's
(still.exr while the output format is PNG) is written in the format it
names."""

from __future__ import annotations

import errno
import os
import re
import tempfile

import bpy
import numpy as np

from ..caustic_addon import WriteError, write_exr_channels
from ..caustic_addon import write_whole as engine_write_whole
from ..export.overrides import Overrides
from .images import PASS_NAMES

# Digits Blender appends to a path with no '#' (BLI_path_frame's default).
DEFAULT_DIGITS = 4
# File name extensions -> the image format Blender writes them in (BKE_image_path_ext_from_imformat)
EXTENSION_FORMATS = {".png": 'PNG', ".jpg": 'JPEG', ".jpeg": 'JPEG', ".exr": 'OPEN_EXR', ".tif": 'TIFF',
                     ".tiff": 'TIFF', ".bmp": 'BMP', ".tga": 'TARGA', ".rgb": 'IRIS', ".sgi": 'IRIS',
                     ".hdr": 'HDR', ".jp2": 'JPEG2000', ".j2c": 'JPEG2000', ".dpx": 'DPX', ".cin": 'CINEON',
                     ".webp": 'WEBP', ".avif": 'AVIF'}
# Formats that share an extension: either is the format the extension names.
_SAME_EXTENSION = {'OPEN_EXR_MULTILAYER': 'OPEN_EXR', 'TARGA_RAW': 'TARGA'}


class OutputError(Exception):
    """The frames cannot be written where they should go; the message says why."""


def frame_range(scene, start: int | None = None, end: int | None = None, step: int | None = None) -> list[int]:
    """The frames from `start` to `end` (the scene's range where None), every `step`-th (the scene's frame step)."""
    start = scene.frame_start if start is None else start
    end = scene.frame_end if end is None else end
    if end < start:
        what = "is empty" if end == start - 1 else "runs backwards"
        raise OutputError(f"The frame range {start} to {end} {what}: the end frame must not come before "
                          "the start frame")
    return list(range(start, end + 1, scene.frame_step if step is None else step))


def check_saved(path: str) -> None:
    """OutputError if `path` is relative to the .blend (//) and the .blend has no folder yet."""
    if path.startswith("//") and not bpy.data.is_saved:
        raise OutputError(f"The output path '{path}' is relative to the .blend file, which is not saved yet: "
                          "save it, or give an absolute path")


def frame_paths(scene, frames: list[int], filepath: str = "") -> dict[int, str]:
    """frame -> absolute file path, from `filepath` or else the scene's
    output path. Raises OutputError for a movie format, a `//` path of an
    unsaved file, or fewer `#` than the frame numbers have digits."""
    if scene.render.is_movie_format:
        raise OutputError(f"The output format is a movie ({scene.render.image_settings.file_format}): "
                          "caustic frames are written as images; choose an image format in Output Properties")
    with Overrides() as overrides:
        if filepath:
            overrides.set(scene.render, "filepath", filepath)
            if os.path.splitext(filepath)[1].lower() in EXTENSION_FORMATS:
                # the extension given is kept, and names the format (file_format), as Blender would change it
                overrides.set(scene.render, "use_file_extension", False)
        template = scene.render.filepath
        paths = {frame: scene.render.frame_path(frame=frame) for frame in frames}
    check_saved(template)
    runs = re.findall("#+", os.path.basename(template))
    digits = len(runs[-1]) if runs else DEFAULT_DIGITS
    widest = max(frames, key=lambda frame: len(str(frame)))
    if len(str(widest)) > digits:
        raise OutputError(f"The output path '{template}' has {digits} '#' for the frame number, but frame "
                          f"{widest} has {len(str(widest))} digits, so the files would not sort in frame order: "
                          f"use {'#' * len(str(widest))}")
    return paths


def check_writable(paths) -> None:
    """Make the folders of `paths` as Blender does, and check a file can be
    written in each; OutputError names the folder that cannot be written."""
    for folder in sorted({os.path.dirname(path) for path in paths}):
        try:
            os.makedirs(folder, exist_ok=True)
            handle, probe = tempfile.mkstemp(dir=folder, prefix=".caustic-probe-")
            os.close(handle)
            os.remove(probe)
        except OSError as exc:
            raise OutputError(f"Cannot write the frames into the folder '{folder}': {exc.strerror or exc}") from exc


def write_whole(path: str, write, file_format: str) -> None:
    """`write(temporary path)` writes a `file_format` file, which the
    engine's write_whole checks whole and renames to `path`; OutputError says why not."""
    try:
        engine_write_whole(path, write, file_format)
    except WriteError as exc:
        raise OutputError(str(exc)) from exc


def blender_reason(exc: RuntimeError) -> str:
    """The first line of a Blender error, without its "Error: Could not write image: " prefix."""
    line = next((line for line in str(exc).splitlines() if line.strip()), "")
    return line.removeprefix("Error: ").removeprefix("Could not write image: ")


def write_float_exr(path: str, rgba: np.ndarray) -> None:
    """`rgba (h,w,4)`, row 0 at the top, as a float32 EXR written whole at `path`."""
    try:
        write_exr_channels(path, {c: rgba[..., i] for i, c in enumerate("RGBA")})
    except WriteError as exc:
        raise OutputError(str(exc)) from exc


def multilayer_channels(layer: str, image: np.ndarray, passes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Channel name -> (h,w) of the `image (h,w,4)` as the Combined pass and
    each of `passes` (name -> (h,w,3)) as its own, in view layer `layer`,
    named "<layer>.<pass>.<channel>" as Blender names them."""
    channels = {f"{layer}.Combined.{c}": image[..., i] for i, c in enumerate("RGBA")}
    for name, rgb in passes.items():
        channels.update({f"{layer}.{PASS_NAMES[name]}.{c}": rgb[..., i] for i, c in enumerate("RGB")})
    return channels


def file_format(scene, path: str) -> str:
    """The image format `path` is written in: the scene's output format,
    unless the file name's extension names another."""
    scene_format = scene.render.image_settings.file_format
    named = EXTENSION_FORMATS.get(os.path.splitext(path)[1].lower())
    if named is None or named == _SAME_EXTENSION.get(scene_format, scene_format):
        return scene_format
    return named


def save_frame(scene, layer: str, image, result, path: str) -> None:
    """The rendered `result` (RenderResult) saved whole at `path` in its
    format (file_format): a multilayer EXR with every pass, or Blender's
    writer of the format on `image` (the bpy image holding the result),
    with the scene's settings of the format (colour depth, codec, colour
    management)."""
    settings = scene.render.image_settings
    written = file_format(scene, path)
    if written == 'OPEN_EXR_MULTILAYER':
        channels = multilayer_channels(layer, result.image, result.passes)
        try:
            write_exr_channels(path, channels)
        except WriteError as exc:
            raise OutputError(str(exc)) from exc
        return
    scene_format = settings.file_format
    with Overrides() as overrides:
        if written != scene_format:
            overrides.keep(settings, "color_depth", "color_mode", "exr_codec", "file_format")
            if hasattr(settings, "media_type"):  # Blender 5: a multilayer EXR is a media type of its own
                overrides.set(settings, "media_type", 'IMAGE')
            try:
                settings.file_format = written
            except TypeError:
                raise OutputError(f"'{os.path.basename(path)}' names the {written} format, which this Blender "
                                  f"cannot write; the scene's output format is {scene_format}: give the "
                                  "file that format's extension, or choose another output format") from None
            if written == 'OPEN_EXR':  # the render's floats as they are, whatever depth the scene's format had
                settings.color_depth = '32'

        def write(temporary: str) -> None:
            try:
                image.save_render(temporary, scene=scene)
            except RuntimeError as exc:
                reason = blender_reason(exc)
                full = reason == os.strerror(errno.ENOSPC)
                raise OSError(errno.ENOSPC if full else errno.EIO, reason) from exc

        write_whole(path, write, written)
