"""Blender's Render menu (the top bar): Render Image and Render Animation with this add-on's caustics baked first."""

from ..operators.render_with_caustics import (CAUSTIC_OT_render_animation_with_caustics,
                                              CAUSTIC_OT_render_image_with_caustics)


def draw_render_menu(self, context) -> None:
    layout = self.layout
    layout.separator()
    layout.operator(CAUSTIC_OT_render_image_with_caustics.bl_idname, icon='RENDER_STILL')
    layout.operator(CAUSTIC_OT_render_animation_with_caustics.bl_idname, icon='RENDER_ANIMATION')
