"""Caustics through transparent meshes and off mirrors: a photon pass into illumination maps
and a Whitted eye pass, on Embree. This package never imports bpy.

    from caustic_addon import render, Scene, RenderSettings
    result = render(scene, RenderSettings(photons=40_000))  # beams, the default
    result.image  # (pixy, pixx, 4) float32, linear
"""

from .cache import MapCache
from .errors import Cancelled, SceneError
from .illumination_map import PlaneChart, UVChart
from .render import RenderResult, render
from .scene import (Camera, Dielectric, Diffuse, Mesh, Object, PointLight, Reflector, RenderSettings, Scene,
                    SpotLight, SunLight)

__all__ = [
    "Camera", "Cancelled", "Dielectric", "Diffuse", "MapCache", "Mesh", "Object", "PlaneChart", "PointLight", "Reflector", "RenderResult",
    "RenderSettings", "Scene", "SceneError", "SpotLight", "SunLight", "UVChart", "render",
]
