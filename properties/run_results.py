"""WindowManager.caustic: what the last runs measured, which the operators
write and the panels only show. The window manager is not saved with the
.blend, so a run leaves the user's file as it was; the figures last until
Blender closes or loads another file."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty


class CausticRunResults(bpy.types.PropertyGroup):
    progress: FloatProperty(
        name="Progress", description="Share of the running caustic render done",
        default=0.0, min=0.0, max=1.0, subtype='FACTOR')
    last_seconds: FloatProperty(
        name="Render Time", description="Seconds the last caustic render took", default=0.0, min=0.0)
    last_lamp_rays: IntProperty(
        name="Light Rays Traced", description="Light rays the last caustic render traced, refinement's included",
        default=0, min=0)
    last_refined: IntProperty(
        name="Added by Refinement", description="Light rays that beam refinement added in the last caustic render",
        default=0, min=0)
    cycles_seconds: FloatProperty(
        name="Cycles Time", description="Seconds the last Cycles reference render took", default=0.0, min=0.0)
    cycles_reference: EnumProperty(
        name="Cycles Reference",
        description="How the last comparison's Cycles reference rendered the caustics",
        items=(('PATH_TRACED', "Path Traced", "Cycles path-traced every caustic: the reference contains them"),
               ('MNEE', "MNEE", "Cycles rendered a caustic by MNEE only, so the reference lacks part of it"),
               ('NONE', "No Caustics", "The scene has no glass or mirror: the error is over the whole image")),
        default='PATH_TRACED')
    cycles_relative_l2: FloatProperty(
        name="Relative L2", description="Error of the caustic render against Cycles over the caustics, last comparison",
        default=0.0, min=0.0)
    cycles_noise: FloatProperty(
        name="Cycles Noise", description="The Cycles reference's own noise over the caustics, last comparison",
        default=0.0, min=0.0)
    cycles_caustic_ratio: FloatProperty(
        name="Caustic Light", description="The caustic render's caustic light over Cycles', last comparison",
        default=0.0, min=0.0)
    cycles_caustic_noise: FloatProperty(
        name="Caustic Light Noise", description="Uncertainty of the caustic light's ratio from Cycles' noise",
        default=0.0, min=0.0)
    cycles_psnr: FloatProperty(
        name="PSNR (dB)", description="Peak signal-to-noise ratio of the caustic render against Cycles, last comparison",
        default=0.0)
    cycles_psnr_outside: BoolProperty(
        name="PSNR outside the Caustics",
        description="The last comparison's PSNR leaves out the caustics, which its reference cannot judge",
        default=False)


def register():
    bpy.utils.register_class(CausticRunResults)
    bpy.types.WindowManager.caustic = PointerProperty(type=CausticRunResults)


def unregister():
    del bpy.types.WindowManager.caustic
    bpy.utils.unregister_class(CausticRunResults)
