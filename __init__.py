"""Caustics for Blender: registers the add-on's properties, operators, panels,
the handlers that keep its images right through undo and Live's. The rendering
engine is `caustic_addon`, which never imports bpy."""

from . import live, operators, panels, properties, writeback

_MODULES = (properties, operators, writeback, live, panels)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        module.unregister()
