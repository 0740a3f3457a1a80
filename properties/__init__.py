"""The add-on's settings, one PropertyGroup per ID type: Scene.caustic and
Object.caustic; and the last runs' figures, WindowManager.caustic."""

from . import object_settings, run_results, scene_settings

_MODULES = (run_results, scene_settings, object_settings)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        module.unregister()
