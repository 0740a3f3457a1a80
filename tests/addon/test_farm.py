"""The add-on's Flamenco job type (examples/flamenco/caustics.js) on a real
farm: a Flamenco 3.8.5 Manager and two Workers on 127.0.0.1 (farm.py),
whose `blender` runs the bpy module of the Blender under test
(farm_blender.py). Jobs go in through the Manager's REST API."""

import os
import re
import signal
import subprocess
import sys
import time

import bpy
import pytest

import farm
from test_animation import moving_glass

pytestmark = pytest.mark.skipif(farm.missing() is not None, reason=farm.missing() or "")

FRAMES = [f"glass_{f:04d}.exr" for f in range(1, 7)]


@pytest.fixture(scope="module")
def the_farm(tmp_path_factory):
    running = farm.Farm(tmp_path_factory.mktemp("farm"))
    yield running
    running.close()


def shot(the_farm, name: str, cycles: bool = False) -> str:
    """The moving glass over frames 1-6, saved to the farm's shared storage
    as `name`.blend; frames to //<name>/glass_####.exr."""
    moving_glass(16, 12)
    scene = bpy.context.scene
    scene.frame_end = 6
    scene.render.filepath = f"//{name}/glass_####"
    ball = bpy.data.objects["Ball"]
    ball.animation_data_clear()
    for frame, x in ((1, -0.3), (6, 0.3)):
        ball.location.x = x
        ball.keyframe_insert("location", frame=frame)
    if cycles:
        scene.render.engine = 'CYCLES'
        scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = 'CPU', 1, False
    path = the_farm.shared / f"{name}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return str(path)


def blender(*args: str) -> str:
    """Run the farm's `blender` here, as one local run."""
    run = subprocess.run([sys.executable, str(farm.HERE / "farm_blender.py"), "-b", *args], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    return run.stdout


def files(folder) -> dict[str, bytes]:
    """The files a user sees in `folder` (not the hidden ones a write in progress keeps)."""
    return {name: (folder / name).read_bytes() for name in sorted(os.listdir(folder)) if not name.startswith(".")}


def logs(the_farm, job_id: str) -> dict[str, str]:
    return {task["name"]: the_farm.task_log(task["id"]) for task in the_farm.tasks(job_id)}


def test_six_frames_in_chunks_of_two_on_two_workers_equal_one_local_render(the_farm):
    blend = shot(the_farm, "caustics")
    blender(blend, "--python-expr", "import bpy; bpy.ops.caustic.render_animation(filepath='//local/glass_####')")
    local = files(the_farm.shared / "local")
    assert list(local) == FRAMES

    job = the_farm.submit(dict(mode="caustics", frames="1-6", chunk_size=2, render_output_path="//caustics/glass_####",
                               blendfile=blend))
    assert the_farm.wait(job) == "completed", logs(the_farm, job)
    assert files(the_farm.shared / "caustics") == local
    tasks = [the_farm.get(f"/api/v3/tasks/{task['id']}") for task in the_farm.tasks(job)]
    assert sorted(task["name"] for task in tasks) == ["caustics-1-2", "caustics-3-4", "caustics-5-6"]
    assert {task["worker"]["name"] for task in tasks} == {"worker-1", "worker-2"}
    # each frame counts as a step of its task, from the lines Blender prints
    for task in tasks:
        assert task["steps_completed"] == task["steps_total"] == 2
        log = the_farm.task_log(task["id"])
        assert len(re.findall(r"> Saved: '.*glass_\d{4}\.exr'$", log, re.M)) == 2, log[-2000:]


def test_a_bake_job_of_scattered_frames_bakes_then_renders_only_those(the_farm):
    blend = shot(the_farm, "baked", cycles=True)
    job = the_farm.submit(dict(mode="bake", frames="1,3,5-6", chunk_size=2, render_output_path="//baked/glass_####",
                               bake_folder="//baked_maps/", blendfile=blend))
    assert the_farm.wait(job) == "completed", logs(the_farm, job)
    wanted = [f"glass_{f:04d}.exr" for f in (1, 3, 5, 6)]
    assert list(files(the_farm.shared / "baked")) == wanted
    assert list(files(the_farm.shared / "baked_maps")) == [f"Floor_{f:04d}.exr" for f in (1, 3, 5, 6)]
    task_logs = logs(the_farm, job)
    assert sorted(task_logs) == ["bake-1,3", "bake-5-6"]
    for name, log in task_logs.items():
        baked = [m.end() for m in re.finditer(r"Baked the caustics of ", log)]
        rendered = [m.start() for m in re.finditer(r"> Saved: '.*glass_\d{4}\.exr'$", log, re.M)]
        assert baked and len(rendered) == 2 and max(baked) < min(rendered), (name, log[-3000:])


def test_a_failing_task_puts_its_error_in_the_task_log_and_fails_the_job(the_farm):
    blend = shot(the_farm, "failing")
    # the output folder would be the .blend file
    job = the_farm.submit(dict(mode="caustics", frames="1-2", chunk_size=2,
                               render_output_path="//failing.blend/glass_####", blendfile=blend))
    assert the_farm.wait(job) == "failed"
    (log,) = logs(the_farm, job).values()
    assert f"Cannot write the frames into the folder '{blend}'" in log and "RuntimeError" in log, log[-3000:]


def test_a_worker_stopped_mid_chunk_leaves_no_half_frame_and_the_task_completes_elsewhere(the_farm):
    blend = shot(the_farm, "stopped")
    blender(blend, "--python-expr",
            "import bpy; bpy.ops.caustic.render_animation(filepath='//stopped_local/glass_####')")
    the_farm.stop("worker-2")
    try:
        job = the_farm.submit(dict(mode="caustics", frames="1-6", chunk_size=6,
                                   render_output_path="//stopped/glass_####", blendfile=blend))
        frames = the_farm.shared / "stopped"
        deadline = time.monotonic() + 120
        while not (frames.is_dir() and files(frames)):
            assert time.monotonic() < deadline, the_farm.log("worker-1")[-3000:]
            time.sleep(0.05)
        the_farm.stop("worker-1")
        assert len(files(frames)) < 6
    finally:
        the_farm.start_worker("worker-1")
        the_farm.start_worker("worker-2")
    assert the_farm.wait(job) == "completed", logs(the_farm, job)
    assert files(frames) == files(the_farm.shared / "stopped_local")


def test_paths_reach_each_platform_s_workers_through_the_two_way_variables(the_farm):
    """The Manager maps a path that starts with shared storage to each
    Worker's mount of it (a two-way variable, here S:\\farm on Windows), and
    rewrites the separators of any argument that holds one; the paths are
    whole arguments, so the Python expression reaches Windows unchanged."""
    blend = shot(the_farm, "twoway")
    output = the_farm.shared / "twoway" / "glass_####"
    the_farm.stop("worker-1")
    the_farm.stop("worker-2")
    try:
        job = the_farm.submit(dict(mode="caustics", frames="1-2", chunk_size=2, render_output_path=str(output),
                                   blendfile=blend))
        windows = the_farm.task_for("windows")
    finally:
        the_farm.start_worker("worker-1")
        the_farm.start_worker("worker-2")
    (command,) = windows["commands"]
    assert command["parameters"]["blendfile"] == farm.WINDOWS_STORAGE + "\\twoway.blend"
    args = command["parameters"]["args"]
    assert args[args.index("--") + 1:] == [farm.WINDOWS_STORAGE + "\\twoway\\glass_####", "1-2"]
    (stored,) = [the_farm.get(f"/api/v3/tasks/{task['id']}") for task in the_farm.tasks(job)]
    assert args[:args.index("--")] == stored["commands"][0]["parameters"]["args"][:args.index("--")]
    assert the_farm.wait(job) == "completed", logs(the_farm, job)
    assert list(files(output.parent)) == ["glass_0001.exr", "glass_0002.exr"]


@pytest.mark.parametrize("settings, message", [
    (dict(mode="render"), 'Unknown mode "render": use "bake" or "caustics"'),
    (dict(frames=""), 'The job has no "frames" setting'),
    (dict(chunk_size=0), "chunk_size must be a whole number of frames, 1 or more (got 0)"),
])
def test_the_manager_refuses_a_job_that_makes_no_sense_by_its_setting(the_farm, settings, message):
    job = {**dict(mode="caustics", frames="1-6", chunk_size=2, render_output_path="//x/glass_####",
                  blendfile=str(the_farm.shared / "x.blend")), **settings}
    status, answer = the_farm.check(job)
    assert status == 400 and message in answer["message"]


def test_missing_chunk_size_and_mode_take_the_job_type_s_defaults(the_farm):
    status, answer = the_farm.check(dict(frames="1-6", render_output_path="//x/glass_####",
                                         blendfile=str(the_farm.shared / "x.blend")))
    assert status == 204, answer


def test_the_farm_s_blender_refuses_what_it_does_not_understand():
    run = subprocess.run([sys.executable, str(farm.HERE / "farm_blender.py"), "-b", "shot.blend", "--engine", "CYCLES"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 1 and "unknown argument '--engine'" in run.stderr
