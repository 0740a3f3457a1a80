"""Caustics in F12 and animation renders with no bake step: with
Scene.caustic.use_bake_on_render, or Live on, the render handlers bake each frame's
caustics into the receivers' materials just before the frame renders, so
EEVEE and Cycles show the current frame's caustic.

When a render starts (render_init) the current frame is baked and wired
in, before Blender builds the render's depsgraph, so the materials it
renders hold the bake's nodes. Then, for each frame (frame_change_post,
with the render's depsgraph evaluated at that frame: render visibility,
render modifier levels), the maps are traced again and written into the
same images. Blender runs these handlers on its main thread in command-line
renders (`blender -b ... -f`, `-a`), where changing data is safe; a render
started from the UI runs them on its render thread, where the add-on must
not touch Blender's data, so there it leaves the materials as they are:
Render > Render Image with Caustics and Render Animation with Caustics
bake on the main thread first and then start Blender's render through
`start_render`, which keeps these handlers out of it; with Live or Bake
While Rendering on, F12 and Ctrl-F12 run those two (shortcuts.py). The last frame's bake
stays in the materials after the render, as Bake Caustics leaves it."""

import threading

import bpy
from bpy.app.handlers import persistent

from ..export import InputError, bake_settings, read_for_bake
from ..export.render_view import ENGINE as READER_ENGINE
from ..jobs import RenderJob, map_rgba
from ..writeback.images import own_image, write_image
from ..writeback.bake import IMAGE_PREFIX, bake_maps


# True while a render that start_render began runs: its frames are baked already.
_baked_ahead = False


def _wanted(scene) -> bool:
    # the add-on's own scene read is a render too: it must not bake
    if not (scene.caustic.use_bake_on_render or scene.caustic.use_live) or scene.render.engine == READER_ENGINE \
            or _baked_ahead:
        return False
    if threading.current_thread() is not threading.main_thread():
        if not scene.caustic.use_bake_on_render:
            return False  # Live keeps the current frame's caustic in the materials
        print("Caustics: this render uses the caustics baked before it: from the interface, Bake While Rendering "
              "bakes through F12, Ctrl-F12 and Render > Render Image or Animation with Caustics")
        return False
    return True


def start_render(invoke: bool, **options) -> set:
    """Blender's own render (render.render with `options`) of frames baked
    ahead, so these handlers stay out of it: with `invoke` as F12 or
    Ctrl-F12 start it (in the background that, too, renders before it
    returns), else here and now. Returns the render operator's result."""
    global _baked_ahead
    _baked_ahead = True
    started = set()
    try:
        started = bpy.ops.render.render('INVOKE_DEFAULT' if invoke else 'EXEC_DEFAULT', **options)
    finally:
        _baked_ahead = 'RUNNING_MODAL' in started
    return started


@persistent
def _render_ended(*_) -> None:
    """render_complete or render_cancel (on the render thread in the UI: it only clears a flag)."""
    global _baked_ahead
    _baked_ahead = False


def _trace(scene, depsgraph):
    """(SceneRead, RenderResult) of the frame, or None after printing why not."""
    try:
        read = read_for_bake(None, depsgraph=depsgraph)
        job = RenderJob(read.scene, bake_settings(scene.caustic))
    except InputError as exc:
        print(f"Caustics: frame {scene.frame_current} renders without caustics: {exc}")
        return None
    job.run()
    if job.error is not None:
        print(f"Caustics: frame {scene.frame_current} renders without caustics: {job.error}")
        return None
    return read, job.result


@persistent
def bake_at_render_start(scene, *_) -> None:
    if not _wanted(scene):
        return
    traced = _trace(scene, bpy.context.evaluated_depsgraph_get())
    if traced is not None:
        read, result = traced
        for warning in bake_maps(read, result.maps)[1]:
            print(f"Caustics: {warning}")


@persistent
def bake_rendered_frame(scene, depsgraph=None) -> None:
    if depsgraph is None or depsgraph.mode != 'RENDER' or not _wanted(scene):
        return
    traced = _trace(scene, depsgraph)
    if traced is None:
        return
    for name, imap in traced[1].maps.items():
        image = own_image(IMAGE_PREFIX + name)
        if image is None or image.source == 'SEQUENCE':
            continue
        if tuple(image.size) != imap.shape[::-1]:
            print(f"Caustics: frame {scene.frame_current}: the map of '{name}' changed size since the render "
                  "started (the receiver moved or changed shape); it keeps the earlier frame's caustic")
            continue
        write_image(image.name, map_rgba(imap))


def register() -> None:
    bpy.app.handlers.render_init.append(bake_at_render_start)
    bpy.app.handlers.frame_change_post.append(bake_rendered_frame)
    bpy.app.handlers.render_complete.append(_render_ended)
    bpy.app.handlers.render_cancel.append(_render_ended)


def unregister() -> None:
    bpy.app.handlers.render_cancel.remove(_render_ended)
    bpy.app.handlers.render_complete.remove(_render_ended)
    bpy.app.handlers.frame_change_post.remove(bake_rendered_frame)
    bpy.app.handlers.render_init.remove(bake_at_render_start)
