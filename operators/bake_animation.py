"""CAUSTIC_OT_bake_animation: one illumination map per frame and receiver,
written as a float EXR sequence (`<folder>/<receiver>_<frame>.exr`, beside
the .blend by default) and shown by the receiver's material through the
bake's node group, its Image Texture an image sequence that follows the
frame: EEVEE and Cycles animation renders then show the moving caustic.
Glass, mirrors and lamps may move; the receivers must keep still, since one
chart maps every frame's image onto them. Unbake removes what it added and
names the files it leaves."""

import os

import bpy

from ..export import InputError, bake_settings, read_for_bake
from ..jobs import JobRunner, RenderJob, StepError, map_rgba
from ..writeback.bake_group import follow_frames
from ..writeback.images import working_colorspace
from ..writeback.output import OutputError, check_saved, check_writable, frame_range, write_float_exr
from ..writeback.results import record_run
from ..writeback.bake import IMAGE_PREFIX, bakeable, wire_bakes
from .engine_run import EngineOperator
from .frame_range import FrameRange, frames_text

DEFAULT_FOLDER = "//caustic_bake/"


def same_chart(a, b) -> bool:
    """Whether two maps lay their images on the receiver alike (chart, frame and size)."""
    fa, fb = a.image_frame(), b.image_frame()
    return a.shape == b.shape and fa.coordinates == fb.coordinates and all(
        (getattr(fa, k) == getattr(fb, k)).all() for k in ("location", "rotation", "scale"))


class BakeFrames(FrameRange, EngineOperator):
    """What Bake Caustic Animation does, for the operators that bake a frame range."""

    directory: bpy.props.StringProperty(
        name="Folder", default=DEFAULT_FOLDER, options={'SKIP_SAVE'},
        description="Where the baked frames go (// is the .blend's folder)")

    def _runner(self, context) -> JobRunner | None:
        scene = context.scene
        try:
            frames = frame_range(scene, self._given("frame_start"), self._given("frame_end"), step=1)
            check_saved(self.directory)
            self._folder = bpy.path.abspath(self.directory)
            self._digits = max(4, len(str(frames[-1])))
            settings = bake_settings(scene.caustic)
            check_writable([os.path.join(self._folder, "frame")])
        except (InputError, OutputError) as exc:
            self.report({'ERROR'}, str(exc))
            return None
        self._begin(scene)
        self._first = self._plan = None
        return JobRunner(frames, lambda frame: self._prepare(frame, settings), self._write)

    def _path(self, name: str, frame: int) -> str:
        return os.path.join(self._folder, f"{bpy.path.clean_name(name)}_{frame:0{self._digits}d}.exr")

    def _prepare(self, frame: int, settings) -> RenderJob:
        self._read = self._read_frame(frame, read_for_bake)
        return RenderJob(self._read.scene, settings)

    def _write(self, frame: int, job: RenderJob) -> None:
        maps = job.result.maps
        if self._plan is None:
            self._plan, warnings = bakeable(self._read, maps)
            if not self._plan:
                raise StepError("No receiver's material can take a baked caustic: " + "; ".join(warnings))
            self._first = frame, self._read, {name: maps[name] for name in self._plan}
            self._warn(warnings)
        first_frame, _, first_maps = self._first
        for name in self._plan:
            if name not in maps or not same_chart(maps[name], first_maps[name]):
                raise StepError(f"Frame {frame}: receiver '{name}' moved or changed shape since frame "
                                f"{first_frame}; an animated bake needs receivers that keep still (glass, "
                                "mirrors and lamps may move)")
        for name in self._plan:
            try:
                write_float_exr(self._path(name, frame), map_rgba(maps[name]))
            except OutputError as exc:
                raise StepError(f"Frame {frame}: the map of '{name}' {exc}") from exc
        self._warn(self._read.warnings + job.result.warnings)
        self._seconds += job.seconds
        record_run(bpy.context.window_manager.caustic, job)
        job.drop_maps()

    def _wire(self, frames: list[int]) -> None:
        """Each receiver's material shows its sequence from the first frame baked for len(`frames`) frames."""
        _, read, maps = self._first
        for group in wire_bakes(read, self._plan, maps, lambda name: self._sequence(name, frames[0])).values():
            follow_frames(group, frames[0], len(frames))

    def _sequence(self, name: str, first: int):
        """The image sequence of receiver `name`'s baked frames, from frame `first`."""
        image = bpy.data.images.load(self._path(name, first), check_existing=False)
        image.name = IMAGE_PREFIX + name
        image.source = 'SEQUENCE'
        if self.directory.startswith("//"):
            image.filepath = bpy.path.relpath(image.filepath)
        image.colorspace_settings.name = working_colorspace()
        return image

    def _status(self, runner: JobRunner) -> str:
        return (f"Baking caustics: frame {runner.step} ({len(runner.done) + 1} of {len(runner.steps)}), "
                f"{runner.stage} (Esc stops after this frame)")

    def _done(self, context, runner: JobRunner) -> set:
        done = runner.done
        if done:
            self._wire(done)
        written = f"{len(done)} of {len(runner.steps)} frames baked" + (
            f" ({frames_text(done)}) into '{self._folder}'" if done else "")
        if self._finish(context, runner, written, "Caustic bake stopped"):
            self.report({'INFO'}, f"Baked the caustics of {frames_text(done)} onto {', '.join(self._plan)} in "
                                  f"{self._seconds:.1f} s, into '{self._folder}'")
        return {'FINISHED'} if done else {'CANCELLED'}


class CAUSTIC_OT_bake_animation(BakeFrames, bpy.types.Operator):
    bl_idname = "caustic.bake_animation"
    bl_label = "Bake Caustic Animation"
    bl_description = "Bake every frame's caustics into an image sequence beside the .blend, which the materials follow"
    bl_options = {'UNDO'}
