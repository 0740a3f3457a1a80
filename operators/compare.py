"""CAUSTIC_OT_compare_cycles: the caustic render next to a Cycles render of
the same camera (CPU, MNEE shadow caustics), with the error between them
(comparison.run). Writes "Caustic Render" (with its passes), "Cycles
Reference" and "Difference"; leaves every render setting as it was. Cycles
cannot render reflectors' caustics, and the report says so. In the UI both
halves run like Render: the caustics on a worker thread, then Cycles as
Blender's own render job (its progress bar and render view, as F12); Esc
stops either, and a stopped comparison writes nothing."""

import bpy

from ..comparison.run import Comparison
from ..export import InputError
from ..export.cycles_still import cycles_enabled
from ..jobs import JobRunner
from .engine_run import EngineOperator


class CAUSTIC_OT_compare_cycles(EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_description = ("Render the camera with caustics and with Cycles (CPU, shadow caustics) and measure "
                      "the difference")
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
        if runner.step == "cycles":
            return "Caustics done; Cycles renders the reference (its progress on the right; Esc to cancel)"
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
        props = context.scene.caustic
        self.report({'INFO'}, f"Caustics {self._comparison.caustics.seconds:.1f} s, Cycles "
                              f"{props.cycles_seconds:.1f} s: relative L2 {props.cycles_relative_l2:.3f} over the "
                              f"caustics, PSNR {props.cycles_psnr:.1f} dB")
        return {'FINISHED'}
