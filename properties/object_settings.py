"""Object.caustic: how one object takes part in the caustic render.

The group holds properties only: Blender 4.2's bpy module crashes at exit
once a group it had registered carried Python callbacks (get, set, update)
or attributes. So dispersion is on where `abbe` is above 0, and the
sidebar's Dispersion toggle is an operator (caustic.toggle_dispersion)."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, PointerProperty


class CausticObjectSettings(bpy.types.PropertyGroup):
    role: EnumProperty(
        name="Role",
        description="What the object does in the caustic render",
        items=[('AUTO', "Auto", "From the material: glass is transparent, metal and glossy reflect, the rest "
                                "receives caustics"),
               ('TRANSPARENT', "Transparent", "Refracts and reflects light: glass, water, gems"),
               ('REFLECTOR', "Reflector", "A mirror or a metal: reflects light in its material's color"),
               ('RECEIVER', "Receiver", "An opaque diffuse surface that collects caustics"),
               ('IGNORE', "Ignore", "Left out of the caustic render")],
        default='AUTO')
    use_ior: BoolProperty(
        name="Override IOR", description="Use the IOR below instead of the material's", default=False)
    ior: FloatProperty(
        name="IOR",
        description="Index of refraction: 1.33 for water, 1.5 for glass, 2.42 for diamond",
        default=1.5, min=0.01, soft_min=1.0, soft_max=3.0)
    abbe: FloatProperty(
        name="Abbe Number",
        description="How little the glass disperses: 58 for crown glass, 55 for diamond; lower disperses, 0 is off",
        default=0.0, min=0.0, soft_min=10.0, soft_max=100.0)
    abbe_off: FloatProperty(
        name="Abbe Number while Off", description="The Abbe number that Dispersion turns back on",
        default=0.0, min=0.0, options={'HIDDEN'})
    absorption_from: EnumProperty(
        name="Absorption",
        description="Where the absorption inside a transparent object comes from",
        items=[('MATERIAL', "Material", "The Volume Absorption node on the material's Volume output, as Cycles "
                                        "reads it"),
               ('COLOR', "Color at Distance", "White light takes this color after this distance inside"),
               ('COEFFICIENT', "Coefficient", "Beer-Lambert absorption coefficient per metre")],
        default='MATERIAL')
    absorption: FloatVectorProperty(
        name="Coefficient",
        description="Absorption inside the object per metre, for red, green and blue; 0 is clear",
        size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=10.0)
    absorption_color: FloatVectorProperty(
        name="Color",
        description="The color white light takes after Distance inside the object",
        subtype='COLOR', size=3, default=(1.0, 1.0, 1.0), min=1e-6, max=1.0)
    absorption_distance: FloatProperty(
        name="Distance",
        description="How far inside the object light goes to take the Color",
        subtype='DISTANCE', default=0.1, min=1e-6, soft_max=10.0)

def register():
    bpy.utils.register_class(CausticObjectSettings)
    bpy.types.Object.caustic = PointerProperty(type=CausticObjectSettings)


def unregister():
    del bpy.types.Object.caustic
    bpy.utils.unregister_class(CausticObjectSettings)
