"""CAUSTIC_OT_render: the active camera's view with caustics, into the image
"Caustic Render" (and its passes into "Caustic Render Direct", "... Caustic"
and "... Ambient"), and optionally to a file. In the UI the engine runs on a
worker thread (progress in the status bar and the panel, Esc cancels); in
the background, or when called from a script, it runs synchronously in
execute()."""

import bpy

from ..export import InputError, read_scene, render_settings
from ..jobs import JobRunner, RenderJob, StepError, refusal
from ..writeback.images import show_image
from ..writeback.output import OutputError, frame_paths, save_frame
from ..writeback.results import write_result
from .engine_run import EngineOperator


class CAUSTIC_OT_render(EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.render"
    bl_label = "Render Caustics"
    bl_description = "Render the active camera's view with caustics into the image \"Caustic Render\""
    # An undo step keeps the image through later undos; no REGISTER, whose
    # redo panel would re-run the whole render.
    bl_options = {'UNDO'}

    filepath: bpy.props.StringProperty(
        name="File Path", options={'SKIP_SAVE'},
        description="Also save the render here, in the scene's output file format (// is the .blend's folder, "
                    "# the frame number)")
    # No FILE_PATH subtype: with it, bpy 5.2 crashes when a script passes a "//" path.

    def _runner(self, context) -> JobRunner | None:
        try:
            read = read_scene(context)
            job = RenderJob(read.scene, render_settings(context.scene.caustic))
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return None
        too_large = refusal(job.scene, job.settings)
        if too_large is not None:
            self.report({'ERROR'}, too_large[0].upper() + too_large[1:])
            return None
        self._read = read
        return JobRunner([context.scene.frame_current], lambda frame: job, self._write)

    def _write(self, frame: int, job: RenderJob) -> None:
        context = bpy.context
        image = write_result(context.window_manager.caustic, job)
        self._image = image.name
        show_image(context, image)
        for warning in self._read.warnings + job.result.warnings:
            self.report({'WARNING'}, warning)
        if not self.filepath:
            return
        path = bpy.path.abspath(self.filepath)
        try:
            if "#" in bpy.path.basename(self.filepath):
                path = frame_paths(context.scene, [frame], self.filepath)[frame]
            save_frame(context.scene, context.view_layer.name, image, job.result, path)
        except OutputError as exc:
            raise StepError(f"Rendered into \"{image.name}\" but {exc}") from exc

    def _done(self, context, runner: JobRunner) -> set:
        if runner.cancelled:
            self.report({'WARNING'}, "Caustic render cancelled")
            return {'CANCELLED'}
        if runner.error is not None:
            self.report({'ERROR'}, runner.error)
            return {'CANCELLED'}
        self.report({'INFO'}, f"Caustics rendered in {runner.last.seconds:.1f} s from "
                              f"{context.window_manager.caustic.last_lamp_rays:,} light rays into \"{self._image}\"")
        return {'FINISHED'}
