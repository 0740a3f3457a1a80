"""The same view rendered by Cycles on the CPU with MNEE shadow caustics
(the reference the caustic render is compared with), as a step a
jobs.JobRunner runs. Every setting changed for it is put back."""

from __future__ import annotations

import bpy

from ..export import SceneRead
from ..export.cycles_still import StillRender
from ..export.overrides import Overrides


def _cycles_settings(overrides: Overrides, scene, samples: int, time_limit: float) -> None:
    overrides.set(scene.render, "engine", 'CYCLES')
    for name, value in (("device", 'CPU'), ("samples", samples), ("time_limit", time_limit),
                        ("use_denoising", False), ("pixel_filter_type", 'BOX'), ("filter_width", 1.0)):
        overrides.set(scene.cycles, name, value)
    for name, value in (("film_transparent", False), ("use_motion_blur", False)):
        overrides.set(scene.render, name, value)
    # the reference shows Cycles' own light: Bake While Rendering must not add ours to it
    overrides.set(scene.caustic, "use_bake_on_render", False)


def _shadow_caustics(overrides: Overrides, read: SceneRead) -> None:
    """Turn MNEE on for the transparent objects (casters), the receivers and the
    lamps. Reflectors are neither: MNEE cannot solve for mirrors."""
    for ob in read.scene.objects:
        source = bpy.data.objects[read.sources[ob.name]]
        if ob.is_transparent or ob.is_receiver:
            overrides.set(source.cycles, "is_caustics_caster" if ob.is_transparent else "is_caustics_receiver", True)
    for light in read.scene.lights:
        overrides.set(bpy.data.objects[read.sources[light.name]].data.cycles, "is_caustics_light", True)


class CyclesReference:
    """The Cycles render of `scene`'s camera as a runner's step, with the
    attributes of jobs.RenderJob: `result` is (h,w,4) float32 top row first.
    `start()` starts Blender's render job (in the UI it runs as F12 does, and
    Esc stops it); `run()` renders here and now. The settings stay changed
    while Cycles renders and are put back when it ends, or is stopped."""

    stage = "Cycles reference"

    def __init__(self, scene, read: SceneRead, samples: int, time_limit: float):
        self._scene, self._read, self._samples, self._time_limit = scene, read, samples, time_limit
        self.fraction, self.seconds = 0.0, 0.0
        self.result = self.error = None
        self.cancelled = False
        self._overrides: Overrides | None = None
        self._still: StillRender | None = None

    def _begin(self, wait: bool) -> None:
        self._overrides = Overrides()
        _cycles_settings(self._overrides, self._scene, self._samples, self._time_limit)
        _shadow_caustics(self._overrides, self._read)
        self._still = StillRender(self._scene, self._overrides)
        try:
            if not self._still.start(wait=wait):
                self.error = "Blender did not start the Cycles render (is another render running?)"
        except RuntimeError as exc:
            self.error = f"The Cycles render failed: {exc}"

    def _end(self) -> None:
        """Read the render back (unless stopped) and put every setting back."""
        still, self._still = self._still, None
        try:
            pixels = None if self.cancelled or self.error else still.pixels()
        finally:
            still.close()
            self._overrides.restore()
        self.seconds = still.seconds
        if pixels is not None:
            self.result, self.fraction = pixels, 1.0
        elif self.error is None:
            self.cancelled = True

    def run(self) -> None:
        self._begin(wait=True)
        self._end()

    def start(self) -> None:
        self._begin(wait=False)

    @property
    def running(self) -> bool:
        """Whether Blender still renders; when it has ended, the reference is read and the settings put back."""
        if self._still is not None and self._still.ended:
            self._end()
        return self._still is not None

    def cancel(self) -> None:
        """Drop the reference. The Esc that asks for it has stopped Blender's render already."""
        self.cancelled = True

    def wait(self) -> None:
        """Blender takes the operator away: put the settings back now (the
        main thread cannot wait for Blender's render job, which Blender ends)."""
        if self._still is not None:
            self.cancelled = True
            self._end()
