"""Pixels of Blender images as numpy arrays, row 0 at the TOP (Blender
stores rows bottom to top)."""

import os
from collections import OrderedDict
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import textures

# Colour spaces whose byte values are linear already
LINEAR_SPACES = ("Non-Color", "Linear Rec.709", "Linear", "Raw")


def image_pixels(image) -> np.ndarray:
    """(h, w, channels) float32 of `image` as Blender holds it."""
    w, h = image.size
    pixels = np.empty(w * h * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(h, w, image.channels)[::-1]


def is_srgb_encoded(image) -> bool:
    """Whether `image`'s pixels are sRGB-encoded: a byte image whose colour
    space is not linear or data (float images are linear)."""
    return not image.is_float and image.colorspace_settings.name not in LINEAR_SPACES


# Images whose linear RGB is kept (`linear_rgb`): an HDRI's is 50 MB at 2048 x 1024.
KEPT_IMAGES = 2
_kept: OrderedDict = OrderedDict()


def linear_rgb(image) -> np.ndarray:
    """(h, w, 3) float64 linear RGB of `image`, decoded from sRGB if it is
    encoded: the very array of the last read while the image is unchanged
    (`_identity`), which the engine then keeps its world's sun, sky and
    sampling tables for (caustic_addon/emission/kept_worlds.py); Live's
    updates read no pixels again. Callers must not write into it."""
    identity = _identity(image)
    if identity is not None and identity in _kept:
        _kept.move_to_end(identity)
        return _kept[identity]
    rgb = image_pixels(image)[..., :3].astype(np.float64)
    rgb = textures.srgb_to_linear(rgb) if is_srgb_encoded(image) else rgb
    if identity is not None:
        _kept[identity] = rgb
        while len(_kept) > KEPT_IMAGES:
            _kept.popitem(last=False)
    return rgb


def _identity(image) -> Optional[tuple]:
    """What the pixels of `image` come from: its name, its file and the
    file's time, its packed data's size, what generates it, its size and
    colour space; None for an image changed in Blender and not saved
    (painted, or its pixels set), whose pixels may change unseen."""
    if image.is_dirty:
        return None
    path = bpy.path.abspath(image.filepath_raw, library=image.library)
    try:
        stamp = os.stat(path).st_mtime_ns
    except OSError:
        stamp = None
    packed = image.packed_file.size if image.packed_file is not None else None
    generated = ((image.generated_type, tuple(image.generated_color), image.use_generated_float)
                 if image.source == 'GENERATED' else None)
    return (image.name_full, path, stamp, packed, image.source, generated, tuple(image.size),
            image.colorspace_settings.name, image.is_float)


def can_read(image) -> bool:
    """Whether `image` has pixels, loading them from its file or its packed
    data if they are not in memory yet."""
    if image.has_data:
        return True
    try:
        image.pixels[0]
    except (RuntimeError, IndexError):
        return False
    return image.has_data

