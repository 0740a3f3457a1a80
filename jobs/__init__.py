"""The engine run off Blender's main thread, with the map cache kept between runs; no bpy."""

from .job import MAP_CACHE, RenderJob

__all__ = ["MAP_CACHE", "RenderJob"]
