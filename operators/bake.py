"""CAUSTIC_OT_bake and CAUSTIC_OT_unbake: each receiver's illumination map
as a packed float image, shown by its material through one node group (see
writeback.bake_group); unbake takes all of it out again. In the UI the bake
runs like Render, with progress and Esc."""

import os

import bpy
import numpy as np

from ..export import InputError, SceneRead, read_scene, render_settings
from ..export.materials import albedo_socket
from ..jobs import JobRunner, RenderJob, StepError
from ..writeback.bake_group import baked_nodes, files_on_disk, make_group, material_output, unwire, wire
from ..writeback.images import write_image
from ..writeback.results import record_run
from .engine_run import EngineOperator

IMAGE_PREFIX = "Caustic Map "
GROUP_PREFIX = "Caustic Bake "


def bakeable(read: SceneRead, names) -> tuple[dict, list[str]]:
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


def read_for_bake(context, depsgraph=None) -> SceneRead:
    """The scene to bake (as `depsgraph` evaluates it, if given); InputError if nothing in it casts caustics."""
    read = read_scene(context, with_camera=False, depsgraph=depsgraph)
    if not read.scene.casters:
        raise InputError("Nothing to bake: no object is transparent or a reflector")
    return read


def map_rgba(imap) -> np.ndarray:
    """(h,w,4) float32 of a map's irradiance, top row first (map row 0 is the chart's lowest y)."""
    rgba = np.ones(imap.shape + (4,), dtype=np.float32)
    rgba[..., :3] = imap.irradiance()
    return rgba[::-1]


def bake_maps(read: SceneRead, maps) -> tuple[list[str], list[str]]:
    """Each bakeable receiver's map of `maps` into a packed image its
    material shows, replacing an earlier bake: (receivers baked, warnings)."""
    plan, warnings = bakeable(read, maps)
    for name, material in plan.items():
        unwire(material)
        wire_bake(read, name, material, write_image(IMAGE_PREFIX + name, map_rgba(maps[name])), maps[name])
    return list(plan), warnings


def wire_bake(read: SceneRead, name: str, material, image, imap):
    """`image` of receiver `name`'s map `imap` shown by its `material` through a new node group; returns the group."""
    source = bpy.data.objects[read.sources[name]].data
    uv_layer = source.uv_layers.active.name if source.uv_layers.active is not None else ""
    receiver = next(o.material for o in read.scene.objects if o.name == name)
    share = receiver.specular.diffuse_share if receiver.specular is not None else None
    group = make_group(GROUP_PREFIX + name, image, imap, receiver.albedo, uv_layer, share)
    wire(material, group, albedo_socket(material))
    return group


class CAUSTIC_OT_bake(EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.bake"
    bl_label = "Bake Caustics"
    bl_description = ("Trace the lamp rays and store each receiver's caustic in an image its material shows "
                      "(EEVEE and the viewport then display it)")
    bl_options = {'REGISTER', 'UNDO'}

    def _runner(self, context) -> JobRunner | None:
        try:
            read = read_for_bake(context)
            job = RenderJob(read.scene, render_settings(context.scene.caustic, spp=1))
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return None
        self._read = read
        return JobRunner([context.scene.frame_current], lambda frame: job, self._write)

    def _write(self, frame: int, job: RenderJob) -> None:
        self._baked, warnings = bake_maps(self._read, job.result.maps)
        for warning in self._read.warnings + job.result.warnings + warnings:
            self.report({'WARNING'}, warning)
        if not self._baked:
            raise StepError("No receiver's material can take a baked caustic")
        record_run(bpy.context.scene.caustic, job)

    def _done(self, context, runner: JobRunner) -> set:
        if runner.cancelled:
            self.report({'WARNING'}, "Caustic bake cancelled")
            return {'CANCELLED'}
        if runner.error is not None:
            self.report({'ERROR'}, runner.error)
            return {'CANCELLED'}
        self.report({'INFO'}, f"Baked caustics onto {', '.join(self._baked)} in {runner.last.seconds:.1f} s")
        return {'FINISHED'}


class CAUSTIC_OT_unbake(bpy.types.Operator):
    bl_idname = "caustic.unbake"
    bl_label = "Remove Baked Caustics"
    bl_description = ("Take every baked caustic out of the materials, with its node groups and images; the files "
                      "of an animated bake stay on disk")
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return any(baked_nodes(material) for material in bpy.data.materials)

    def execute(self, context):
        files = sorted({path for material in bpy.data.materials for path in files_on_disk(material)})
        removed = sum(unwire(material) for material in bpy.data.materials)
        self.report({'INFO'}, f"Removed {removed} baked caustic{'s' if removed != 1 else ''}")
        for folder in sorted({os.path.dirname(path) for path in files}):
            names = [os.path.basename(path) for path in files if os.path.dirname(path) == folder]
            self.report({'INFO'}, f"The baked frames stay on disk: {len(names)} file{'s' if len(names) != 1 else ''} "
                                  f"in '{folder}' ({names[0]}{f' to {names[-1]}' if len(names) > 1 else ''}); "
                                  "delete them by hand if they are no longer needed")
        return {'FINISHED'}
