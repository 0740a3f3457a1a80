"""CAUSTIC_OT_apply_preset: the paper's settings in one click."""

import bpy

# The paper traced 40,000 lamp rays into bilinear illumination maps, at lamp
# energy 10 or 20 and map scale 5 or 40 mm. The rays go toward the glass:
# over the whole sphere, as its equation (1), few of 40,000 would reach a
# small object.


def _paper(energy: int, map_scale: int) -> tuple[str, str, dict]:
    return (f"Paper: energy {energy}, map {map_scale} mm",
            f"40,000 light rays, light energy {energy}, map scale {map_scale} mm, bilinear map",
            dict(lamp_rays=40_000, emission='TARGETED', energy=float(energy), use_auto_map_scale=False,
                 map_scale=map_scale / 1000.0, density='SPLAT'))


# key -> (label, description, Scene.caustic values)
PRESETS = {
    'DEFAULT': ("Default", "40,000 light rays as beams, automatic map scale, Cycles brightness",
                dict(lamp_rays=40_000, emission='TARGETED', energy=1.0, use_auto_map_scale=True,
                     density='BEAM', beam_refinement=1)),
    **{f'PAPER_{energy}_{scale}': _paper(energy, scale) for energy in (10, 20) for scale in (5, 40)},
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
