"""Blender's lights as the engine's lamps, as Cycles reads them: power,
colour, temperature and exposure (4.5+), Normalize (4.5+), a point or spot
lamp's radius and Soft Falloff, a sun's angle, an area lamp's shape, size and
spread, and an Emission node's colour and strength in the light's nodes."""

import math

import bpy
import numpy as np

from ..caustic_addon import AreaLight, PointLight, SpotLight, SunLight

# Blender's area shapes: the engine's shape, and whether Size Y applies
AREA_SHAPES = {'SQUARE': ("RECTANGLE", False), 'RECTANGLE': ("RECTANGLE", True),
               'DISK': ("ELLIPSE", False), 'ELLIPSE': ("ELLIPSE", True)}


def _node_emission(light, name: str, warnings: list[str]) -> np.ndarray:
    """(3,) what the light's node tree multiplies its emission by: an
    Emission node's Color x Strength into the Light Output, 1 without nodes."""
    tree = light.node_tree if bpy.app.version >= (5, 0, 0) or light.use_nodes else None
    if tree is None:
        return np.ones(3)
    output = next((n for n in tree.nodes if n.bl_idname == 'ShaderNodeOutputLight' and n.is_active_output), None)
    socket = output.inputs['Surface'] if output is not None else None
    node = socket.links[0].from_node if socket is not None and socket.is_linked else None
    if node is None:
        return np.ones(3)
    if node.bl_idname != 'ShaderNodeEmission' or any(s.is_linked for s in node.inputs):
        warnings.append(f"light '{name}': only a plain Emission node is understood in its nodes; "
                        "they are ignored")
        return np.ones(3)
    return np.array(node.inputs['Color'].default_value[:3], dtype=np.float64) * node.inputs['Strength'].default_value


def engine_light(ob_eval, matrix: np.ndarray, name: str, warnings: list[str]):
    """The engine lamp for a Blender light object."""
    light = ob_eval.data
    color = np.array(light.color[:], dtype=np.float64) * _node_emission(light, name, warnings)
    if getattr(light, "use_temperature", False):
        color *= np.array(light.temperature_color[:], dtype=np.float64)
    power = light.energy * 2.0 ** getattr(light, "exposure", 0.0)
    # Normalize off (4.5+): the power is not divided by the lamp's area
    # (Cycles' Light.area(): 4 pi r^2, or 4 for a point; pi sin^2(angle/2);
    # an area lamp's area), so the engine's power is that much more
    normalized = getattr(light, "normalize", True)
    position, down = matrix[:3, 3], -matrix[:3, 2]
    # Blender keeps angles in float32, whose pi is a hair above math.pi: 180 degrees is math.pi
    if light.type == 'SUN':
        angle = min(light.angle, math.pi)
        if not normalized and angle > 0.0:
            power *= math.pi * math.sin(0.5 * angle) ** 2
        return SunLight(down, power, color, name=name, angle=angle)
    if light.type == 'AREA':
        shape, own_y = AREA_SHAPES[light.shape]
        axis_x = matrix[:3, 0] * (0.5 * light.size)
        axis_y = matrix[:3, 1] * (0.5 * (light.size_y if own_y else light.size))
        spread = min(light.spread, math.pi)
        lamp = AreaLight(position, axis_x, axis_y, down, power, shape, spread, color, name=name)
        if not normalized:
            lamp.power *= lamp.area
        return lamp
    radius = light.shadow_soft_size
    if not normalized:
        power *= 4.0 * math.pi * radius ** 2 if radius > 0 else 4.0
    sized = dict(radius=radius, soft_falloff=light.use_soft_falloff)
    if light.type == 'SPOT':
        return SpotLight(position, down, power, min(light.spot_size, math.pi), light.spot_blend, color, name=name,
                         **sized)
    return PointLight(position, power, color, name=name, **sized)
