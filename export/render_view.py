"""The scene as a render sees it. Blender evaluates a scene for rendering
(modifiers at their render settings, such as a Subdivision Surface's Render
levels; objects hidden in the viewport but enabled for render; a geometry
node tree's Is Viewport false; particles at their render amount) only for
a render engine, and its Python API gives no such depsgraph otherwise. So
a render engine of the add-on's own is registered for a moment and Blender
renders the view layer with it, as F12 would; its render() hands the render
depsgraph to the reader and draws nothing. Everything changed for it is put
back: the scene's engine and output settings, and the Render Result, which
gets a slot of its own so that an earlier render stays as it was.
Nothing is written into the file, and no undo step is pushed.

Without a camera, or for a view layer disabled for rendering, Blender
renders nothing, so such a scene is read from the viewport's depsgraph, and
what a render would see differently is named in a warning."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, TypeVar

import bpy

from .cycles_still import RENDER_RESULT
from .errors import InputError
from .overrides import Overrides

T = TypeVar("T")
ENGINE = "CAUSTIC_SCENE_READER"
READ_SLOT = "Caustics: scene read"


class CAUSTIC_RE_scene_reader(bpy.types.RenderEngine):
    """Registered only while a scene is read: hands the render depsgraph to `reader`."""

    bl_idname = ENGINE
    bl_label = "Caustics scene reader"
    reader: Callable = None
    outcome: list = []

    def render(self, depsgraph):
        try:
            type(self).outcome.append(('read', type(self).reader(depsgraph)))
        except Exception as exc:  # Blender would print it and render on: carry it out instead
            type(self).outcome.append(('error', exc))


@contextmanager
def _own_render_slot():
    """The Render Result, if there is one, pointed at a slot kept for scene
    reads while the context lasts, so that the earlier render's slot is left
    alone; without one, the Render Result the read makes is deleted."""
    result = bpy.data.images.get(RENDER_RESULT)
    if result is None:
        try:
            yield
        finally:
            if RENDER_RESULT in bpy.data.images:
                bpy.data.images.remove(bpy.data.images[RENDER_RESULT])
        return
    slots = result.render_slots
    earlier = slots.active_index
    slot = next((s for s in slots if s.name == READ_SLOT), None) or slots.new(name=READ_SLOT)
    slots.active_index = list(slots).index(slot)
    try:
        yield
    finally:
        slots.active_index = earlier


def read_as_render(scene, view_layer, reader: Callable[[object], T]) -> T:
    """`reader(depsgraph)`'s result, for the render depsgraph of `view_layer`
    of `scene` (which must have a camera). Exceptions it raises come out here."""
    CAUSTIC_RE_scene_reader.reader, CAUSTIC_RE_scene_reader.outcome = reader, []
    bpy.utils.register_class(CAUSTIC_RE_scene_reader)
    try:
        with _own_render_slot(), Overrides() as overrides:
            for name, value in (("engine", ENGINE), ("use_compositing", False), ("use_sequencer", False),
                                ("use_multiview", False)):
                overrides.set(scene.render, name, value)
            try:
                bpy.ops.render.render(layer=view_layer.name, scene=scene.name)
            except RuntimeError as exc:
                raise InputError(f"Blender cannot render the view layer '{view_layer.name}': "
                                 f"{str(exc).strip().removeprefix('Error: ')}") from None
    finally:
        bpy.utils.unregister_class(CAUSTIC_RE_scene_reader)
        CAUSTIC_RE_scene_reader.reader = None
    outcome, CAUSTIC_RE_scene_reader.outcome = CAUSTIC_RE_scene_reader.outcome, []
    if not outcome:
        raise InputError(f"Blender rendered nothing of the view layer '{view_layer.name}': is another render "
                         "running, or is the view layer disabled for rendering?")
    kind, value = outcome[0]
    if kind == 'error':
        raise value
    return value


def _modifier_differences(ob) -> list[str]:
    """The modifiers of `ob` that a render evaluates otherwise than the viewport."""
    differ = []
    for modifier in ob.modifiers:
        levels = (getattr(modifier, "levels", None), getattr(modifier, "render_levels", None))
        if modifier.show_viewport != modifier.show_render or (modifier.show_render and levels[0] != levels[1]):
            differ.append(f"modifier '{modifier.name}'")
    return differ


def viewport_differences(view_layer, seen: set[str]) -> list[str]:
    """What a render would see otherwise than the viewport's depsgraph did
    (`seen`: the names of the objects read from it): objects hidden in the
    viewport but enabled for render, and modifiers whose viewport and render
    settings differ, each named."""
    differ = []
    for name in sorted(renderable_objects(view_layer)):
        ob = bpy.data.objects[name]
        if ob.type not in {'MESH', 'LIGHT'}:
            continue
        if name not in seen:
            differ.append(f"'{name}' (hidden in the viewport, so left out)")
        elif ob.type == 'MESH':
            differ += [f"'{name}' ({what}, at its viewport settings)" for what in _modifier_differences(ob)]
    return differ


def renderable_objects(view_layer) -> set[str]:
    """Names of the objects the view layer renders: in included collections
    not disabled for renders, and not disabled for renders themselves."""
    names, stack = set(), [view_layer.layer_collection]
    while stack:
        layer = stack.pop()
        if layer.exclude or layer.collection.hide_render:
            continue
        names.update(ob.name for ob in layer.collection.objects if not ob.hide_render)
        stack.extend(layer.children)
    return names


def adaptive_subdivision(scene, ob) -> bool:
    """Whether Cycles dices `ob` itself at render time (Adaptive
    Subdivision: a Subdivision Surface modifier's option in Blender 5, the
    object's Cycles setting with the Experimental feature set before)."""
    subsurf = [m for m in ob.modifiers if m.type == 'SUBSURF' and m.show_render]
    if not subsurf or scene.render.engine != 'CYCLES':
        return False
    if hasattr(subsurf[-1], "use_adaptive_subdivision"):
        return subsurf[-1].use_adaptive_subdivision
    cycles = getattr(ob, "cycles", None)
    return (getattr(cycles, "use_adaptive_subdivision", False)
            and getattr(scene.cycles, "feature_set", 'SUPPORTED') == 'EXPERIMENTAL')
