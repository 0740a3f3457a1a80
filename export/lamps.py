"""Blender's point, spot and sun lights as the engine's lamps, at Blender's
power, colour, temperature and exposure."""

import numpy as np

from ..caustic_addon import PointLight, SpotLight, SunLight


def engine_light(ob_eval, matrix: np.ndarray, name: str, warnings: list[str]):
    """The engine lamp for a Blender light object, or None (with a warning) if it has none."""
    light = ob_eval.data
    color = np.array(light.color[:], dtype=np.float64)
    if getattr(light, "use_temperature", False):
        color *= np.array(light.temperature_color[:], dtype=np.float64)
    power = light.energy * 2.0 ** getattr(light, "exposure", 0.0)
    position, down = matrix[:3, 3], -matrix[:3, 2]
    if light.type == 'POINT':
        return PointLight(position, power, color, name=name)
    if light.type == 'SPOT':
        return SpotLight(position, down, power, light.spot_size, light.spot_blend, color, name=name)
    if light.type == 'SUN':
        return SunLight(down, power, color, name=name)
    warnings.append(f"lamp '{name}': {light.type.lower()} lamps are not supported; it was left out")
    return None
