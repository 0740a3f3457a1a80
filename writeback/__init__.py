"""The engine's results written into Blender: images, the bake's node groups, a run's figures, the paper's scene."""

from .images import register, unregister

__all__ = ["register", "unregister"]
