"""The Blender scene converted into the engine's: objects, materials, lamps, camera, world and settings."""

from .errors import InputError
from .scene import SceneRead, read_for_bake, read_scene
from .settings import bake_settings, render_settings

__all__ = ["InputError", "SceneRead", "bake_settings", "read_for_bake", "read_scene", "render_settings"]
