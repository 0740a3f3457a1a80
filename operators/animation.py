"""CAUSTIC_OT_render_animation: the frame range with caustics, each frame
to its own file by Blender's output-path rules, in the scene's format
(writeback.output). Esc stops after the frame being rendered and keeps the
frames written; a second Esc stops that frame too. A frame whose
geometry, lamps and settings of the lamp pass are those of an earlier one
reuses its maps (jobs.MAP_CACHE). The scene's current frame is put back."""

import bpy

from ..export import InputError, read_scene, render_settings
from ..jobs import JobRunner, RenderJob, StepError
from ..writeback.images import show_image
from ..writeback.output import OutputError, check_writable, frame_paths, frame_range, save_frame
from ..writeback.results import RESULT_IMAGE, write_result
from .engine_run import EngineOperator


def frames_text(frames: list[int]) -> str:
    return f"frame {frames[0]}" if len(frames) == 1 else f"frames {frames[0]}-{frames[-1]}"


class FrameRangeOptions:
    """Operator options for a frame range; unset, the scene's."""

    frame_start: bpy.props.IntProperty(name="Start Frame", options={'SKIP_SAVE'},
                                       description="First frame (default: the scene's)")
    frame_end: bpy.props.IntProperty(name="End Frame", options={'SKIP_SAVE'},
                                     description="Last frame (default: the scene's)")

    def _given(self, name: str):
        return getattr(self, name) if self.properties.is_property_set(name) else None


class CAUSTIC_OT_render_animation(FrameRangeOptions, EngineOperator, bpy.types.Operator):
    bl_idname = "caustic.render_animation"
    bl_label = "Render Caustic Animation"
    bl_description = ("Render the frame range with caustics, each frame to the output path (Output Properties) "
                      "in the scene's file format")
    bl_options = {'UNDO'}

    filepath: bpy.props.StringProperty(
        name="File Path", options={'SKIP_SAVE'},
        description="Where the frames go instead of the output path: // is the .blend's folder, the last # run "
                    "the frame number")
    def _runner(self, context) -> JobRunner | None:
        scene = context.scene
        try:
            frames = frame_range(scene, self._given("frame_start"), self._given("frame_end"))
            self._paths = frame_paths(scene, frames, self.filepath)
            settings = render_settings(scene.caustic)
            check_writable(self._paths.values())
        except (InputError, OutputError) as exc:
            self.report({'ERROR'}, str(exc))
            return None
        self._frame_before = scene.frame_current, scene.frame_subframe
        self._warnings, self._reused, self._seconds = [], 0, 0.0
        return JobRunner(frames, lambda frame: self._prepare(frame, settings), self._write)

    def _prepare(self, frame: int, settings) -> RenderJob:
        context = bpy.context
        context.scene.frame_set(frame)
        try:
            read = read_scene(context)
        except InputError as exc:
            raise StepError(f"Frame {frame}: {exc}") from exc
        self._warnings += [w for w in read.warnings if w not in self._warnings]
        return RenderJob(read.scene, settings)

    def _write(self, frame: int, job: RenderJob) -> None:
        context = bpy.context
        image = write_result(context.scene.caustic, job)
        try:
            save_frame(context.scene, context.view_layer.name, image, job.result, self._paths[frame])
        except OutputError as exc:
            raise StepError(f"Frame {frame} {exc}") from exc
        self._warnings += [w for w in job.result.warnings if w not in self._warnings]
        self._reused += bool(job.result.stats["maps_cached"])
        self._seconds += job.seconds

    def _status(self, runner: JobRunner) -> str:
        return (f"Caustics: frame {runner.step} ({len(runner.done) + 1} of {len(runner.steps)}), {runner.stage} "
                f"(Esc stops after this frame)")

    def _done(self, context, runner: JobRunner) -> set:
        frame, subframe = self._frame_before
        context.scene.frame_set(frame, subframe=subframe)
        for warning in self._warnings:
            self.report({'WARNING'}, warning)
        if runner.last is not None:
            show_image(context, bpy.data.images[RESULT_IMAGE])
        done = runner.done
        written = f"{len(done)} of {len(runner.steps)} frames written" + (
            f" ({frames_text(done)}, the last to '{self._paths[done[-1]]}')" if done else "")
        if runner.error is not None:
            self.report({'ERROR'}, f"{runner.error}; {written}")
        elif runner.cancelled:
            self.report({'WARNING'}, f"Caustic animation stopped: {written}")
        else:
            reused = f", maps reused on {self._reused}" if self._reused else ""
            self.report({'INFO'}, f"Rendered {frames_text(done)} with caustics in {self._seconds:.1f} s{reused}: "
                                  f"'{self._paths[done[0]]}' to '{self._paths[done[-1]]}'")
        # Frames written are kept: the image showing the last is an undo step of its own.
        return {'FINISHED'} if done else {'CANCELLED'}
