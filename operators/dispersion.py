"""CAUSTIC_OT_toggle_dispersion: the Object panel's Dispersion check box.
Dispersion is on where the object's Abbe number is above 0 (as scripts and
older files set it); turning it off keeps the number to turn it on again."""

import bpy

# The Abbe number dispersion starts at when the object never had one.
DEFAULT_ABBE = 40.0


class CAUSTIC_OT_toggle_dispersion(bpy.types.Operator):
    bl_idname = "caustic.toggle_dispersion"
    bl_label = "Dispersion"
    bl_description = "Split white light into its colors, as a prism or a diamond does"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == 'MESH'

    def execute(self, context):
        settings = context.object.caustic
        if settings.abbe > 0.0:
            settings.abbe_off, settings.abbe = settings.abbe, 0.0
        else:
            settings.abbe = settings.abbe_off if settings.abbe_off > 0.0 else DEFAULT_ABBE
        return {'FINISHED'}
