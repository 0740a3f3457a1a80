"""Caustics for Blender: registers the add-on's properties, operators, panels
and the handlers that keep its images right through undo. The rendering engine
is `caustic_addon`, which never imports bpy."""

from . import operators, panels, properties, writeback

_MODULES = (properties, operators, writeback, panels)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        module.unregister()
