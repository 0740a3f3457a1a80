"""What stops an operator before the engine runs."""


class InputError(Exception):
    """The Blender scene cannot be rendered as it is; the message tells the user why."""
