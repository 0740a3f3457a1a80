"""The add-on's UI: View3D > Sidebar > Caustics, the viewport header's Caustics popover, and two entries in
the Render menu."""

import bpy

from .panels import (CAUSTIC_MT_presets, CAUSTIC_PT_camera, CAUSTIC_PT_compare, CAUSTIC_PT_eye, CAUSTIC_PT_header,
                     CAUSTIC_PT_object, CAUSTIC_PT_photons, CAUSTIC_PT_render, draw_header)
from .render_menu import draw_render_menu

_register_classes, _unregister_classes = bpy.utils.register_classes_factory((
    CAUSTIC_MT_presets,
    CAUSTIC_PT_render,
    CAUSTIC_PT_photons,
    CAUSTIC_PT_eye,
    CAUSTIC_PT_camera,
    CAUSTIC_PT_object,
    CAUSTIC_PT_compare,
    CAUSTIC_PT_header,
))


def register() -> None:
    _register_classes()
    bpy.types.TOPBAR_MT_render.append(draw_render_menu)
    bpy.types.VIEW3D_HT_header.append(draw_header)


def unregister() -> None:
    bpy.types.VIEW3D_HT_header.remove(draw_header)
    bpy.types.TOPBAR_MT_render.remove(draw_render_menu)
    _unregister_classes()
