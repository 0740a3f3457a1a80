"""The worker side of the modal render: the engine on a thread of its own,
reporting progress and stopping when cancelled (as Esc does)."""

import time

import bpy
import pytest

import blender_scenes as scenes


def job_for_scene(addon, lamp_rays):
    scenes.ball_lens_scene(64, 48, lamp_rays=lamp_rays, segments=32, rings=16)
    read = addon.export.read_scene(bpy.context)
    settings = addon.export.render_settings(bpy.context.scene.caustic)
    settings.chunk_size = 1 << 14  # many chunks: progress moves, and the cancel is seen soon
    return addon.jobs.RenderJob(read.scene, settings)


def test_job_runs_on_a_thread_to_the_end(addon):
    job = job_for_scene(addon, 50_000)
    job.start()
    job.wait()
    assert job.result is not None and job.error is None and not job.cancelled
    assert job.fraction == pytest.approx(1.0) and job.stage == "eye pass"
    assert job.result.stats["lamp_rays"] == 50_000


def test_cancel_stops_the_job(addon):
    job = job_for_scene(addon, 5_000_000)
    job.start()
    deadline = time.monotonic() + 60.0
    while job.fraction == 0.0 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert 0.0 < job.fraction < 1.0
    job.cancel()
    job.wait()
    assert job.cancelled and job.result is None and job.error is None
    assert not job.running


def ticking_runner(addon, lamp_rays, steps):
    """A JobRunner over `steps`, each a job of the scene, with what it finished."""
    finished = []
    runner = addon.jobs.JobRunner(steps, lambda step: job_for_scene(addon, lamp_rays),
                                  lambda step, job: finished.append(step))
    return runner, finished


def tick_to_the_end(runner):
    deadline = time.monotonic() + 120.0
    while runner.tick() and time.monotonic() < deadline:
        time.sleep(0.01)


def test_a_stop_ends_the_run_after_the_step_running_now(addon):
    """Esc in Render Animation: the frame being rendered is finished and kept, the next is not begun."""
    runner, finished = ticking_runner(addon, 300_000, [1, 2, 3])
    assert runner.tick() and runner.job.running
    runner.stop()
    tick_to_the_end(runner)
    assert finished == runner.done == [1] and runner.cancelled and runner.error is None
    assert runner.last.result is not None


def test_a_second_stop_cancels_the_step_running_now(addon):
    runner, finished = ticking_runner(addon, 5_000_000, [1, 2, 3])
    assert runner.tick()
    runner.stop()
    runner.stop()
    tick_to_the_end(runner)
    assert finished == runner.done == [] and runner.cancelled and runner.last is None


def test_a_step_that_cannot_be_prepared_stops_the_run_with_its_message(addon):
    def prepare(step):
        if step == 2:
            raise addon.jobs.StepError("Frame 2: no camera")
        return job_for_scene(addon, 2_000)
    runner = addon.jobs.JobRunner([1, 2, 3], prepare, lambda step, job: None)
    runner.run()
    assert runner.done == [1] and runner.error == "Frame 2: no camera" and not runner.cancelled
