"""CAUSTIC_OT_render_image_with_caustics and
CAUSTIC_OT_render_animation_with_caustics (in the Render menu): F12 and
Ctrl-F12 showing the caustics of every frame they render, with no manual
bake. From the interface Blender runs its render handlers on the render
thread, where an add-on must not change data, so these bake first, on the
main thread with progress and Esc: the current frame as Bake Caustics does
it, or the range as Bake Caustic Animation does it (an image sequence the
materials follow). Then they start Blender's own render as F12 or Ctrl-F12
would (its render view, its progress, its Esc). The bake stays in the
materials afterwards, as the bake operators leave it. F12 and Ctrl-F12
themselves come here when a scene wants caustics in its renders
(shortcuts.py)."""

import bpy

from ..jobs import JobRunner
from ..live import session as live
from .bake import BakeFrame
from .bake_animation import BakeFrames
from .bake_on_render import start_render


def render_takes_a_range() -> bool:
    """Whether Blender's Render operator takes a frame range (5.x), not only the scene's."""
    return "frame_start" in bpy.ops.render.render.get_rna_type().properties


class RenderAfterBake:
    """Mixin for a bake operator: after a whole bake, Blender's render with
    `_render_options()`, started as F12 starts it when the operator was
    invoked (a button, a menu), else here and now (a script). Called by F12
    or Ctrl-F12, it passes the key on to Blender's Render unless
    `_bakes_for(scene)`."""

    from_shortcut: bpy.props.BoolProperty(options={'HIDDEN', 'SKIP_SAVE'})

    _invoked = False

    def _passes_key_on(self, context) -> bool:
        return self.from_shortcut and not self._bakes_for(context.scene)

    def invoke(self, context, event):
        if self._passes_key_on(context):
            return {'PASS_THROUGH'}
        self._invoked = True
        return super().invoke(context, event)

    def execute(self, context):
        return {'PASS_THROUGH'} if self._passes_key_on(context) else super().execute(context)

    def _done(self, context, runner: JobRunner) -> set:
        result = super()._done(context, runner)
        if 'FINISHED' not in result or runner.cancelled or runner.error is not None:
            return result
        try:
            options = self._render_options(context) | ({"use_viewport": True} if self.from_shortcut else {})
            started = start_render(self._invoked, **options)
        except RuntimeError as exc:
            self.report({'ERROR'}, f"The caustics are baked, but Blender's render failed: {exc}")
            return result
        if 'CANCELLED' in started:
            self.report({'ERROR'}, "The caustics are baked, but Blender did not start the render")
        return result


class CAUSTIC_OT_render_image_with_caustics(RenderAfterBake, BakeFrame, bpy.types.Operator):
    bl_idname = "caustic.render_image_with_caustics"
    bl_label = "Render Image with Caustics"
    bl_description = "Bake this frame's caustics into the receivers' materials, then render the scene as F12 does"
    # An undo step keeps the bake; no redo panel would re-run bake and render.
    bl_options = {'UNDO'}

    write_still: bpy.props.BoolProperty(
        name="Write Image", options={'SKIP_SAVE'},
        description="Save the rendered image to the output path, as Render Image's option does")

    @staticmethod
    def _bakes_for(scene) -> bool:
        """Live's images already hold this frame's full caustic once it refined."""
        return scene.caustic.use_bake_on_render or (scene.caustic.use_live and not live.shows_final(scene))

    def _render_options(self, context) -> dict:
        return {"write_still": self.write_still}


class CAUSTIC_OT_render_animation_with_caustics(RenderAfterBake, BakeFrames, bpy.types.Operator):
    bl_idname = "caustic.render_animation_with_caustics"
    bl_label = "Render Animation with Caustics"
    bl_description = "Bake every frame's caustics, then render the animation as Ctrl-F12 does"
    bl_options = {'UNDO'}

    @staticmethod
    def _bakes_for(scene) -> bool:
        return scene.caustic.use_bake_on_render or scene.caustic.use_live

    def _runner(self, context) -> JobRunner | None:
        scene = context.scene
        given = (self._given("frame_start"), self._given("frame_end"))
        own_range = all(frame in (None, default) for frame, default in zip(given, (scene.frame_start,
                                                                                 scene.frame_end)))
        if not own_range and not render_takes_a_range():
            self.report({'ERROR'}, f"Blender {bpy.app.version_string} renders an animation over the scene's frame "
                                   "range only: leave Start and End Frame unset, or set the scene's range")
            return None
        return super()._runner(context)

    def _render_options(self, context) -> dict:
        options = {"animation": True}
        for name in ("frame_start", "frame_end"):
            if self._given(name) is not None and render_takes_a_range():
                options[name] = self._given(name)
        return options
