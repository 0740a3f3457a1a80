"""CAUSTIC_OT_bake and CAUSTIC_OT_unbake: each receiver's illumination map
as a packed float image, shown by its material through one node group (see
writeback.bake_group); unbake takes all of it out again."""

import bpy
import numpy as np

from ..export import InputError, SceneRead, read_scene, render_settings
from ..export.materials import albedo_socket
from ..jobs import RenderJob
from ..writeback.bake_group import baked_nodes, make_group, material_output, unwire, wire
from ..writeback.images import write_image
from ..writeback.results import record_run
from .render import no_render_running

IMAGE_PREFIX = "Caustic Map "
GROUP_PREFIX = "Caustic Bake "


def _bakeable(read: SceneRead, names) -> tuple[dict, list[str]]:
    """{receiver name: material} for the receivers whose material can show a
    bake, and a warning for each one that cannot."""
    plan, warnings, owners = {}, [], {}
    for name in names:
        material = bpy.data.materials.get(read.materials.get(name) or "")
        if name in read.instanced:
            warnings.append(f"'{name}' is an instance; its caustic cannot be baked into a material")
        elif material is None:
            warnings.append(f"'{name}' has no material to show its baked caustic")
        elif material.node_tree is None or material_output(material) is None or not (
                bpy.app.version >= (5, 0, 0) or material.use_nodes):
            warnings.append(f"material '{material.name}' of '{name}' has no node output to add the caustic to")
        elif material.name in owners:
            warnings.append(f"material '{material.name}' is shared by '{owners[material.name]}' and '{name}'; "
                            f"only the caustic on '{owners[material.name]}' is baked")
        else:
            owners[material.name] = name
            plan[name] = material
    return plan, warnings


class CAUSTIC_OT_bake(bpy.types.Operator):
    bl_idname = "caustic.bake"
    bl_label = "Bake Caustics"
    bl_description = ("Trace the lamp rays and store each receiver's caustic in an image its material shows "
                      "(EEVEE and the viewport then display it)")
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return no_render_running(cls)

    def execute(self, context):
        props = context.scene.caustic
        try:
            read = read_scene(context, with_camera=False)
            settings = render_settings(props, spp=1)
            if not read.scene.casters:
                raise InputError("Nothing to bake: no object is transparent or a reflector")
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        job = RenderJob(read.scene, settings)
        job.run()
        if job.error is not None:
            self.report({'ERROR'}, job.error)
            return {'CANCELLED'}
        maps = job.result.maps
        plan, warnings = _bakeable(read, maps)
        for warning in read.warnings + job.result.warnings + warnings:
            self.report({'WARNING'}, warning)
        if not plan:
            self.report({'ERROR'}, "No receiver's material can take a baked caustic")
            return {'CANCELLED'}
        for name, material in plan.items():
            unwire(material)
            imap = maps[name]
            rgba = np.ones(imap.shape + (4,), dtype=np.float32)
            rgba[..., :3] = imap.irradiance()
            # Map row 0 is the chart's lowest y, the image's bottom row.
            image = write_image(IMAGE_PREFIX + name, rgba[::-1])
            source = bpy.data.objects[read.sources[name]].data
            uv_layer = source.uv_layers.active.name if source.uv_layers.active is not None else ""
            receiver = next(o.material for o in read.scene.objects if o.name == name)
            share = receiver.specular.diffuse_share if receiver.specular is not None else None
            wire(material, make_group(GROUP_PREFIX + name, image, imap, receiver.albedo, uv_layer, share),
                 albedo_socket(material))
        record_run(props, job)
        self.report({'INFO'}, f"Baked caustics onto {', '.join(plan)} in {job.seconds:.1f} s")
        return {'FINISHED'}


class CAUSTIC_OT_unbake(bpy.types.Operator):
    bl_idname = "caustic.unbake"
    bl_label = "Remove Baked Caustics"
    bl_description = "Take every baked caustic out of the materials, with its node groups and images"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return any(baked_nodes(material) for material in bpy.data.materials)

    def execute(self, context):
        removed = sum(unwire(material) for material in bpy.data.materials)
        self.report({'INFO'}, f"Removed {removed} baked caustic{'s' if removed != 1 else ''}")
        return {'FINISHED'}
