"""The same view rendered by Cycles on the CPU (the reference the caustic
render is compared with), as a step a jobs.JobRunner runs: the light the
caustic render computes (whitted.py), the caustics path-traced, or by MNEE
for the lamps Cycles cannot path-trace them from (sources.py). Every
setting changed for it is put back."""

from __future__ import annotations

from dataclasses import dataclass

import bpy

from ..export import SceneRead
from ..export.cycles_still import StillRender
from ..export.overrides import Overrides
from .whitted import black_after_a_diffuse_bounce, whitted_settings


def _cycles_settings(overrides: Overrides, scene, samples: int, time_limit: float, seed: int) -> None:
    overrides.set(scene.render, "engine", 'CYCLES')
    for name, value in (("device", 'CPU'), ("samples", samples), ("time_limit", time_limit),
                        ("use_adaptive_sampling", False), ("seed", seed), ("use_animated_seed", False),
                        ("use_denoising", False), ("pixel_filter_type", 'BOX'), ("filter_width", 1.0)):
        overrides.set(scene.cycles, name, value)
    for name, value in (("film_transparent", False), ("use_motion_blur", False)):
        overrides.set(scene.render, name, value)
    # the reference shows Cycles' own light: Bake While Rendering must not add ours to it
    overrides.set(scene.caustic, "use_bake_on_render", False)


def _shadow_caustics(overrides: Overrides, scene, read: SceneRead, lamps: frozenset[str]) -> None:
    """MNEE for the lamps named in `lamps` (Blender objects), through the
    smooth transparent objects (casters), onto the receivers. Every other
    lamp, the world and every other object are no part of it, whatever the
    user set, so that Cycles path-traces their caustics. Reflectors are
    never casters: MNEE cannot solve for mirrors."""
    casters = {read.sources[o.name] for o in read.scene.objects if o.is_transparent and o.material.smooth}
    receivers = {read.sources[o.name] for o in read.scene.objects if o.is_receiver}
    for name in sorted({read.sources[o.name] for o in read.scene.objects}):
        settings = bpy.data.objects[name].cycles
        overrides.set(settings, "is_caustics_caster", bool(lamps) and name in casters)
        overrides.set(settings, "is_caustics_receiver", bool(lamps) and name in receivers)
    for light in read.scene.lights:
        name = read.sources[light.name]
        overrides.set(bpy.data.objects[name].data.cycles, "is_caustics_light", name in lamps)
    if scene.world is not None:
        overrides.set(scene.world.cycles, "is_caustics_light", False)


def _diffuse_materials(read: SceneRead) -> list:
    """The Blender materials of the objects that are neither glass nor mirrors."""
    names = {read.materials[o.name] for o in read.scene.objects if not o.is_caster}
    return [bpy.data.materials[name] for name in sorted(n for n in names if n is not None)]


@dataclass(frozen=True)
class ReferenceRender:
    """One Cycles render of the reference: its samples, time limit (s, 0 for
    none) and seed; with `caustics`, the caustics (path-traced, and by MNEE
    for the lamps `mnee_lamps` names), without, none."""

    samples: int
    time_limit: float
    seed: int
    caustics: bool = True
    mnee_lamps: frozenset[str] = frozenset()


class CyclesReference:
    """The Cycles render of `scene`'s camera as a runner's step, with the
    attributes of jobs.RenderJob: `result` is (h,w,4) float32 top row first.
    `start()` starts Blender's render job (in the UI it runs as F12 does, and
    Esc stops it); `run()` renders here and now. The settings stay changed
    while Cycles renders and are put back when it ends, or is stopped."""

    stage = "Cycles reference"

    def __init__(self, scene, read: SceneRead, render: ReferenceRender, max_depth: int):
        self._scene, self._read, self.render, self._max_depth = scene, read, render, max_depth
        self.fraction, self.seconds = 0.0, 0.0
        self.result = self.error = None
        self.cancelled = False
        self._overrides: Overrides | None = None
        self._still: StillRender | None = None
        self._take_out: list = []

    def _begin(self, wait: bool) -> None:
        self._overrides = Overrides()
        render = self.render
        _cycles_settings(self._overrides, self._scene, render.samples, render.time_limit, render.seed)
        whitted_settings(self._overrides, self._scene, self._max_depth, render.caustics)
        _shadow_caustics(self._overrides, self._scene, self._read, render.mnee_lamps if render.caustics
                         else frozenset())
        self._take_out = [take_out for material in _diffuse_materials(self._read)
                          if (take_out := black_after_a_diffuse_bounce(material)) is not None]
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
            for take_out in reversed(self._take_out):
                take_out()
            self._take_out = []
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
