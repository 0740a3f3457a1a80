"""Sidebar panels: they draw properties and operator buttons, nothing else."""

import math

import bpy

from ..operators.paper_scene import CAUSTIC_OT_add_paper_scene
from ..operators.presets import CAUSTIC_OT_apply_preset
from ..operators.engine_run import EngineOperator
from ..live import session as live


class CAUSTIC_MT_presets(bpy.types.Menu):
    bl_label = "Caustics Presets"

    def draw(self, context):
        layout = self.layout
        layout.operator_enum(CAUSTIC_OT_apply_preset.bl_idname, "preset")
        layout.separator()
        layout.label(text="Add the Paper's Scene")
        layout.operator_enum(CAUSTIC_OT_add_paper_scene.bl_idname, "shape")


class _CausticPanel:
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Caustics"


class CAUSTIC_PT_render(_CausticPanel, bpy.types.Panel):
    bl_label = "Caustics"

    def draw(self, context):
        layout, props, run = self.layout, context.scene.caustic, context.window_manager.caustic
        row = layout.row(align=True)
        row.scale_y = 1.4
        row.operator("caustic.render", icon='RENDER_STILL')
        row.operator("caustic.render_animation", text="Animation", icon='RENDER_ANIMATION')
        if EngineOperator.running:
            layout.progress(factor=run.progress, type='BAR', text=f"{run.progress:.0%}  (Esc cancels)")
        if run.last_seconds > 0:
            col = layout.column(align=True)
            col.label(text=f"Last render: {run.last_seconds:.1f} s")
            col.label(text=f"Light rays traced: {run.last_lamp_rays:,}")
            if run.last_refined:
                col.label(text=f"  of which refinement added {run.last_refined:,}")
        draw_bake(layout, props)


def draw_bake(layout, props) -> None:
    """Live, Bake and what they say: the sidebar's and the viewport header's."""
    layout.operator("caustic.toggle_live", icon='PAUSE' if props.use_live else 'PLAY', depress=props.use_live)
    session = live.SESSION
    if props.use_live and session is not None and session.message:
        layout.label(text=session.message, icon='ERROR')
    row = layout.row(align=True)
    row.operator("caustic.bake", icon='TEXTURE')
    row.operator("caustic.bake_animation", text="Animation", icon='RENDER_ANIMATION')
    row.operator("caustic.unbake", text="", icon='X')
    layout.prop(props, "use_bake_on_render")


class CAUSTIC_PT_header(bpy.types.Panel):
    """The viewport header's Caustics popover."""

    bl_space_type = 'VIEW_3D'
    bl_region_type = 'HEADER'
    bl_label = "Caustics"

    def draw(self, context):
        draw_bake(self.layout, context.scene.caustic)


def draw_header(self, context) -> None:
    """The popover's button in the 3D Viewport's header."""
    icon = 'LIGHT_SUN' if context.scene.caustic.use_live else 'LIGHT'
    self.layout.popover(panel="CAUSTIC_PT_header", text="Caustics", icon=icon)


class CAUSTIC_PT_photons(_CausticPanel, bpy.types.Panel):
    bl_label = "Illumination Map"
    bl_parent_id = "CAUSTIC_PT_render"

    def draw(self, context):
        layout, props = self.layout, context.scene.caustic
        layout.menu(CAUSTIC_MT_presets.__name__, text="Presets", icon='PRESET')
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "lamp_rays")
        layout.prop(props, "emission")
        layout.prop(props, "energy")
        layout.prop(props, "use_auto_map_scale")
        sub = layout.column()
        sub.active = not props.use_auto_map_scale
        sub.prop(props, "map_scale")
        layout.prop(props, "density")
        if props.density == 'BEAM':
            layout.prop(props, "beam_refinement")
        layout.prop(props, "max_depth")
        layout.prop(props, "bands")


class CAUSTIC_PT_eye(_CausticPanel, bpy.types.Panel):
    bl_label = "Sampling"
    bl_parent_id = "CAUSTIC_PT_render"

    def draw(self, context):
        layout, scene = self.layout, context.scene
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(scene.caustic, "spp")
        layout.prop(scene.caustic, "edge_samples")
        layout.prop(scene.caustic, "lamp_samples")
        layout.prop(scene.caustic, "world_samples")
        layout.prop(scene.caustic, "ambient")


class CAUSTIC_PT_camera(_CausticPanel, bpy.types.Panel):
    bl_label = "Camera"
    bl_parent_id = "CAUSTIC_PT_eye"
    bl_description = "The scene's resolution and the active camera's field of view: the paper's pixx, pixy and FOV"

    def draw(self, context):
        layout, scene = self.layout, context.scene
        layout.use_property_split = True
        layout.use_property_decorate = False
        col = layout.column(align=True)
        col.prop(scene.render, "resolution_x", text="Resolution X")
        col.prop(scene.render, "resolution_y", text="Y")
        col.prop(scene.render, "resolution_percentage", text="%")
        if scene.camera is None or scene.camera.type != 'CAMERA':
            layout.label(text="No active camera", icon='ERROR')
        elif scene.camera.data.type == 'PERSP':
            layout.prop(scene.camera.data, "angle")


class CAUSTIC_PT_object(_CausticPanel, bpy.types.Panel):
    bl_label = "Object"
    bl_parent_id = "CAUSTIC_PT_render"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == 'MESH'

    def draw(self, context):
        layout, settings = self.layout, context.object.caustic
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.label(text=context.object.name, icon='OBJECT_DATA')
        layout.prop(settings, "role")
        if settings.role in {'AUTO', 'TRANSPARENT'}:
            row = layout.row(heading="Override IOR")
            row.prop(settings, "use_ior", text="")
            sub = row.row()
            sub.active = settings.use_ior
            sub.prop(settings, "ior", text="")
            row = layout.row(heading="Dispersion")
            on = settings.abbe > 0.0
            row.operator("caustic.toggle_dispersion", text="", emboss=False,
                         icon='CHECKBOX_HLT' if on else 'CHECKBOX_DEHLT')
            if on:
                row.prop(settings, "abbe", text="")
            layout.prop(settings, "absorption_from")
            if settings.absorption_from == 'COEFFICIENT':
                layout.prop(settings, "absorption")
            elif settings.absorption_from == 'COLOR':
                layout.prop(settings, "absorption_color")
                layout.prop(settings, "absorption_distance")


class CAUSTIC_PT_compare(_CausticPanel, bpy.types.Panel):
    bl_label = "Compare with Cycles"
    bl_parent_id = "CAUSTIC_PT_render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout, props = self.layout, context.scene.caustic
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "cycles_samples")
        layout.prop(props, "cycles_time_limit")
        layout.operator("caustic.compare_cycles", icon='IMAGE_REFERENCE')
        run = context.window_manager.caustic
        if run.cycles_seconds > 0:
            col = layout.column(align=True)
            col.label(text=f"Caustics: {run.last_seconds:.1f} s   Cycles: {run.cycles_seconds:.1f} s")
            if run.cycles_reference == 'MNEE':
                col.label(text="Cycles lacks part of the caustic (MNEE)", icon='ERROR')
                if run.cycles_caustic_ratio > 0:
                    col.label(text=f"Caustic light Cycles holds: {1.0 / run.cycles_caustic_ratio:.0%}")
            else:
                over = " (caustics)" if run.cycles_reference == 'PATH_TRACED' else ""
                col.label(text=f"Relative L2{over}: {run.cycles_relative_l2:.3f}")
                col.label(text=f"Noise of Cycles{over}: {run.cycles_noise:.3f}")
                if run.cycles_reference == 'PATH_TRACED':
                    col.label(text=f"Caustic light: {run.cycles_caustic_ratio:.2f} "
                                   f"± {run.cycles_caustic_noise:.2f} of Cycles'")
                if run.cycles_psnr_outside:
                    col.label(text="Cycles too noisy to judge the caustics", icon='ERROR')
            where = " outside caustics" if run.cycles_psnr_outside else ""
            col.label(text=f"PSNR{where}: {run.cycles_psnr:.1f} dB" if math.isfinite(run.cycles_psnr)
                      else "PSNR: identical")
