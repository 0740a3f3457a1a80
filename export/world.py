"""The world's light: a Background node's colour and strength, times an
Environment Texture's image if one drives its colour; any other tree (a
Sky Texture, a rotated or mixed environment) baked by Cycles
(`world_bake.py`); or, before Blender 5.0 and without nodes, the world's
plain colour."""

import bpy
import numpy as np

from ..caustic_addon import World
from .pixels import can_read, linear_rgb
from .world_bake import bake_world


def _direct(world, node, warnings: list[str]):
    """The World of a Background `node` read without Cycles, or None if its
    inputs need a bake (a World() when they name an image that cannot be read)."""
    if node.bl_idname != 'ShaderNodeBackground' or node.inputs['Strength'].is_linked:
        return None
    strength = node.inputs['Strength'].default_value
    color = node.inputs['Color']
    if not color.is_linked:
        return World(np.array(color.default_value[:3], dtype=np.float64) * strength)
    source = color.links[0].from_node
    if source.bl_idname != 'ShaderNodeTexEnvironment' or any(s.is_linked for s in source.inputs):
        return None
    if source.image is None or not can_read(source.image):
        warnings.append(f"world '{world.name}': the Environment Texture '{source.name}' has no image it can "
                        "read; the world is black")
        return World()
    return World(np.full(3, strength), linear_rgb(source.image))


def engine_world(world, warnings: list[str]) -> World:
    """The world's light, or a black world (with a warning naming the world
    and the node) when it cannot be read."""
    if world is None:
        return World()
    if world.node_tree is None or not (bpy.app.version >= (5, 0, 0) or world.use_nodes):
        return World(np.array(world.color[:], dtype=np.float64))
    output = world.node_tree.get_output_node('CYCLES')
    if output is None or not output.inputs['Surface'].is_linked:
        return World()
    read = _direct(world, output.inputs['Surface'].links[0].from_node, warnings)
    if read is not None:
        return read
    path_tricks = [n.name for n in world.node_tree.nodes if n.bl_idname == 'ShaderNodeLightPath']
    if path_tricks:
        warnings.append(f"world '{world.name}': its Light Path node '{path_tricks[0]}' gives the camera and "
                        "the lighting different worlds; the caustic render takes the one the camera sees")
    baked = bake_world(world, warnings)
    return World(np.ones(3), baked) if baked is not None else World()
