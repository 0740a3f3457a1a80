"""Scene.caustic: the render settings, named as in the paper where it has a
name (the paper's "lamp rays" are Light Rays, its "lamp energy" Light
Energy). What a run measures is on WindowManager.caustic (run_results.py)."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, PointerProperty


class CausticSceneSettings(bpy.types.PropertyGroup):
    lamp_rays: IntProperty(
        name="Light Rays",
        description="Rays traced from all lights toward the glass and mirrors; more sharpen the finest caustics",
        default=40_000, min=0, soft_max=10_000_000)
    emission: EnumProperty(
        name="Emission",
        description="Where the lights send their rays",
        items=[('TARGETED', "Targeted", "Only toward transparent and reflecting objects, so every ray can make "
                                        "a caustic"),
               ('SPHERE', "Sphere", "Over the whole sphere of directions, as the paper does")],
        default='TARGETED')
    energy: FloatProperty(
        name="Light Energy",
        description="Multiplier on every light's power, the paper's lamp energy; at 1 lights are as bright as in Cycles",
        default=1.0, min=0.0, soft_max=100.0)
    use_auto_map_scale: BoolProperty(
        name="Auto Map Scale",
        description="Size each receiver's illumination map cells from the receiver itself",
        default=True)
    map_scale: FloatProperty(
        name="Map Scale",
        description="Edge of one illumination map cell, the paper's map scale; larger cells blur the caustic",
        subtype='DISTANCE', unit='LENGTH', default=0.005, min=1e-6, soft_min=1e-4, soft_max=0.1,
        step=0.1, precision=4)
    density: EnumProperty(
        name="Density",
        description="How the light rays that reach a receiver become its caustic",
        items=[('BEAM', "Beam", "Neighbouring rays on a grid bound beams of light: no noise, sharp caustics"),
               ('ADAPTIVE', "Adaptive", "Each point averages its nearest rays: sharp where they are dense"),
               ('SPLAT', "Splat", "Each ray spread over its nearest map cells, as in the paper")],
        default='BEAM')
    beam_refinement: IntProperty(
        name="Beam Refinement",
        description="Times a beam is split where neighbouring rays part ways, as at a gem's facet edges",
        default=1, min=0, max=5)
    max_depth: IntProperty(
        name="Max Bounces",
        description="Reflections and refractions followed along each ray",
        default=12, min=1, max=64)
    bands: IntProperty(
        name="Wavelength Bands",
        description="Bands of the spectrum traced where an object disperses light",
        default=6, min=1, max=64, soft_max=16)
    spp: IntProperty(
        name="Samples",
        description="Camera rays per pixel",
        default=4, min=1, soft_max=64)
    edge_samples: IntProperty(
        name="Edge Samples",
        description="Camera rays that replace a pixel's samples where they disagree, as at edges; 0 turns it off",
        default=8, min=0, soft_max=64)
    lamp_samples: IntProperty(
        name="Light Samples",
        description="Shadow rays per camera ray toward each light with a size; more give smoother soft shadows",
        default=8, min=1, soft_max=64)
    world_samples: IntProperty(
        name="World Samples",
        description="Directions per camera ray toward the world, through glass and water too",
        default=8, min=1, soft_max=64)
    ambient: FloatVectorProperty(
        name="Ambient",
        description="Uniform ambient light that every surface reflects in its color",
        subtype='COLOR', size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=1.0)

    use_live: BoolProperty(
        name="Live",
        description="Keep the receivers' caustics up to date as you work, in the viewport and in renders",
        default=False)
    use_bake_on_render: BoolProperty(
        name="Bake While Rendering",
        description="Bake each frame's caustics just before Blender renders it: from the command line, "
                    "and from F12 and Ctrl-F12",
        default=False)

    cycles_samples: IntProperty(
        name="Cycles Samples",
        description="Samples per pixel of the Cycles reference render",
        default=128, min=1, soft_max=4096)
    cycles_time_limit: FloatProperty(
        name="Cycles Time Limit",
        description="Stop the Cycles reference render after this long; 0 for no limit",
        default=0.0, min=0.0, soft_max=600.0, subtype='TIME_ABSOLUTE', unit='TIME_ABSOLUTE')


def register():
    bpy.utils.register_class(CausticSceneSettings)
    bpy.types.Scene.caustic = PointerProperty(type=CausticSceneSettings)


def unregister():
    del bpy.types.Scene.caustic
    bpy.utils.unregister_class(CausticSceneSettings)
