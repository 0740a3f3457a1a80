"""What the operators that run the engine share: one run at a time, and
the run itself through jobs.JobRunner. From a script or in the background
execute() does it all before it returns; from a button, invoke() runs it on
a timer, with the progress bar and the status text, and Esc stops it."""

from pathlib import Path

import bpy

from ..jobs import JobRunner, kernels

COMPILING = "compiling the engine's kernels, once (about half a minute)"


def kernel_folder() -> str | None:
    """Blender's user folder for the extension's compiled kernels, or None
    where the add-on runs from a source tree and not as an extension."""
    try:
        return bpy.utils.extension_path_user(__package__.rpartition(".")[0], path="kernels", create=True)
    except ValueError:
        return None


def shipped_kernels() -> Path:
    """The folder of the compiled kernels the extension's zip carries
    (absent in a source tree, and in zips of other platforms than the
    packaging machine's)."""
    return Path(__file__).resolve().parents[1] / "kernels"


def no_render_running(operator) -> bool:
    """Poll for the operators that run the engine: one run at a time."""
    if EngineOperator.running:
        operator.poll_message_set("A caustic render is running: wait for it, or press Esc to cancel it")
        return False
    return True


class EngineOperator:
    """Mixin for a bpy.types.Operator. The operator gives `_runner(context)`
    (a JobRunner, or None after reporting why not) and `_done(context,
    runner)` (reports; returns the operator's result); `_status(runner)`
    may word the status bar."""

    running = False

    @classmethod
    def poll(cls, context):
        return no_render_running(cls)

    def _status(self, runner: JobRunner) -> str:
        if kernels.compiling():
            return f"Caustics: {COMPILING} (Esc to cancel)"
        return f"Caustics: {runner.stage}, {runner.fraction:.0%} (Esc to cancel)"

    def _say_if_compiling(self) -> None:
        if kernels.compiling():
            self.report({'INFO'}, f"Caustics: {COMPILING}; the run goes on when they are ready")

    def execute(self, context):
        runner = self._runner(context)
        if runner is None:
            return {'CANCELLED'}
        self._say_if_compiling()
        runner.run()
        return self._end(context, runner)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        runner = self._runner(context)
        if runner is None:
            return {'CANCELLED'}
        self._run, self._progress_before = runner, context.window_manager.caustic.progress
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        EngineOperator.running = True
        self._say_if_compiling()
        runner.tick()
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        if event.type == 'ESC' and event.value == 'PRESS':
            self._run.stop()
            return {'RUNNING_MODAL'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        try:
            ticking = self._run.tick()
        except Exception:
            # a bug in a step: free the UI for the next run before Blender reports it
            self._stop(context)
            raise
        if ticking:
            context.window_manager.progress_update(self._run.fraction)
            context.window_manager.caustic.progress = self._run.fraction
            context.workspace.status_text_set(self._status(self._run))
            for area in context.screen.areas:
                if area.type == 'VIEW_3D':
                    area.tag_redraw()
            return {'RUNNING_MODAL'}
        self._stop(context)
        if not self._run.done:
            context.window_manager.caustic.progress = self._progress_before
        return self._end(context, self._run)

    def cancel(self, context):
        """Blender aborts the operator (a file is loaded, the window closes): stop the worker first."""
        self._run.abort()
        self._stop(context)

    def _stop(self, context) -> None:
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        EngineOperator.running = False

    def _end(self, context, runner: JobRunner) -> set:
        if runner.done and runner.error is None and not runner.cancelled:
            context.window_manager.caustic.progress = 1.0
        return self._done(context, runner)
