"""Compare with Cycles as one run of steps: the caustic render, then Cycles
renders of the same view; the images and the figures are written only once
all are done, so a run stopped part-way leaves nothing.

The reference's caustic light over the caustics (the pixels the caustic
render's caustic lights) is its render less one without caustics. Where
Cycles path-traces every caustic (sources.py), the reference is the mean of
two renders of half the samples each, with different seeds, whose
difference measures its own noise: the error over the caustics, relative to
the reference's caustic light, comes with the share of it that is Cycles'
noise, and no PSNR over them is given where that noise makes most of it.
Where a lamp without a size lights a smooth caster, the reference has only
MNEE's part of its caustic: the report names the lamps and casters, gives
the share of the caustic render's caustic light it lacks, and measures no
error over the caustics."""

from __future__ import annotations

import math
from dataclasses import replace

import bpy
import numpy as np

from ..export import InputError, read_scene, render_settings
from ..jobs import LOWER_RESOLUTION, JobRunner, RenderJob, refusal
from ..writeback.images import show_image, write_image
from ..writeback.results import write_result
from .cycles import CyclesReference, ReferenceRender
from .metrics import caustic_region, half_renders_light_noise, half_renders_noise, light, psnr, relative_l2
from .sources import caustic_sources

# Cycles' CPU render of the reference, as it runs beside the rest: its kernels and scene, and its film and
# render result a pixel (measured in the bpy module: 0.9 GB at 1000 x 1000, 3.3 GB at 3000 x 3000).
CYCLES_BASE_BYTES, CYCLES_BYTES_PER_PIXEL = 0.6e9, 300.0
REFERENCE_IMAGE = "Cycles Reference"
DIFFERENCE_IMAGE = "Difference"
SECOND_SEED, WITHOUT_CAUSTICS = "cycles, second seed", "cycles without caustics"
# The reference's noise makes most of the error over the caustics when its
# square is above this share of the error's square.
NOISY = 0.5


def _renders(props, seed: int, mnee_lamps: frozenset[str], casters: bool) -> dict[str, ReferenceRender]:
    """The Cycles renders, by step: the reference in two renders of half the
    samples each, with two seeds, or with `mnee_lamps` in one of all the
    samples; then, if the scene has `casters`, one without caustics, of half
    the samples. The time limit is shared by samples."""
    samples, limit = props.cycles_samples, props.cycles_time_limit
    half = max(1, (samples + 1) // 2) if not mnee_lamps else max(1, samples // 2)
    renders = ({"cycles": ReferenceRender(samples, 0.0, seed, mnee_lamps=mnee_lamps)} if mnee_lamps else
               {"cycles": ReferenceRender(half, 0.0, seed), SECOND_SEED: ReferenceRender(half, 0.0, seed + 1)})
    if casters:
        renders[WITHOUT_CAUSTICS] = ReferenceRender(half, 0.0, seed + 2, caustics=False)
    total = sum(render.samples for render in renders.values())
    return {step: replace(render, time_limit=limit * render.samples / total) for step, render in renders.items()}


class Comparison:
    """`runner` runs it (InputError from the constructor if the scene
    cannot be read); after it, `warnings` and `summary` hold what the user
    should read."""

    def __init__(self, context):
        self.read = read_scene(context)
        props = context.scene.caustic
        self.settings = render_settings(props)
        self.caustics = RenderJob(self.read.scene, self.settings)
        self.sources = caustic_sources(self.read)
        lamps = frozenset(self.sources.point_lamps) if self.sources.mnee else frozenset()
        self.renders = _renders(props, context.scene.cycles.seed, lamps, bool(self.read.scene.casters))
        too_large = refusal(self.read.scene, self.settings, besides=_cycles_bytes(self.read.scene, len(self.renders)))
        if too_large is not None:
            raise InputError(f"Compare with Cycles: {too_large}")
        self.runner = JobRunner(("caustics", *self.renders), self._prepare, self._finish, parts=True)
        self.references: dict[str, np.ndarray] = {}
        self.cycles_seconds = 0.0
        self.warnings: list[str] = []
        self.summary = ""

    def _prepare(self, step: str):
        if step == "caustics":
            return self.caustics
        return CyclesReference(bpy.context.scene, self.read, self.renders[step], self.settings.max_depth)

    def _finish(self, step: str, job) -> None:
        if step == "caustics":
            return
        self.references[step], self.cycles_seconds = job.result, self.cycles_seconds + job.seconds
        if len(self.references) == len(self.renders):
            self._write(bpy.context)

    def _write(self, context) -> None:
        props, result = context.window_manager.caustic, self.caustics.result
        image, caustic = result.image, result.passes["caustic"]
        first, second = self.references["cycles"], self.references.get(SECOND_SEED)
        without = self.references.get(WITHOUT_CAUSTICS)
        reference = first if second is None else 0.5 * (first + second)
        difference = np.abs(image - reference)
        difference[..., 3] = 1.0
        write_image(REFERENCE_IMAGE, reference)
        write_image(DIFFERENCE_IMAGE, difference)
        show_image(context, write_result(props, self.caustics))
        props.cycles_seconds = self.cycles_seconds

        region = caustic_region(caustic)
        figures, warnings = self._figures(image, caustic, region, reference, first, second, without)
        for name, value in figures.items():
            setattr(props, name, value)
        if props.cycles_reference != 'MNEE' and not props.cycles_noise ** 2 <= NOISY * props.cycles_relative_l2 ** 2:
            props.cycles_psnr_outside = not region.all()
            what = "the caustics" if props.cycles_reference == 'PATH_TRACED' else "the image"
            warnings.append(f"The Cycles Reference is too noisy to judge {what}: its own noise, "
                            f"{props.cycles_noise:.3f}, makes most of the relative L2 of "
                            f"{props.cycles_relative_l2:.3f} over {what}"
                            f"{', so no PSNR is given over them' if props.cycles_psnr_outside else ''}; raise "
                            f"Cycles Samples (now {context.scene.caustic.cycles_samples})")
        props.cycles_psnr = psnr(image, reference, ~region if props.cycles_psnr_outside else None)
        self.warnings = self.read.warnings + result.warnings + warnings
        self.summary = summary(props, self.caustics.seconds)

    def _figures(self, image, caustic, region, reference, first, second, without) -> tuple[dict, list[str]]:
        """WindowManager.caustic's figures by name, but the PSNR, over the
        caustics' pixels `region`; and the warnings. `reference` is the
        `first` render, or its mean with the `second`; `without` is the one
        without caustics, if any."""
        if without is None:
            return dict(cycles_reference='NONE', cycles_psnr_outside=False,
                        cycles_relative_l2=relative_l2(image, reference, region),
                        cycles_noise=half_renders_noise(first, second, region, of=reference),
                        cycles_caustic_ratio=math.nan, cycles_caustic_noise=math.nan), []
        theirs = reference[..., :3] - without[..., :3]
        ours, their_light = light(caustic, region), light(theirs, region)
        ratio = ours / their_light if their_light > 0 else math.inf
        if second is None:
            return dict(cycles_reference='MNEE', cycles_psnr_outside=not region.all(),
                        cycles_relative_l2=math.nan, cycles_noise=math.nan, cycles_caustic_ratio=ratio,
                        cycles_caustic_noise=math.nan), [self._lacking(their_light / ours if ours > 0 else math.nan)]
        noise = half_renders_light_noise(first, second, region) / their_light if their_light > 0 else math.inf
        return dict(cycles_reference='PATH_TRACED', cycles_psnr_outside=False,
                    cycles_relative_l2=relative_l2(image, reference, region, of=theirs),
                    cycles_noise=half_renders_noise(first, second, region, of=theirs),
                    cycles_caustic_ratio=ratio, cycles_caustic_noise=ratio * noise), []

    def _lacking(self, held: float) -> str:
        """The warning that the reference lacks part of the caustic, with the
        share `held` of the caustic render's caustic light it holds (noise
        can make it a little below 0)."""
        held = max(0.0, held)
        share = ("" if not math.isfinite(held) else
                 f" Over the caustics it holds {held:.0%} of the caustic render's caustic light: it lacks "
                 f"{max(0.0, 1.0 - held):.0%}.")
        return (f"The Cycles Reference lacks part of the caustic. {self.sources.lacking()}.{share} No error is "
                "measured over the caustics; give the lamps a size (Radius, Angle) for a reference that "
                "path-traces them")


def summary(props, caustic_seconds: float) -> str:
    """The comparison's figures in a line, as its report gives them."""
    times = f"Caustics {caustic_seconds:.1f} s, Cycles {props.cycles_seconds:.1f} s"
    where = " outside the caustics" if props.cycles_psnr_outside else ""
    psnr_text = f"PSNR {props.cycles_psnr:.1f} dB{where}" if math.isfinite(props.cycles_psnr) else "identical"
    if props.cycles_reference == 'MNEE':
        return f"{times} (MNEE): {psnr_text}; no error over the caustics, which the Cycles Reference lacks in part"
    error, noise = props.cycles_relative_l2, props.cycles_noise
    without_noise = math.sqrt(max(0.0, error * error - noise * noise))
    if props.cycles_reference == 'NONE':
        return (f"{times} (no caustics): relative L2 {error:.3f}, {without_noise:.3f} without the Cycles "
                f"Reference's own noise ({noise:.3f}); {psnr_text}")
    return (f"{times} (path-traced): relative L2 {error:.3f} over the caustics (of Cycles' caustic light), "
            f"{without_noise:.3f} without the Cycles Reference's own noise ({noise:.3f}); caustic light "
            f"{props.cycles_caustic_ratio:.2f} ± {props.cycles_caustic_noise:.2f} of Cycles'; {psnr_text}")


def _cycles_bytes(scene, renders: int) -> dict[str, tuple[float, str]]:
    """What a comparison holds besides the caustic render: one Cycles render
    at a time, the `renders` references kept as float RGBA, and the
    reference and difference images (part: (bytes, what to lower))."""
    pixels = scene.camera.pixx * scene.camera.pixy
    return {"the Cycles reference render": (CYCLES_BASE_BYTES + CYCLES_BYTES_PER_PIXEL * pixels, LOWER_RESOLUTION),
            "the comparison's images": (16.0 * (renders + 2) * pixels, LOWER_RESOLUTION)}
