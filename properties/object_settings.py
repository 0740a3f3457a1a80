"""Object.caustic: how one object takes part in the caustic render."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, PointerProperty


class CausticObjectSettings(bpy.types.PropertyGroup):
    role: EnumProperty(
        name="Role",
        description="What the object does in the caustic render",
        items=[('AUTO', "Auto", "From the material: Glass or Refraction BSDF, or Principled BSDF with "
                                "Transmission Weight above 0.5, is transparent; Glossy BSDF, or Principled BSDF "
                                "with Metallic above 0.5, is a reflector, each with its Roughness; anything else "
                                "receives caustics"),
               ('TRANSPARENT', "Transparent", "Refracts and reflects light: glass, water, gems"),
               ('REFLECTOR', "Reflector", "A mirror or a metal: reflects light in its material's colour (white "
                                          "if the material has none), smooth or as rough as its Roughness"),
               ('RECEIVER', "Receiver", "An opaque diffuse surface that collects caustics"),
               ('IGNORE', "Ignore", "Left out of the caustic render")],
        default='AUTO')
    use_ior: BoolProperty(
        name="Override IOR", description="Use the IOR below instead of the material's", default=False)
    ior: FloatProperty(
        name="IOR",
        description="Index of refraction: 1.33 water, 1.5 glass, 2.42 diamond",
        default=1.5, min=0.0, soft_min=1.0, soft_max=3.0)
    abbe: FloatProperty(
        name="Abbe Number",
        description="Dispersion: the Abbe number V_d of the glass, whose IOR is the one at 587.6 nm "
                    "(55 diamond, 58 crown glass, 33 cubic zirconia, 56 water; lower disperses more). "
                    "0: no dispersion. A Principled BSDF's own Transmission Dispersion, where its scale is set, "
                    "is used instead",
        default=0.0, min=0.0, soft_min=10.0, soft_max=100.0)
    absorption_from: EnumProperty(
        name="Absorption",
        description="Where the absorption inside a transparent object comes from",
        items=[('MATERIAL', "Material", "A Volume Absorption node on the material's Volume output "
                                        "(density x (1 - colour) per metre, as Cycles); clear without one"),
               ('COLOR', "Colour at Distance", "White light takes this colour after this distance inside"),
               ('COEFFICIENT', "Coefficient", "Beer-Lambert absorption coefficient per metre")],
        default='MATERIAL')
    absorption: FloatVectorProperty(
        name="Coefficient",
        description="Beer-Lambert absorption coefficient inside a transparent object, per metre, "
                    "for red, green and blue (0: clear)",
        size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=10.0)
    absorption_color: FloatVectorProperty(
        name="Colour",
        description="The colour white light takes after Distance inside the object",
        subtype='COLOR', size=3, default=(1.0, 1.0, 1.0), min=1e-6, max=1.0)
    absorption_distance: FloatProperty(
        name="Distance",
        description="How far inside the object light goes to take the Colour",
        subtype='DISTANCE', default=0.1, min=1e-6, soft_max=10.0)


def register():
    bpy.utils.register_class(CausticObjectSettings)
    bpy.types.Object.caustic = PointerProperty(type=CausticObjectSettings)


def unregister():
    del bpy.types.Object.caustic
    bpy.utils.unregister_class(CausticObjectSettings)
