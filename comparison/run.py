"""Compare with Cycles as one run of two steps: the caustic render, then
Cycles' reference of the same view; the images and the error are written
only once both are done, so a run stopped part-way leaves nothing."""

from __future__ import annotations

import bpy
import numpy as np

from ..export import read_scene, render_settings
from ..jobs import JobRunner, RenderJob
from ..writeback.images import show_image, write_image
from ..writeback.results import write_result
from .cycles import CyclesReference
from .metrics import caustic_region, psnr, relative_l2

REFERENCE_IMAGE = "Cycles Reference"
DIFFERENCE_IMAGE = "Difference"
STEPS = ("caustics", "cycles")


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


class Comparison:
    """`runner` runs it (InputError from the constructor if the scene
    cannot be read); `warnings` holds what the user should read after it."""

    def __init__(self, context):
        self.read = read_scene(context)
        self.caustics = RenderJob(self.read.scene, render_settings(context.scene.caustic))
        self.runner = JobRunner(STEPS, self._prepare, self._finish, parts=True)
        self.warnings: list[str] = []

    def _prepare(self, step: str):
        if step == "caustics":
            return self.caustics
        scene = bpy.context.scene
        return CyclesReference(scene, self.read, scene.caustic.cycles_samples, scene.caustic.cycles_time_limit)

    def _finish(self, step: str, job) -> None:
        if step == "cycles":
            self._write(bpy.context, job)

    def _write(self, context, cycles: CyclesReference) -> None:
        props, image, reference = context.scene.caustic, self.caustics.result.image, cycles.result
        difference = np.abs(image - reference)
        difference[..., 3] = 1.0
        write_image(REFERENCE_IMAGE, reference)
        write_image(DIFFERENCE_IMAGE, difference)
        show_image(context, write_result(props, self.caustics))
        props.cycles_seconds = cycles.seconds
        props.cycles_relative_l2 = relative_l2(image, reference, caustic_region(self.caustics.result.passes["caustic"]))
        props.cycles_psnr = psnr(image, reference)
        honesty = reflector_warning(self.read)
        self.warnings = self.read.warnings + self.caustics.result.warnings + ([honesty] if honesty else [])
