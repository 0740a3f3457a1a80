"""The add-on's UI: View3D > Sidebar > Caustics, and two entries in the Render menu."""

import bpy

from .panels import (CAUSTIC_MT_presets, CAUSTIC_PT_camera, CAUSTIC_PT_compare, CAUSTIC_PT_eye, CAUSTIC_PT_object,
                     CAUSTIC_PT_photons, CAUSTIC_PT_render)
from .render_menu import draw_render_menu

_register_classes, _unregister_classes = bpy.utils.register_classes_factory((
    CAUSTIC_MT_presets,
    CAUSTIC_PT_render,
    CAUSTIC_PT_photons,
    CAUSTIC_PT_eye,
    CAUSTIC_PT_camera,
    CAUSTIC_PT_object,
    CAUSTIC_PT_compare,
))


def register() -> None:
    _register_classes()
    bpy.types.TOPBAR_MT_render.append(draw_render_menu)


def unregister() -> None:
    bpy.types.TOPBAR_MT_render.remove(draw_render_menu)
    _unregister_classes()
