"""The world as the background the camera sees: a plain colour, or black."""

import bpy
import numpy as np


def background(world, warnings: list[str]) -> np.ndarray:
    """(3,) radiance the camera sees where it sees nothing: the world's plain colour."""
    if world is None:
        return np.zeros(3)
    if world.node_tree is None or not (bpy.app.version >= (5, 0, 0) or world.use_nodes):
        return np.array(world.color[:], dtype=np.float64)
    output = world.node_tree.get_output_node('CYCLES')
    link = output.inputs['Surface'].links[0] if output is not None and output.inputs['Surface'].is_linked else None
    node = link.from_node if link is not None else None
    if node is None or node.bl_idname != 'ShaderNodeBackground' or any(s.is_linked for s in node.inputs):
        warnings.append(f"world '{world.name}': only a plain Background colour is understood; "
                        "the background is black")
        return np.zeros(3)
    return np.array(node.inputs['Color'].default_value[:3], dtype=np.float64) * node.inputs['Strength'].default_value
