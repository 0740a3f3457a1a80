"""CAUSTIC_OT_apply_preset: the paper's settings in one click."""

import bpy

# The paper traced 40,000 lamp rays over the whole sphere (its equation (1))
# into bilinear illumination maps, at lamp energy 10 or 20 and map scale 5 or 40 mm.
PRESETS = {
    'DEFAULT': ("Default", "1,000,000 targeted lamp rays, adaptive density, automatic map scale, Cycles brightness",
                dict(photons=1_000_000, emission='TARGETED', energy=1.0, use_auto_map_scale=True,
                     density='ADAPTIVE')),
    'PAPER_10_5': ("Paper: energy 10, map 5 mm", "40,000 lamp rays over the sphere, lamp energy 10, map scale 5 mm",
                   dict(photons=40_000, emission='SPHERE', energy=10.0, use_auto_map_scale=False, map_scale=5.0,
                        density='SPLAT')),
    'PAPER_10_40': ("Paper: energy 10, map 40 mm",
                    "40,000 lamp rays over the sphere, lamp energy 10, map scale 40 mm",
                    dict(photons=40_000, emission='SPHERE', energy=10.0, use_auto_map_scale=False, map_scale=40.0,
                         density='SPLAT')),
    'PAPER_20_5': ("Paper: energy 20, map 5 mm", "40,000 lamp rays over the sphere, lamp energy 20, map scale 5 mm",
                   dict(photons=40_000, emission='SPHERE', energy=20.0, use_auto_map_scale=False, map_scale=5.0,
                        density='SPLAT')),
    'PAPER_20_40': ("Paper: energy 20, map 40 mm",
                    "40,000 lamp rays over the sphere, lamp energy 20, map scale 40 mm",
                    dict(photons=40_000, emission='SPHERE', energy=20.0, use_auto_map_scale=False, map_scale=40.0,
                         density='SPLAT')),
}


class CAUSTIC_OT_apply_preset(bpy.types.Operator):
    bl_idname = "caustic.apply_preset"
    bl_label = "Apply Caustics Preset"
    bl_description = "Set the photon pass to a preset, such as the paper's settings"
    bl_options = {'REGISTER', 'UNDO'}

    preset: bpy.props.EnumProperty(
        name="Preset", items=[(key, label, description) for key, (label, description, _) in PRESETS.items()])

    def execute(self, context):
        props = context.scene.caustic
        for name, value in PRESETS[self.preset][2].items():
            setattr(props, name, value)
        return {'FINISHED'}
