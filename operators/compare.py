"""CAUSTIC_OT_compare_cycles: the caustic render next to a Cycles render of
the same camera (CPU; the light the caustic render computes, its caustics
path-traced, or by MNEE for lamps without a size), with the error between
them (comparison.run). Writes "Caustic Render" (with its passes), "Cycles
Reference" and "Difference"; leaves every render setting as it was. Where
the reference lacks part of the caustic, or is too noisy to judge it, the
report says so and measures no error there. In the UI both halves run like
Render: the caustics on a worker thread, then Cycles as Blender's own
render job (its progress bar and render view, as F12); Esc stops either,
and a stopped comparison writes nothing."""

import bpy

from ..comparison.run import Comparison
from ..export import InputError
from ..export.cycles_still import cycles_enabled
from ..jobs import JobRunner
from .engine_run import EngineOperator


class CAUSTIC_OT_compare_cycles(EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_description = "Render the camera with caustics and with Cycles, and measure the difference"
    # As caustic.render: an undo step keeps the images, and no redo panel re-runs both renders.
    bl_options = {'UNDO'}

    @classmethod
    def poll(cls, context):
        if not cycles_enabled():
            cls.poll_message_set("Compare with Cycles needs the Cycles add-on: turn it on in Preferences > Add-ons")
            return False
        return super().poll(context)

    def _runner(self, context) -> JobRunner | None:
        try:
            self._comparison = Comparison(context)
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return None
        return self._comparison.runner

    def _status(self, runner: JobRunner) -> str:
        if runner.step != "caustics":
            return (f"Caustics done; Cycles render {len(runner.done)} of {len(runner.steps) - 1} for the reference "
                    "(its progress on the right; Esc to cancel)")
        return f"Caustics, then Cycles: {runner.stage}, {runner.fraction:.0%} (Esc to cancel)"

    def _done(self, context, runner: JobRunner) -> set:
        if runner.cancelled:
            self.report({'WARNING'}, "Comparison cancelled: nothing was written, and the settings are as they were")
            return {'CANCELLED'}
        if runner.error is not None:
            self.report({'ERROR'}, runner.error)
            return {'CANCELLED'}
        for warning in self._comparison.warnings:
            self.report({'WARNING'}, warning)
        self.report({'INFO'}, self._comparison.summary)
        return {'FINISHED'}
