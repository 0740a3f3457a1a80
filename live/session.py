"""Live caustics: while Scene.caustic.use_live is on, every change that can
move a caustic (changes.py) runs the pass from the lights and the maps on a
worker thread, and the receivers' bake images show the result in every
viewport and render (writeback/live.py). jobs/live.py decides what runs
when: a preview while the user works, the scene's own settings once all is
quiet.

Blender's handlers only take note; `tick`, a timer on the main thread,
reads the scene, starts the job and writes its images. A run of Render,
Bake or Compare pauses Live, and so does Blender's own render, whose
thread reads the images Live writes; Live takes up the scene again after
them.
Live follows the window's scene: it rests while the window shows a scene
without Live, updates once on coming back, and hands over to a scene
whose own Live is on.
In the background Blender runs no timers, so none is registered there (a
caller may run `tick` itself): bpy 4.5's module hangs at exit after a file
is loaded while a Python timer is registered."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Optional

import bpy
from bpy.app.handlers import persistent

from ..caustic_addon import MapCache
from ..export import InputError, bake_settings, read_for_bake
from ..export.render_view import ENGINE as READER_ENGINE
from ..jobs.live import PREVIEW, REFINE, LiveJob, LiveSchedule, preview_settings
from ..operators.engine_run import EngineOperator
from ..writeback.live import LiveImages, pack_live, remove_live
from .changes import forget_meshes, moves_caustic, settings_key

# Seconds between the timer's calls while Live is on, and while the window
# shows another scene, one without Live.
INTERVAL = 0.01
AWAY_INTERVAL = 0.25
# The maps Live keeps, so that a frame or a state seen again (playback's
# next loop, scrubbing, undo) shows at once: at most this many, holding at
# most this many bytes.
KEPT_MAPS = 1024
KEPT_MAP_BYTES = 256 << 20


@dataclass
class Update:
    """One update shown: its kind, seconds from the first change it shows
    to its images, the main thread's seconds for it (read and write),
    whether its maps were kept from an earlier update, and the engine's
    seconds by stage (RenderResult.stats)."""

    kind: str
    latency: float
    main_thread: float
    maps_cached: bool
    stages: dict


@dataclass
class Live:
    """Live's state for one scene; `updates` keeps the last figures, `message`
    why nothing shows; `away` while the window shows another scene."""

    scene: str
    schedule: LiveSchedule = field(default_factory=LiveSchedule)
    images: LiveImages = field(default_factory=LiveImages)
    cache: MapCache = field(default_factory=lambda: MapCache(KEPT_MAPS, KEPT_MAP_BYTES))
    read_from: set = field(default_factory=set)
    meshes: dict = field(default_factory=dict)
    settings: tuple = ()
    changed_at: Optional[float] = None
    read: object = None
    read_seconds: float = 0.0
    message: str = ""
    updates: list = field(default_factory=list)
    away: bool = False

    def changed(self) -> None:
        if self.changed_at is None:
            self.changed_at = time.perf_counter()
        self.schedule.changed()


SESSION: Optional[Live] = None
# True from a render's render_init to its render_complete or render_cancel.
_blender_rendering = False
# How many updates' figures a session keeps.
KEPT_FIGURES = 256


def start(scene) -> Live:
    """Live on `scene`, from its current state."""
    global SESSION
    _end()
    SESSION = Live(scene.name, settings=settings_key(scene))
    SESSION.changed()
    if not bpy.app.background and not bpy.app.timers.is_registered(tick):
        bpy.app.timers.register(tick, first_interval=0.0)
    return SESSION


def _end() -> None:
    """Stop the session's job; what it wrote stays."""
    global SESSION
    if SESSION is not None:
        SESSION.schedule.cancel()
        SESSION = None


def _end_timer() -> None:
    """The session ended and its timer taken off."""
    _end()
    if bpy.app.timers.is_registered(tick):
        bpy.app.timers.unregister(tick)


def stop() -> None:
    """Live off: its job stopped, what it added taken out."""
    _end_timer()
    remove_live()


def shows_final(scene) -> bool:
    """Whether Live's images hold `scene`'s caustic at its own settings, with no change since."""
    live = SESSION
    return live is not None and live.scene == scene.name and not live.away and live.schedule.settled()


def _blender_renders() -> bool:
    """Blender's own render runs: from the interface a job, whose thread
    reads the receivers' images; in the background a call that the render
    handlers bracket."""
    return _blender_rendering or bpy.app.is_job_running('RENDER')


def _begin_update(live: Live, kind: str) -> None:
    clock = time.perf_counter()
    try:
        read = read_for_bake(bpy.context, depsgraph=bpy.context.evaluated_depsgraph_get(), meshes=live.meshes)
        settings = bake_settings(bpy.context.scene.caustic)
    except InputError as exc:
        live.message, live.changed_at = str(exc), None
        live.schedule.pending = False
        return
    live.read, live.read_from = read, set(read.sources.values())
    live.read_seconds = time.perf_counter() - clock
    refined = live.schedule.refined_previews
    job = LiveJob(read.scene, preview_settings(settings, refined) if kind == PREVIEW else settings, live.cache,
                  changed_at=live.changed_at if kind == PREVIEW else None,
                  alternative=preview_settings(settings, not refined) if kind == PREVIEW else None)
    if kind == PREVIEW:
        live.changed_at = None
    live.schedule.started(kind, job)
    job.start()


def _finish_update(live: Live) -> None:
    job, kind = live.schedule.job, live.schedule.kind
    if not live.schedule.ended():
        if job.error is not None:
            live.message = job.error
        return
    clock = time.perf_counter()
    shown, warnings = live.images.show(live.read, job.result.maps, job.images, pack=kind == REFINE)
    live.message = "" if shown else (warnings[0] if warnings else "No receiver can show a caustic")
    job.drop_maps()
    now = time.perf_counter()
    latency = now - job.changed_at if job.changed_at is not None else float("nan")
    stats = job.result.stats
    live.updates = live.updates[-(KEPT_FIGURES - 1):] + [Update(kind, latency, live.read_seconds + now - clock,
                                                                       stats["maps_cached"], stats["seconds"])]
    for area in bpy.context.screen.areas if bpy.context.screen is not None else ():
        if area.type == 'VIEW_3D':
            area.tag_redraw()


def tick() -> Optional[float]:
    """The timer: end a finished job and show it, start what is due.
    Returns the seconds to the next call, None once Live is off."""
    live = SESSION
    if live is None:
        return None
    scene = bpy.data.scenes.get(live.scene)
    if scene is None or not scene.caustic.use_live:
        stop()
        return None
    shown = bpy.context.scene
    if shown != scene:
        if shown is not None and shown.caustic.use_live:
            start(shown)
            return INTERVAL
        # the scene's objects may change meanwhile, in other scenes that hold them
        if live.schedule.job is not None:
            live.schedule.cancel()
        live.away = True
        return AWAY_INTERVAL
    if live.away:
        live.away = False
        live.meshes.clear()
        live.changed()
    key = settings_key(scene)
    if key != live.settings:
        live.settings = key
        live.meshes.clear()
        live.changed()
    if EngineOperator.running or _blender_renders():
        if live.schedule.job is not None:
            live.schedule.cancel()
            live.changed()
        return INTERVAL
    if live.schedule.job is not None and not live.schedule.job.running:
        _finish_update(live)
    kind = live.schedule.due()
    if kind is not None:
        _begin_update(live, kind)
    return INTERVAL


def _on_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    live = SESSION
    if not _on_main_thread() or scene.render.engine == READER_ENGINE:
        return
    if not scene.caustic.use_live:
        return
    if live is None or live.scene != scene.name:
        start(scene)
        return
    echo, live.images.echo = live.images.echo, set()
    forget_meshes(depsgraph, live.meshes)
    if moves_caustic(depsgraph, live.read_from, echo):
        live.changed()


@persistent
def on_frame_change(scene, depsgraph=None) -> None:
    live = SESSION
    if _on_main_thread() and live is not None and live.scene == scene.name and scene.caustic.use_live:
        live.meshes.clear()
        live.changed()


@persistent
def on_render_start(scene, *_) -> None:
    global _blender_rendering
    _blender_rendering = scene.render.engine != READER_ENGINE or _blender_rendering


@persistent
def on_render_end(scene, *_) -> None:
    global _blender_rendering
    if scene.render.engine != READER_ENGINE:
        _blender_rendering = False


@persistent
def on_undo(*_) -> None:
    if SESSION is not None:
        SESSION.images.wired.clear()
        SESSION.meshes.clear()
        SESSION.changed()


@persistent
def on_load(*_) -> None:
    _end()


@persistent
def on_loaded(*_) -> None:
    if bpy.context.scene is not None and bpy.context.scene.caustic.use_live:
        start(bpy.context.scene)


@persistent
def on_save(*_) -> None:
    pack_live()


_HANDLERS = (("depsgraph_update_post", on_depsgraph_update), ("frame_change_post", on_frame_change),
             ("undo_post", on_undo), ("redo_post", on_undo), ("load_pre", on_load), ("load_post", on_loaded),
             ("save_pre", on_save), ("render_init", on_render_start), ("render_complete", on_render_end),
             ("render_cancel", on_render_end))


def register() -> None:
    for name, handler in _HANDLERS:
        getattr(bpy.app.handlers, name).append(handler)


def unregister() -> None:
    _end_timer()
    for name, handler in _HANDLERS:
        getattr(bpy.app.handlers, name).remove(handler)
