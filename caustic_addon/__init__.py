"""Caustics through transparent meshes and off mirrors: a photon pass into
illumination maps and a Whitted eye pass, on Embree. This package never
imports bpy: a numpy scene goes in, float arrays come out.

    from caustic_addon import render, Scene, RenderSettings
    result = render(scene, RenderSettings(lamp_rays=40_000))  # beams, the default
    result.image  # (pixy, pixx, 4) float32, linear

The stages, in the order data flows through them: scene (the model), tracing
(Embree), emission (the lamps), passes (photons, beams, eye rays), maps (the
illumination maps), renderer (all of it, in one call); beneath them util,
sampling and optics; beside them cli, the command line.

A render sets glibc's malloc to reuse what it frees
(util.heap.reuse_freed_memory) before it starts its threads.
"""

from .cli.files import WriteError, write_whole
from .cli.image_io import write_exr_channels
from .errors import Cancelled, SceneError
from .maps.cache import MapCache
from .maps.charts import ImageFrame
from .maps.illumination_map import IlluminationMap
from .memory import refusal as memory_refusal
from .optics.media import absorption_from_color, volume_absorption
from .renderer import RenderResult, render
from .scene import (AreaLight, Camera, Coat, Dielectric, Diffuse, Mesh, Object, PointLight, Reflector,
                    RenderSettings, Scene, Specular, SpotLight, SunLight, Visibility, World, paper, shapes, textures)
from .util.jit import compile_kernels, use_kernel_cache

__all__ = [
    "AreaLight", "Camera", "Cancelled", "Coat", "Dielectric", "Diffuse", "IlluminationMap", "ImageFrame", "MapCache",
    "Mesh", "Object", "PointLight", "Reflector",
    "RenderResult", "RenderSettings", "Scene", "SceneError", "Specular", "SpotLight", "SunLight", "Visibility", "World",
    "WriteError",
    "absorption_from_color", "compile_kernels", "memory_refusal",
    "paper", "render", "shapes", "textures", "use_kernel_cache", "volume_absorption", "write_exr_channels",
    "write_whole",
]
