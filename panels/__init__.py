"""The add-on's UI: View3D > Sidebar > Caustics."""

import bpy

from .panels import (CAUSTIC_MT_presets, CAUSTIC_PT_camera, CAUSTIC_PT_compare, CAUSTIC_PT_eye, CAUSTIC_PT_object,
                     CAUSTIC_PT_photons, CAUSTIC_PT_render)

register, unregister = bpy.utils.register_classes_factory((
    CAUSTIC_MT_presets,
    CAUSTIC_PT_render,
    CAUSTIC_PT_photons,
    CAUSTIC_PT_eye,
    CAUSTIC_PT_camera,
    CAUSTIC_PT_object,
    CAUSTIC_PT_compare,
))
