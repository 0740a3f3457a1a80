"""When Live runs the engine, and with what settings; no bpy.

A change starts a preview (`preview_settings`: fewer light rays, a coarser
map, beam refinement only where previews fit their budget), which runs to
its end and is shown: it takes a fraction of a second,
and a preview cancelled at every mouse move would show nothing until the
mouse stops. Changes that come meanwhile are folded into one: the next
preview reads the scene as it is then. Once nothing has changed for
`REFINE_AFTER` seconds, the scene's own settings run once (the refine); a
change cancels a refine that is running."""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable, Optional

from ..caustic_addon import RenderSettings
from ..caustic_addon.maps.cache import lamp_pass_key, scene_digest
from .job import RenderJob, map_rgba

PREVIEW, REFINE = "preview", "refine"
# Quiet time, in seconds, before the full settings run.
REFINE_AFTER = 0.2
# A preview traces this fraction of the light rays, into maps of at most PREVIEW_MAP_CELLS cells a side.
PREVIEW_RAY_SHARE = 1 / 8
PREVIEW_MIN_RAYS = 1000
PREVIEW_MAP_CELLS = 256
# Wavelength bands a preview of a dispersive caster traces, at most: the
# lamp rays are shared among the bands, so fewer bands have finer grids.
PREVIEW_BANDS = 3
# Seconds of engine a preview may take: 10 updates a second. Previews refine
# their beams once (about twice the time, half the error at silhouettes)
# while an unrefined one takes under a third of it, and stop where a refined
# one overruns it; between the two, they keep what they do.
PREVIEW_BUDGET_S = 0.1


def preview_settings(settings: RenderSettings, refined: bool = False) -> RenderSettings:
    """The settings of a preview of `settings`: a share of the light rays,
    beam refinement once if `refined` and none otherwise, cells four times
    wider (or a map at most PREVIEW_MAP_CELLS a side), and at most
    PREVIEW_BANDS wavelength bands, whose grids then get more of the rays
    (a dispersive gem's preview, 40,000 lamp rays: 43% relative L2 against
    the full caustic with 6 bands refined, 31% with 3, at the same cost;
    fewer rays a band cut more grid triangles across facet edges, whose
    light goes to photons, a haze). The adaptive density's k nearest photons
    shrink with the photons, so its kernel keeps its width: k-nearest
    estimates are biased up where photons are few (+16% over the ball
    lens's floor at an eighth of 40,000 with k = 64), and the preview would
    be brighter. Beams and splats keep the light's total as they are."""
    rays = min(settings.lamp_rays, max(PREVIEW_MIN_RAYS, round(settings.lamp_rays * PREVIEW_RAY_SHARE)))
    share = rays / max(settings.lamp_rays, 1)
    return replace(settings, lamp_rays=rays, beam_refinement=min(settings.beam_refinement, int(refined)), spp=1,
                   bands=min(settings.bands, PREVIEW_BANDS),
                   k_nearest=max(1, round(settings.k_nearest * share)),
                   map_scale=None if settings.map_scale is None else settings.map_scale * 4.0,
                   map_resolution_limit=min(settings.map_resolution_limit, PREVIEW_MAP_CELLS))


class LiveJob(RenderJob):
    """A Live update: the render, then each map's image (`images`,
    receiver name -> map_rgba), both on the worker thread; `changed_at`
    is when the first change it shows was made (None for a refine). With
    `alternative` settings (a preview's other refinement), these run
    instead where the cache keeps their maps and not the settings' own:
    a frame seen again shows at once, whichever way it was first traced."""

    def __init__(self, *args, changed_at: Optional[float] = None, alternative: Optional[RenderSettings] = None,
                 **kwargs):
        super().__init__(*args, **kwargs)
        self.changed_at, self.alternative = changed_at, alternative
        self.images: dict = {}

    def run(self) -> None:
        digest = scene_digest(self.scene)
        self.key = lamp_pass_key(self.scene, self.settings, digest)
        if self.alternative is not None and self.cache.get(self.key) is None:
            other = lamp_pass_key(self.scene, self.alternative, digest)
            if self.cache.get(other) is not None:
                self.settings, self.key = self.alternative, other
        super().run()
        if self.result is not None:
            self.images = {name: map_rgba(imap, self.settings.threads) for name, imap in self.result.maps.items()}


class LiveSchedule:
    """Which update runs when. The caller reports changes (`changed`),
    asks what to start (`due`), starts it (`started`) and hands back each
    job that ended (`ended`), which says whether to show its result.
    `refined_previews`: whether previews refine their beams, as the last
    preview's time against PREVIEW_BUDGET_S decides. `clock` gives seconds."""

    def __init__(self, clock: Callable[[], float] = time.monotonic):
        self.clock = clock
        self.pending = False
        self.job: Optional[RenderJob] = None
        self.kind: Optional[str] = None
        self.shown: Optional[str] = None
        self.refined_previews = False
        self._quiet_since = clock()

    def changed(self) -> None:
        """Something that moves a caustic changed."""
        self.pending = True
        self._quiet_since = self.clock()
        if self.job is not None and self.kind == REFINE:
            self.job.cancel()

    def due(self) -> Optional[str]:
        """PREVIEW, REFINE or None: what to start now."""
        if self.job is not None:
            return None
        if self.pending:
            return PREVIEW
        if self.shown == PREVIEW and self.clock() - self._quiet_since >= REFINE_AFTER:
            return REFINE
        return None

    def settled(self) -> bool:
        """Whether the last update shown is a refine, with nothing changed or running since."""
        return self.job is None and not self.pending and self.shown == REFINE

    def started(self, kind: str, job: RenderJob) -> None:
        self.job, self.kind = job, kind
        if kind == PREVIEW:
            self.pending = False

    def ended(self) -> bool:
        """The running job has ended: whether its result is to be shown
        (False when it failed, was cancelled, or a refine that a change
        made stale)."""
        job, kind = self.job, self.kind
        self.job = self.kind = None
        if job.result is None or (kind == REFINE and self.pending):
            return False
        if kind == PREVIEW and self.refined_previews and job.seconds > PREVIEW_BUDGET_S:
            self.refined_previews = False
        elif kind == PREVIEW and not self.refined_previews and job.seconds < PREVIEW_BUDGET_S / 3:
            self.refined_previews = True
        self.shown = kind
        return True

    def cancel(self) -> None:
        """Stop the running job and forget what was pending."""
        if self.job is not None:
            self.job.cancel()
            self.job.wait()
        self.job = self.kind = None
        self.pending, self.shown = False, None
