"""CAUSTIC_OT_render: the active camera's view with caustics, into the image
"Caustic Render", and optionally to a file. In the UI the engine runs on a
worker thread (progress in the status bar and the panel, Esc cancels); in the
background, or when called from a script, it runs synchronously in
execute()."""

import bpy

from ..export import InputError, SceneRead, read_scene, render_settings
from ..jobs import RenderJob
from ..writeback.images import show_image, write_image
from ..writeback.results import record_run

RESULT_IMAGE = "Caustic Render"


def no_render_running(operator) -> bool:
    """Poll for the operators that run the engine: one render at a time."""
    if CAUSTIC_OT_render.running:
        operator.poll_message_set("A caustic render is running: wait for it, or press Esc to cancel it")
        return False
    return True


class CAUSTIC_OT_render(bpy.types.Operator):
    bl_idname = "caustic.render"
    bl_label = "Render Caustics"
    bl_description = "Render the active camera's view with caustics into the image \"Caustic Render\""
    # An undo step keeps the image through later undos; no REGISTER, whose
    # redo panel would re-run the whole render.
    bl_options = {'UNDO'}

    filepath: bpy.props.StringProperty(
        name="File Path", options={'SKIP_SAVE'},
        description="Also save the render here, in the scene's output file format (// is the .blend's folder)")
    # No FILE_PATH subtype: with it, bpy 5.2 crashes when a script passes a "//" path.

    running = False

    @classmethod
    def poll(cls, context):
        return no_render_running(cls)

    def _prepare(self, context) -> tuple[SceneRead, RenderJob] | None:
        try:
            read = read_scene(context)
            return read, RenderJob(read.scene, render_settings(context.scene.caustic))
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return None

    def execute(self, context):
        prepared = self._prepare(context)
        if prepared is None:
            return {'CANCELLED'}
        read, job = prepared
        job.run()
        return self._finish(context, read, job)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        prepared = self._prepare(context)
        if prepared is None:
            return {'CANCELLED'}
        self._read, self._job = prepared
        self._progress_before = context.scene.caustic.progress
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        CAUSTIC_OT_render.running = True
        self._job.start()
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        if event.type == 'ESC' and event.value == 'PRESS':
            self._job.cancel()
            return {'RUNNING_MODAL'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        if self._job.running:
            context.window_manager.progress_update(self._job.fraction)
            context.scene.caustic.progress = self._job.fraction
            context.workspace.status_text_set(f"Caustics: {self._job.stage}, {self._job.fraction:.0%} (Esc to cancel)")
            for area in context.screen.areas:
                if area.type == 'VIEW_3D':
                    area.tag_redraw()
            return {'RUNNING_MODAL'}
        self._stop(context)
        if self._job.result is None:
            context.scene.caustic.progress = self._progress_before
        return self._finish(context, self._read, self._job)

    def cancel(self, context):
        """Blender aborts the operator (a file is loaded, the window closes): stop the worker first."""
        self._job.cancel()
        self._job.wait()
        self._stop(context)

    def _stop(self, context) -> None:
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        CAUSTIC_OT_render.running = False

    def _finish(self, context, read: SceneRead, job: RenderJob):
        if job.cancelled:
            self.report({'WARNING'}, "Caustic render cancelled")
            return {'CANCELLED'}
        if job.error is not None:
            self.report({'ERROR'}, job.error)
            return {'CANCELLED'}
        props = context.scene.caustic
        image = write_image(RESULT_IMAGE, job.result.image)
        record_run(props, job)
        props.progress = 1.0
        show_image(context, image)
        for warning in read.warnings + job.result.warnings:
            self.report({'WARNING'}, warning)
        if self.filepath:
            try:
                image.save_render(bpy.path.abspath(self.filepath), scene=context.scene)
            except RuntimeError as exc:
                self.report({'ERROR'}, f"Rendered into \"{RESULT_IMAGE}\" but could not save it: {exc}")
                return {'CANCELLED'}
        self.report({'INFO'}, f"Caustics rendered in {job.seconds:.1f} s from "
                              f"{props.last_lamp_rays:,} lamp rays into \"{RESULT_IMAGE}\"")
        return {'FINISHED'}
