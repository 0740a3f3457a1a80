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
