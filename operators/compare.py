"""CAUSTIC_OT_compare_cycles: the caustic render next to a Cycles render of
the same camera (CPU, MNEE shadow caustics), with the error between them.
Writes "Caustic Render", "Cycles Reference" and "Difference"; leaves every
render setting as it was. Cycles cannot render reflectors' caustics, and the
report says so."""

import bpy
import numpy as np

from ..comparison.cycles import render_cycles
from ..comparison.metrics import caustic_region, psnr, relative_l2
from ..export import InputError, read_scene, render_settings
from ..export.cycles_still import cycles_enabled
from ..jobs import RenderJob
from ..writeback.images import show_image, write_image
from ..writeback.results import record_run
from .render import RESULT_IMAGE, no_render_running

REFERENCE_IMAGE = "Cycles Reference"
DIFFERENCE_IMAGE = "Difference"


def reflector_warning(read) -> str | None:
    """What the comparison cannot show when the scene has smooth
    reflectors: MNEE solves only for refracting casters, and a path tracer
    cannot reach a point or sun lamp through a perfect mirror, so Cycles
    renders no caustic from them. A rough one's caustic Cycles path-traces
    by its lamp sampling, so it is in the reference."""
    names = [o.name for o in read.scene.objects if o.is_reflector and o.material.smooth]
    if not names:
        return None
    listed = ", ".join(f"'{n}'" for n in names)
    return (f"Cycles (MNEE) cannot render caustics cast by smooth reflectors ({listed}): MNEE handles refraction "
            "only, so the Cycles Reference lacks them and the error includes them in full")


class CAUSTIC_OT_compare_cycles(bpy.types.Operator):
    bl_idname = "caustic.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_description = ("Render the camera with caustics and with Cycles (CPU, shadow caustics) and measure "
                      "the difference; this blocks Blender until both are done")
    # As caustic.render: an undo step keeps the images, and no redo panel re-runs both renders.
    bl_options = {'UNDO'}

    @classmethod
    def poll(cls, context):
        if not cycles_enabled():
            cls.poll_message_set("Compare with Cycles needs the Cycles add-on: turn it on in Preferences > Add-ons")
            return False
        return no_render_running(cls)

    def execute(self, context):
        scene, props = context.scene, context.scene.caustic
        try:
            read = read_scene(context)
            job = RenderJob(read.scene, render_settings(props))
        except InputError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        job.run()
        if job.error is not None:
            self.report({'ERROR'}, job.error)
            return {'CANCELLED'}
        try:
            reference, cycles_seconds = render_cycles(scene, read, props.cycles_samples, props.cycles_time_limit)
        except RuntimeError as exc:
            self.report({'ERROR'}, f"The Cycles render failed: {exc}")
            return {'CANCELLED'}
        image = job.result.image
        difference = np.abs(image - reference)
        difference[..., 3] = 1.0
        write_image(REFERENCE_IMAGE, reference)
        write_image(DIFFERENCE_IMAGE, difference)
        show_image(context, write_image(RESULT_IMAGE, image))
        region = caustic_region(job.result.passes["caustic"])
        record_run(props, job)
        props.cycles_seconds = cycles_seconds
        props.cycles_relative_l2 = relative_l2(image, reference, region)
        props.cycles_psnr = psnr(image, reference)
        honesty = reflector_warning(read)
        for warning in read.warnings + job.result.warnings + ([honesty] if honesty else []):
            self.report({'WARNING'}, warning)
        self.report({'INFO'}, f"Caustics {job.seconds:.1f} s, Cycles {cycles_seconds:.1f} s: relative L2 "
                              f"{props.cycles_relative_l2:.3f} over the caustics, PSNR {props.cycles_psnr:.1f} dB")
        return {'FINISHED'}
