"""Scene.caustic: the render settings (named as in the paper where it has a
name) and the last runs' results, which the operators write and the panels
only show."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty, PointerProperty


class CausticSceneSettings(bpy.types.PropertyGroup):
    lamp_rays: IntProperty(
        name="Lamp Rays",
        description="Rays traced from the lamps, in all, the paper's \"number of lamp rays\" (it used "
                    "40,000); the lamps share them by the light each sends toward the glass and mirrors. "
                    "As beams, the default already gives a smooth caustic, within 1% of exact for a glass "
                    "ball: more sharpen its finest folds and cusps (rippled water wants about 300,000), at "
                    "a time that grows in proportion (about 10 s per million on two cores) and no more "
                    "memory. Photons need millions for the same smoothness",
        default=40_000, min=0, soft_max=10_000_000)
    emission: EnumProperty(
        name="Emission",
        description="Where the lamps send their rays",
        items=[('TARGETED', "Targeted", "Only toward transparent and reflecting objects, so every lamp ray "
                                        "can make a caustic"),
               ('SPHERE', "Sphere", "Over the whole sphere of directions, as the paper's equation (1)")],
        default='TARGETED')
    energy: FloatProperty(
        name="Lamp Energy",
        description="Multiplier on every lamp's power, the paper's \"lamp energy\" (it used 10 and 20). "
                    "At 1 the lamps are as bright as in Cycles",
        default=1.0, min=0.0, soft_max=100.0)
    use_auto_map_scale: BoolProperty(
        name="Auto Map Scale",
        description="Size the illumination maps' cells from each receiver, with no tuning",
        default=True)
    map_scale: FloatProperty(
        name="Map Scale",
        description="Edge of one illumination-map cell, the paper's \"map scale\" (it compared 5 and 40 mm). "
                    "Larger cells give smoother, blurrier caustics",
        subtype='DISTANCE', unit='LENGTH', default=0.005, min=1e-6, soft_min=1e-4, soft_max=0.1,
        step=0.1, precision=4)
    density: EnumProperty(
        name="Density",
        description="How stored lamp rays become irradiance on a receiver",
        items=[('BEAM', "Beam", "Lamp rays on a grid: each triangle of neighbours that takes the same path "
                                "carries its light onto the triangle it lands on. No noise, sharp caustics"),
               ('ADAPTIVE', "Adaptive", "Average over the nearest 64 lamp rays: sharp where they are dense, "
                                        "smooth where they are sparse"),
               ('SPLAT', "Splat", "Each ray spread over the 4 nearest map cells, as in the paper")],
        default='BEAM')
    beam_refinement: IntProperty(
        name="Beam Refinement",
        description="Times a beam's grid cell is split in four where neighbouring lamp rays part ways (a "
                    "silhouette, a facet edge, a fold of the caustic). Facetted gems gain most",
        default=1, min=0, max=5)
    max_depth: IntProperty(
        name="Max Bounces",
        description="Reflections and refractions followed per lamp ray and per eye ray",
        default=12, min=1, max=64)
    bands: IntProperty(
        name="Wavelength Bands",
        description="Wavelength bands traced when an object disperses (its Abbe number is set); "
                    "each lamp ray carries one, so more bands cost no more rays",
        default=6, min=1, max=64, soft_max=16)
    spp: IntProperty(
        name="Samples",
        description="Eye rays per pixel (anti-aliasing)",
        default=4, min=1, soft_max=64)
    edge_samples: IntProperty(
        name="Edge Samples",
        description="Eye rays that replace a pixel's samples where they disagree (a silhouette, a shadow's "
                    "edge, an edge seen through glass), when more than Samples: clean edges at 1 sample per "
                    "pixel, without more samples everywhere. 0 turns it off",
        default=8, min=0, soft_max=64)
    lamp_samples: IntProperty(
        name="Lamp Samples",
        description="Shadow rays per eye sample toward each lamp with a size (a radius, an area or a sun's "
                    "angle), spread evenly over the pixel: more give smoother soft shadows. A lamp that looks smaller "
                    "than a degree (a sun) casts two first, the rest only where a pixel's disagree",
        default=8, min=1, soft_max=64)
    world_samples: IntProperty(
        name="World Samples",
        description="Directions per eye sample toward the world, spread evenly over the pixel and followed on "
                    "through glass and water: more give smoother light from the sky, in the open and through them",
        default=8, min=1, soft_max=64)
    ambient: FloatVectorProperty(
        name="Ambient",
        description="Uniform ambient radiance (W/m^2/sr) a surface reflects times its colour",
        subtype='COLOR', size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=1.0)

    use_bake_on_render: BoolProperty(
        name="Bake While Rendering",
        description="Bake each frame's caustics into the receivers' materials just before Blender renders it, "
                    "so EEVEE and Cycles renders (F12, animations) show the current frame's caustic. Works in "
                    "command-line renders (blender -b); a render started from the interface uses the last bake",
        default=False)

    cycles_samples: IntProperty(
        name="Cycles Samples",
        description="Samples per pixel of the Cycles reference render",
        default=128, min=1, soft_max=4096)
    cycles_time_limit: FloatProperty(
        name="Cycles Time Limit",
        description="Stop the Cycles reference render after this many seconds (0: no limit)",
        default=0.0, min=0.0, soft_max=600.0, subtype='TIME_ABSOLUTE', unit='TIME_ABSOLUTE')

    progress: FloatProperty(
        name="Progress", description="Share of the running caustic render done",
        default=0.0, min=0.0, max=1.0, subtype='FACTOR')
    last_seconds: FloatProperty(
        name="Render Time", description="Seconds the last caustic render took", default=0.0, min=0.0)
    last_lamp_rays: IntProperty(
        name="Lamp Rays Traced", description="Lamp rays the last caustic render traced, all lamps, with those "
                                             "beam refinement added", default=0, min=0)
    last_refined: IntProperty(
        name="Added by Refinement", description="Lamp rays beam refinement added in the last caustic render, "
                                                "where neighbouring rays part ways", default=0, min=0)
    cycles_seconds: FloatProperty(
        name="Cycles Time", description="Seconds the last Cycles reference render took", default=0.0, min=0.0)
    cycles_reference: EnumProperty(
        name="Cycles Reference",
        description="How the last comparison's Cycles reference rendered the caustics",
        items=(('PATH_TRACED', "Path Traced", "Cycles path-traced every caustic: the reference contains them"),
               ('MNEE', "MNEE", "A lamp without a size lights a smooth caster: Cycles renders its caustic only "
                                "by MNEE (refraction, inside the shadow), so the reference lacks part of it"),
               ('NONE', "No Caustics", "The scene has no glass or mirror: the error is over the whole image")),
        default='PATH_TRACED')
    cycles_relative_l2: FloatProperty(
        name="Relative L2",
        description="|caustic render - Cycles| over the pixels the caustics light, over the Cycles reference's "
                    "caustic light there (over the whole image, over |Cycles|, without caustics), last comparison; "
                    "not a number where the reference lacks part of the caustic",
        default=0.0, min=0.0)
    cycles_noise: FloatProperty(
        name="Cycles Noise",
        description="The Cycles reference's own noise over the caustics, relative as the relative L2 is, from "
                    "its two renders of half the samples with different seeds, last comparison; the relative L2 "
                    "squared is, on average, the caustic render's own error squared plus this one's",
        default=0.0, min=0.0)
    cycles_caustic_ratio: FloatProperty(
        name="Caustic Light",
        description="The caustic render's caustic light over the caustics divided by the Cycles reference's "
                    "(its render less one without caustics), last comparison",
        default=0.0, min=0.0)
    cycles_caustic_noise: FloatProperty(
        name="Caustic Light Noise",
        description="The standard deviation of the caustic light's ratio from the Cycles reference's noise, "
                    "last comparison (not a number where the reference lacks part of the caustic)",
        default=0.0, min=0.0)
    cycles_psnr: FloatProperty(
        name="PSNR (dB)", description="Peak signal-to-noise ratio of the caustic render against Cycles, "
                                      "peak = brightest Cycles pixel, last comparison",
        default=0.0)
    cycles_psnr_outside: BoolProperty(
        name="PSNR outside the Caustics",
        description="The last comparison's PSNR leaves the caustics out: its reference lacks part of them, or "
                    "its noise there is most of the error",
        default=False)


def register():
    bpy.utils.register_class(CausticSceneSettings)
    bpy.types.Scene.caustic = PointerProperty(type=CausticSceneSettings)


def unregister():
    del bpy.types.Scene.caustic
    bpy.utils.unregister_class(CausticSceneSettings)
