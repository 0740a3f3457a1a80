"""The engine run off Blender's main thread, one job or a run of them, with the map cache kept between runs; no bpy."""

from .job import LOWER_RESOLUTION, MAP_CACHE, RenderJob, map_rgba, refusal
from .runner import JobRunner, StepError

__all__ = ["LOWER_RESOLUTION", "MAP_CACHE", "JobRunner", "RenderJob", "StepError", "map_rgba", "refusal"]
