"""CAUSTIC_OT_compare_cycles: the caustic render next to a Cycles render of
the same camera (CPU, MNEE shadow caustics), with the error between them.
Writes "Caustic Render" (with its passes), "Cycles Reference" and
"Difference"; leaves every render setting as it was. Cycles cannot render
reflectors' caustics, and the report says so. In the UI the caustic render
runs like Render (progress, Esc); the Cycles render after it holds Blender
until it is done, as F12 in the background would."""

import bpy
import numpy as np

from ..comparison.cycles import render_cycles
from ..comparison.metrics import caustic_region, psnr, relative_l2
from ..export import InputError, read_scene, render_settings
from ..export.cycles_still import cycles_enabled
from ..jobs import JobRunner, RenderJob, StepError
from ..writeback.images import show_image, write_image
from .engine_run import EngineOperator
from .render import write_result

REFERENCE_IMAGE = "Cycles Reference"
DIFFERENCE_IMAGE = "Difference"


def reflector_warning(read) -> str | None:
    """What the comparison cannot show when the scene has reflectors: MNEE
    solves only for refracting casters, and a path tracer cannot reach a
    point or sun lamp through a perfect mirror, so Cycles renders no
    caustic from them."""
    names = [o.name for o in read.scene.objects if o.is_reflector]
    if not names:
        return None
    listed = ", ".join(f"'{n}'" for n in names)
    return (f"Cycles (MNEE) cannot render caustics cast by reflectors ({listed}): MNEE handles refraction only, "
            "so the Cycles Reference lacks them and the error includes them in full")


class CAUSTIC_OT_compare_cycles(EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_description = ("Render the camera with caustics and with Cycles (CPU, shadow caustics) and measure "
                      "the difference; Blender waits while Cycles renders")
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
            read = read_scene(context)
            job = RenderJob(read.scene, render_settings(context.scene.caustic))
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return None
        self._read = read
        return JobRunner([context.scene.frame_current], lambda frame: job, self._compare)

    def _status(self, runner: JobRunner) -> str:
        if runner.job is not None and runner.job.fraction >= 1.0:
            return "Caustics done; rendering the Cycles reference (Blender waits for it)"
        return f"Caustics, then Cycles: {runner.stage}, {runner.fraction:.0%} (Esc to cancel)"

    def _compare(self, frame: int, job: RenderJob) -> None:
        context, read = bpy.context, self._read
        scene, props = context.scene, context.scene.caustic
        try:
            reference, cycles_seconds = render_cycles(scene, read, props.cycles_samples, props.cycles_time_limit)
        except RuntimeError as exc:
            raise StepError(f"The Cycles render failed: {exc}") from exc
        image = job.result.image
        difference = np.abs(image - reference)
        difference[..., 3] = 1.0
        write_image(REFERENCE_IMAGE, reference)
        write_image(DIFFERENCE_IMAGE, difference)
        show_image(context, write_result(context, job))
        region = caustic_region(job.result.passes["caustic"])
        props.cycles_seconds = cycles_seconds
        props.cycles_relative_l2 = relative_l2(image, reference, region)
        props.cycles_psnr = psnr(image, reference)
        honesty = reflector_warning(read)
        for warning in read.warnings + job.result.warnings + ([honesty] if honesty else []):
            self.report({'WARNING'}, warning)

    def _done(self, context, runner: JobRunner) -> set:
        if runner.cancelled:
            self.report({'WARNING'}, "Comparison cancelled")
            return {'CANCELLED'}
        if runner.error is not None:
            self.report({'ERROR'}, runner.error)
            return {'CANCELLED'}
        props = context.scene.caustic
        self.report({'INFO'}, f"Caustics {runner.last.seconds:.1f} s, Cycles {props.cycles_seconds:.1f} s: relative "
                              f"L2 {props.cycles_relative_l2:.3f} over the caustics, PSNR {props.cycles_psnr:.1f} dB")
        return {'FINISHED'}
