"""The world's light: a Background node's colour and strength, times an
Environment Texture's image if one drives its colour; or, before Blender
5.0 and without nodes, the world's plain colour."""

import bpy
import numpy as np

from ..caustic_addon import World


def _image_radiance(image) -> np.ndarray:
    """(h, w, 3) linear radiance of a Blender image, row 0 at the top: float
    images are linear already; byte images are decoded from sRGB unless
    their colour space says they are linear or data."""
    w, h = image.size
    pixels = np.empty(w * h * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(h, w, image.channels)[::-1, :, :3].astype(np.float64)
    space = image.colorspace_settings.name
    if not image.is_float and space not in ("Non-Color", "Linear Rec.709", "Linear", "Raw"):
        rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    return rgb


def engine_world(world, warnings: list[str]) -> World:
    """The world's light, or a black world (with a warning naming what is
    not understood)."""
    if world is None:
        return World()
    if world.node_tree is None or not (bpy.app.version >= (5, 0, 0) or world.use_nodes):
        return World(np.array(world.color[:], dtype=np.float64))
    output = world.node_tree.get_output_node('CYCLES')
    link = output.inputs['Surface'].links[0] if output is not None and output.inputs['Surface'].is_linked else None
    node = link.from_node if link is not None else None
    if node is None:
        return World()
    if node.bl_idname != 'ShaderNodeBackground' or node.inputs['Strength'].is_linked:
        warnings.append(f"world '{world.name}': a '{node.name}' shader is not understood, only a Background; "
                        "the world is black")
        return World()
    strength = node.inputs['Strength'].default_value
    color = node.inputs['Color']
    if not color.is_linked:
        return World(np.array(color.default_value[:3], dtype=np.float64) * strength)
    source = color.links[0].from_node
    if source.bl_idname == 'ShaderNodeTexEnvironment' and not any(s.is_linked for s in source.inputs):
        if source.image is None or not source.image.has_data and not _loads(source.image):
            warnings.append(f"world '{world.name}': the Environment Texture '{source.name}' has no image it can "
                            "read; the world is black")
            return World()
        return World(np.full(3, strength), _image_radiance(source.image))
    warnings.append(f"world '{world.name}': its Background's Color comes from '{source.name}', which is not "
                    "understood (only an Environment Texture with its own coordinates is); the world is black")
    return World()


def _loads(image) -> bool:
    """Whether a not yet loaded image can be read (from its file or packed)."""
    try:
        image.pixels[0]
    except (RuntimeError, IndexError):
        return False
    return image.has_data
