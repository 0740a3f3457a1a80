"""The add-on's settings, one PropertyGroup per ID type: Scene.caustic and Object.caustic."""

from . import object_settings, scene_settings

_MODULES = (scene_settings, object_settings)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        module.unregister()
