"""CAUSTIC_OT_toggle_live: the Live button. Turning Live on starts it at
once; turning it off takes out what Live added (live/session.py). A script
may set Scene.caustic.use_live too: Live then starts at the next change."""

import bpy

from ..live import session


class CAUSTIC_OT_toggle_live(bpy.types.Operator):
    bl_idname = "caustic.toggle_live"
    bl_label = "Live"
    bl_description = "Keep the receivers' caustics up to date as you work, in the viewport and in renders"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):
        props = context.scene.caustic
        props.use_live = not props.use_live
        if props.use_live:
            session.start(context.scene)
        else:
            session.stop()
        return {'FINISHED'}
