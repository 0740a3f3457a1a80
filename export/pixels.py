"""Pixels of Blender images as numpy arrays, row 0 at the TOP (Blender
stores rows bottom to top)."""

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


def linear_rgb(image) -> np.ndarray:
    """(h, w, 3) float64 linear RGB of `image`, decoded from sRGB if it is encoded."""
    rgb = image_pixels(image)[..., :3].astype(np.float64)
    return textures.srgb_to_linear(rgb) if is_srgb_encoded(image) else rgb


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

