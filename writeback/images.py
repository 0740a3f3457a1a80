"""Float images written into Blender. Arrays here are (h, w, 4) float32
linear RGBA with row 0 at the TOP; Blender stores rows bottom to top."""

import uuid

import bpy
import numpy as np
from bpy.app.handlers import persistent

# RenderResult.passes by the names Blender shows: images "<render> <pass>" and multilayer EXR passes
PASS_NAMES = {"direct": "Direct", "caustic": "Caustic", "ambient": "Ambient"}
# ID property: which write an image's packed EXR holds
SERIAL = "caustic_pixels"
# ID property: the name the add-on writes an image under ("Caustic Render"), whatever Blender named it
OWNER = "caustic_image"
# image name -> the write whose pixels are in that image's buffer
_in_memory: dict[str, str] = {}


def working_colorspace() -> str:
    """The scene-linear colour space Blender renders in (5.0+ lets the user choose it)."""
    colorspace = getattr(bpy.data, "colorspace", None)
    return colorspace.working_space if colorspace is not None else "Linear Rec.709"


def own_image(name: str):
    """The image the add-on writes under `name`, or None: the image of that
    name if the add-on made it, else the one it made when another image
    (the user's) had the name, which Blender then named "<name>.001"."""
    image = bpy.data.images.get(name)
    if image is not None and (image.get(OWNER) == name or SERIAL in image):  # SERIAL alone: an earlier version's
        return image
    return next((image for image in bpy.data.images if image.get(OWNER) == name), None)


def write_image(name: str, rgba: np.ndarray, pack: bool = True):
    """The add-on's image `name` (own_image; float, linear) holding `rgba
    (h,w,4)`, made if there is none; an image of the name that the add-on
    did not make is never touched, and the one written may then be named
    otherwise: report `image.name`. With `pack`, the
    pixels are packed as a float EXR: undo and redo rebuild images from the
    .blend's data, so pixels that are only in memory would come back blank
    (see `drop_stale_pixels`). Without, they are there only for Blender's
    file writers, until a packed write replaces them."""
    h, w = rgba.shape[:2]
    image = own_image(name)
    if image is None:
        image = bpy.data.images.new(name, w, h, alpha=True, float_buffer=True)
        image[OWNER] = name
    elif tuple(image.size) != (w, h) or not image.is_float:
        if image.source != 'GENERATED':  # packed, or saved by the user: a buffer of the new size
            image.source = 'GENERATED'
        image.generated_width, image.generated_height = w, h
        image.use_generated_float = True
    if image.colorspace_settings.name != working_colorspace():
        image.colorspace_settings.name = working_colorspace()
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1], dtype=np.float32).ravel())
    image.update()
    if pack:
        pack_image(image)
    return image


def pack_image(image) -> None:
    """Pack the pixels `image` holds as a float EXR, for undo and saving
    (write_image)."""
    image.file_format = 'OPEN_EXR'
    image.pack()
    image[SERIAL] = _in_memory[image.name] = uuid.uuid4().hex


def write_passes(prefix: str, passes: dict[str, np.ndarray]) -> None:
    """Each of `passes` (name -> (h,w,3) linear RGB) into the image "`prefix` <pass>", alpha 1."""
    for name, rgb in passes.items():
        rgba = np.ones(rgb.shape[:2] + (4,), dtype=np.float32)
        rgba[..., :3] = rgb
        write_image(f"{prefix} {PASS_NAMES[name]}", rgba)


@persistent
def drop_stale_pixels(*_) -> None:
    """After an undo or redo: an image restores its packed EXR but keeps the
    pixels it had in memory. Where those are another write's, free them, and
    Blender decodes the restored EXR when the pixels are next needed."""
    for image in bpy.data.images:
        serial = image.get(SERIAL)
        if serial is not None and _in_memory.get(image.name) != serial:
            image.buffers_free()
            _in_memory[image.name] = serial


def register() -> None:
    bpy.app.handlers.undo_post.append(drop_stale_pixels)
    bpy.app.handlers.redo_post.append(drop_stale_pixels)


def unregister() -> None:
    bpy.app.handlers.undo_post.remove(drop_stale_pixels)
    bpy.app.handlers.redo_post.remove(drop_stale_pixels)


def show_image(context, image) -> None:
    """Show `image` in the first Image Editor on screen, if there is one."""
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == 'IMAGE_EDITOR':
                area.spaces.active.image = image
                area.tag_redraw()
                return
