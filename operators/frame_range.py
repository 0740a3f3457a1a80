"""What the operators that run over a frame range share: the range's
options (unset, the scene's), each frame read at its own time, the scene's
current frame put back at the end, each warning reported once, and a
closing report that says how many frames were done."""

import bpy

from ..export import InputError
from ..jobs import JobRunner, StepError


def frames_text(frames: list[int]) -> str:
    return f"frame {frames[0]}" if len(frames) == 1 else f"frames {frames[0]}-{frames[-1]}"


def _clock(seconds: float) -> str:
    return f"{int(seconds // 60):02d}:{seconds % 60:05.2f}"


def print_saved(path: str, seconds: float, saving: float) -> None:
    """The lines Blender prints for a frame written in the background,
    which farm managers count frames by (Flamenco's blender-render command)."""
    print(f"Saved: '{path}'")
    print(f"Time: {_clock(seconds + saving)} (Saving: {_clock(saving)})", flush=True)


class FrameRange:
    """Mixin for an EngineOperator over frames; `_begin` when its runner is
    made, `_read_frame` in each frame's preparation, `_finish` in `_done`."""

    frame_start: bpy.props.IntProperty(name="Start Frame", options={'SKIP_SAVE'},
                                       description="First frame (default: the scene's)")
    frame_end: bpy.props.IntProperty(name="End Frame", options={'SKIP_SAVE'},
                                     description="Last frame (default: the scene's)")

    def _given(self, name: str):
        return getattr(self, name) if self.properties.is_property_set(name) else None

    def _begin(self, scene) -> None:
        self._frame_before = scene.frame_current, scene.frame_subframe
        self._warnings, self._seconds = [], 0.0

    def _read_frame(self, frame: int, read):
        """`read(context)` at `frame`; its InputError becomes the frame's StepError."""
        bpy.context.scene.frame_set(frame)
        try:
            return read(bpy.context)
        except InputError as exc:
            raise StepError(f"Frame {frame}: {exc}") from exc

    def _warn(self, warnings: list[str]) -> None:
        self._warnings += [w for w in warnings if w not in self._warnings]

    def _finish(self, context, runner: JobRunner, written: str, stopped: str) -> bool:
        """Put the frame back, report the warnings and, with `written` (what
        was done), an error or `stopped` (a cancel); True when the run went
        to its end, for the caller's own report."""
        frame, subframe = self._frame_before
        context.scene.frame_set(frame, subframe=subframe)
        for warning in self._warnings:
            self.report({'WARNING'}, warning)
        if runner.error is not None:
            self.report({'ERROR'}, f"{runner.error}; {written}")
        elif runner.cancelled:
            self.report({'WARNING'}, f"{stopped}: {written}")
        return runner.error is None and not runner.cancelled
