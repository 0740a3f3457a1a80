"""Rendered frames as files, by Blender's rules for its output path:
`//` is the .blend's folder, the last run of `#` in the file name is the
frame number with that many digits at least (four are appended when there
is none), and the extension and format are the scene's (Output
Properties); scene.render.frame_path applies all three. OpenEXR MultiLayer
files hold the image and each pass.

Each frame is written to a temporary file beside its final name and renamed
once whole, so a write that fails (a full disk) leaves no half frame: a
frame on disk is either the old file or the whole new one."""

from __future__ import annotations

import os
import re
import tempfile
import uuid

import bpy
import numpy as np

from ..caustic_addon import write_exr_channels
from ..export.overrides import Overrides
from .images import PASS_NAMES

# Digits Blender appends to a path with no '#' (BLI_path_frame's default).
DEFAULT_DIGITS = 4


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


def write_whole(path: str, write) -> None:
    """`write(temporary path)`, then the file renamed to `path`; on failure
    the temporary file is removed and OutputError says why."""
    folder, name = os.path.split(path)
    temporary = os.path.join(folder, f".{name}.{uuid.uuid4().hex[:8]}.part")
    try:
        write(temporary)
        if not os.path.isfile(temporary):
            raise OSError("nothing was written")
        os.replace(temporary, path)
    except (OSError, RuntimeError) as exc:
        if os.path.exists(temporary):
            os.remove(temporary)
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else blender_reason(exc)
        raise OutputError(f"could not write '{path}': {reason}") from exc


def blender_reason(exc: RuntimeError) -> str:
    """The first line of a Blender error, without its "Error: Could not write image: " prefix."""
    line = next((line for line in str(exc).splitlines() if line.strip()), "")
    return line.removeprefix("Error: ").removeprefix("Could not write image: ")


def write_float_exr(path: str, rgba: np.ndarray) -> None:
    """`rgba (h,w,4)`, row 0 at the top, as a float32 EXR written whole at `path`."""
    write_whole(path, lambda temporary: write_exr_channels(temporary, {c: rgba[..., i] for i, c in enumerate("RGBA")}))


def multilayer_channels(layer: str, image: np.ndarray, passes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Channel name -> (h,w) of the `image (h,w,4)` as the Combined pass and
    each of `passes` (name -> (h,w,3)) as its own, in view layer `layer`,
    named "<layer>.<pass>.<channel>" as Blender names them."""
    channels = {f"{layer}.Combined.{c}": image[..., i] for i, c in enumerate("RGBA")}
    for name, rgb in passes.items():
        channels.update({f"{layer}.{PASS_NAMES[name]}.{c}": rgb[..., i] for i, c in enumerate("RGB")})
    return channels


def save_frame(scene, layer: str, image, result, path: str) -> None:
    """The rendered `result` (RenderResult) saved whole at `path` in the
    scene's format: a multilayer EXR with every pass, or Blender's writer of
    the format on `image` (the bpy image holding the result)."""
    if scene.render.image_settings.file_format == 'OPEN_EXR_MULTILAYER':
        write_whole(path, lambda temporary: write_exr_channels(
            temporary, multilayer_channels(layer, result.image, result.passes)))
    else:
        write_whole(path, lambda temporary: image.save_render(temporary, scene=scene))
