"""CAUSTIC_OT_render_animation: the frame range with caustics, each frame
to its own file by Blender's output-path rules, in the scene's format
(writeback.output). Esc stops after the frame being rendered and keeps the
frames written; a second Esc stops that frame too. A frame whose
geometry, lamps and settings of the lamp pass are those of the frame
before reuses its maps (jobs.MAP_CACHE keeps the last scene's). The scene's current frame is put back."""

import time

import bpy

from ..export import InputError, read_scene, render_settings
from ..jobs import JobRunner, RenderJob, StepError, refusal
from ..writeback.images import show_image, write_image
from ..writeback.output import OutputError, check_writable, frame_paths, frame_range, save_frame
from ..writeback.results import RESULT_IMAGE, write_result
from .engine_run import EngineOperator
from .frame_range import FrameRange, frames_text, print_saved


class CAUSTIC_OT_render_animation(FrameRange, EngineOperator, bpy.types.Operator):
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
        self._begin(scene)
        self._reused = 0
        return JobRunner(frames, lambda frame: self._prepare(frame, settings), self._write)

    def _prepare(self, frame: int, settings) -> RenderJob:
        read = self._read_frame(frame, read_scene)
        self._warn(read.warnings)
        too_large = refusal(read.scene, settings)
        if too_large is not None:
            raise StepError(f"Frame {frame}: {too_large}")
        return RenderJob(read.scene, settings)

    def _write(self, frame: int, job: RenderJob) -> None:
        context = bpy.context
        # the frame for the format's writer; the last frame's image and passes are kept once the run ends
        image = write_image(RESULT_IMAGE, job.result.image, pack=False)
        saving = time.perf_counter()
        try:
            save_frame(context.scene, context.view_layer.name, image, job.result, self._paths[frame])
        except OutputError as exc:
            raise StepError(f"Frame {frame} {exc}") from exc
        if bpy.app.background:
            print_saved(self._paths[frame], job.seconds, time.perf_counter() - saving)
        self._warn(job.result.warnings)
        self._reused += bool(job.result.stats["maps_cached"])
        self._seconds += job.seconds
        job.drop_maps()

    def _status(self, runner: JobRunner) -> str:
        return (f"Caustics: frame {runner.step} ({len(runner.done) + 1} of {len(runner.steps)}), {runner.stage} "
                f"(Esc stops after this frame)")

    def _done(self, context, runner: JobRunner) -> set:
        if runner.last is not None:
            show_image(context, write_result(context.window_manager.caustic, runner.last))
        done = runner.done
        written = f"{len(done)} of {len(runner.steps)} frames written" + (
            f" ({frames_text(done)}, the last to '{self._paths[done[-1]]}')" if done else "")
        if self._finish(context, runner, written, "Caustic animation stopped"):
            reused = f", maps reused on {self._reused}" if self._reused else ""
            self.report({'INFO'}, f"Rendered {frames_text(done)} with caustics in {self._seconds:.1f} s{reused}: "
                                  f"'{self._paths[done[0]]}' to '{self._paths[done[-1]]}'")
        # Frames written are kept: the image showing the last is an undo step of its own.
        return {'FINISHED'} if done else {'CANCELLED'}
