"""Exceptions the engine raises on purpose; anything else is a bug."""


class SceneError(ValueError):
    """The scene cannot be rendered; the message names the object or field."""


class Cancelled(Exception):
    """The caller's cancel callback asked the render to stop."""
