"""Object.caustic: how one object takes part in the caustic render."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, PointerProperty


class CausticObjectSettings(bpy.types.PropertyGroup):
    role: EnumProperty(
        name="Role",
        description="What the object does in the caustic render",
        items=[('AUTO', "Auto", "From the material: Glass BSDF, or Principled BSDF with Transmission Weight "
                                "above 0.5, is transparent; Glossy BSDF, or Principled BSDF with Metallic above "
                                "0.5 and Roughness up to 0.2, is a reflector; anything else receives caustics"),
               ('TRANSPARENT', "Transparent", "Refracts and reflects light: glass, water, gems"),
               ('REFLECTOR', "Reflector", "A perfect mirror or polished metal: reflects light in its "
                                          "material's colour (white if the material has none)"),
               ('RECEIVER', "Receiver", "An opaque diffuse surface that collects caustics"),
               ('IGNORE', "Ignore", "Left out of the caustic render")],
        default='AUTO')
    use_ior: BoolProperty(
        name="Override IOR", description="Use the IOR below instead of the material's", default=False)
    ior: FloatProperty(
        name="IOR",
        description="Index of refraction: 1.33 water, 1.5 glass, 2.42 diamond",
        default=1.5, min=0.0, soft_min=1.0, soft_max=3.0)
    absorption: FloatVectorProperty(
        name="Absorption",
        description="Beer-Lambert absorption coefficient inside a transparent object, per metre, "
                    "for red, green and blue (0: clear)",
        size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=10.0)


def register():
    bpy.utils.register_class(CausticObjectSettings)
    bpy.types.Object.caustic = PointerProperty(type=CausticObjectSettings)


def unregister():
    del bpy.types.Object.caustic
    bpy.utils.unregister_class(CausticObjectSettings)
