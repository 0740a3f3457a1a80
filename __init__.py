"""Caustics for Blender: registers the add-on's properties, operators and
panels. The rendering engine is `caustic_addon`, which never imports bpy."""

from . import operators, panels, properties

_MODULES = (properties, operators, panels)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        module.unregister()
