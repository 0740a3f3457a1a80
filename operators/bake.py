"""CAUSTIC_OT_bake and CAUSTIC_OT_unbake: each receiver's illumination map
as a packed float image, shown by its material through one node group (see
writeback.bake_group); unbake takes all of it out again, and turns Live
off. In the UI the bake runs like Render, with progress and Esc."""

import os

import bpy

from ..export import InputError, bake_settings, read_for_bake
from ..jobs import JobRunner, RenderJob, StepError
from ..live import session as live
from ..writeback.bake import bake_maps, forget_selectors
from ..writeback.bake_group import baked_nodes, files_on_disk, unwire
from ..writeback.results import record_run
from .engine_run import EngineOperator


class BakeFrame(EngineOperator):
    """What Bake Caustics does, for the operators that bake the current frame."""

    def _runner(self, context) -> JobRunner | None:
        try:
            read = read_for_bake(context)
            job = RenderJob(read.scene, bake_settings(context.scene.caustic))
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
        record_run(bpy.context.window_manager.caustic, job)

    def _done(self, context, runner: JobRunner) -> set:
        if runner.cancelled:
            self.report({'WARNING'}, "Caustic bake cancelled")
            return {'CANCELLED'}
        if runner.error is not None:
            self.report({'ERROR'}, runner.error)
            return {'CANCELLED'}
        self.report({'INFO'}, f"Baked caustics onto {', '.join(self._baked)} in {runner.last.seconds:.1f} s")
        return {'FINISHED'}


class CAUSTIC_OT_bake(BakeFrame, bpy.types.Operator):
    bl_idname = "caustic.bake"
    bl_label = "Bake Caustics"
    bl_description = "Store each receiver's caustic in an image its material shows, in EEVEE, Cycles and the viewport"
    bl_options = {'REGISTER', 'UNDO'}


class CAUSTIC_OT_unbake(bpy.types.Operator):
    bl_idname = "caustic.unbake"
    bl_label = "Remove Baked Caustics"
    bl_description = "Take every baked caustic out of the materials, with its node groups and images"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return any(baked_nodes(material) for material in bpy.data.materials)

    def execute(self, context):
        if context.scene.caustic.use_live:
            context.scene.caustic.use_live = False
            live.stop()
            self.report({'INFO'}, "Live is off: it would bake the caustics again at the next change")
        files = sorted({path for material in bpy.data.materials for path in files_on_disk(material)})
        removed = sum(unwire(material) for material in bpy.data.materials)
        forget_selectors()
        self.report({'INFO'}, f"Removed {removed} baked caustic{'s' if removed != 1 else ''}")
        for folder in sorted({os.path.dirname(path) for path in files}):
            names = [os.path.basename(path) for path in files if os.path.dirname(path) == folder]
            self.report({'INFO'}, f"The baked frames stay on disk: {len(names)} file{'s' if len(names) != 1 else ''} "
                                  f"in '{folder}' ({names[0]}{f' to {names[-1]}' if len(names) > 1 else ''}); "
                                  "delete them by hand if they are no longer needed")
        return {'FINISHED'}
