"""Batch rendering: what `blender -b scene.blend --python-expr
"import bpy; bpy.ops.caustic.render()"` does, with the bpy module: open a
saved file, render with the settings saved in it, write the image out. Also
the paper's scene script, run as Blender would run it."""

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

REPO = Path(__file__).resolve().parents[2]


def test_saved_file_renders_in_the_background(tmp_path):
    scenes.ball_lens_scene(48, 36, lamp_rays=30_000, segments=32, rings=16)
    bpy.context.scene.caustic.spp = 2
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    bpy.ops.wm.read_factory_settings(use_empty=True)

    bpy.ops.wm.open_mainfile(filepath=str(blend))
    props = bpy.context.scene.caustic
    assert (props.lamp_rays, props.spp) == (30_000, 2)
    # A button press invokes the operator; in the background that is the synchronous path.
    assert bpy.ops.caustic.render('INVOKE_DEFAULT') == {'FINISHED'}
    assert bpy.context.window_manager.caustic.last_lamp_rays == 30_000
    rendered = np.array(bpy.data.images["Caustic Render"].pixels[:], dtype=np.float32)
    assert rendered.max() > 1.0

    # The documented batch line: the output format comes from the scene's output settings.
    bpy.context.scene.render.image_settings.file_format = 'OPEN_EXR'
    bpy.context.scene.render.image_settings.color_depth = '32'
    assert bpy.ops.caustic.render(filepath="//render.exr") == {'FINISHED'}
    saved = bpy.data.images.load(str(tmp_path / "render.exr"))
    assert tuple(saved.size) == (48, 36)
    assert np.allclose(np.array(saved.pixels[:], dtype=np.float32), rendered, rtol=1e-5, atol=1e-6)


def test_the_demo_renders_ours_cycles_and_the_paper_after_the_compile(tmp_path):
    """make demo: the kernels' one-time compile is reported on its own line
    before any render is timed; then the artist's scene by the add-on and by
    Cycles, and the paper's scene, each written linear, with their times."""
    run = subprocess.run([sys.executable, str(REPO / "examples" / "demo.py"), "--out", str(tmp_path),
                          "--percentage", "10"], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    lines = run.stdout.splitlines()
    compiled = next(i for i, line in enumerate(lines) if line.startswith("compiling the engine's"))
    rendered = next(i for i, line in enumerate(lines) if "Caustics rendered in" in line)
    assert compiled < rendered
    summary = json.loads((tmp_path / "demo.json").read_text())
    assert list(summary["panels"]) == ["caustics", "cycles", "paper"]
    assert summary["cycles_samples"] > 0
    for name in summary["panels"]:
        saved = bpy.data.images.load(str(tmp_path / f"demo_{name}.exr"))
        pixels = np.array(saved.pixels[:]).reshape(saved.size[1], saved.size[0], 4)
        assert np.isfinite(pixels).all() and pixels[..., :3].max() > 0.0, name
    # the labelled picture needs matplotlib, which only the main venv has
    assert (tmp_path / "demo.png").exists() == (importlib.util.find_spec("matplotlib") is not None)


def test_the_demo_fails_loudly(tmp_path):
    run = subprocess.run([sys.executable, str(REPO / "examples" / "demo.py"), "--out", str(tmp_path),
                          "--percentage", "nope"], capture_output=True, text=True, timeout=600)
    assert run.returncode != 0
    assert "--percentage" in run.stderr


def run_blender(blend, expression, cpus=None):
    """What `blender -b blend --python-expr expression` does, with the bpy module
    in a process of its own and the add-on registered from the source tree;
    on a machine of `cpus` cores, where given (PYTHON_CPU_COUNT, which
    Python 3.13 reads: Blender 5.x)."""
    # Blender 4.2's bpy module crashes at exit while an operator is registered: unregister at the end.
    script = (f"import sys; sys.path.insert(0, {str(REPO / 'tests' / 'addon')!r}); import bpy, conftest; "
              f"addon = conftest.load_addon(); addon.register(); bpy.ops.wm.open_mainfile(filepath={str(blend)!r}); "
              + expression + "; addon.unregister()")
    env = None if cpus is None else {**os.environ, "PYTHON_CPU_COUNT": str(cpus)}
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]


def test_chunks_of_a_frame_range_give_the_files_of_one_run(tmp_path):
    """A farm's chunks, each its own process on a node of its own: frames 1-2
    on 1 core and 3-4 on 3 equal one run of 1-4, file by file."""
    from test_animation import moving_glass
    moving_glass(32, 24)
    bpy.context.scene.frame_end = 4
    bpy.context.scene.render.filepath = "//frames/glass_####"
    blend = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    run_blender(blend, "bpy.ops.caustic.render_animation()")
    whole = {name: (tmp_path / "frames" / name).read_bytes() for name in sorted(os.listdir(tmp_path / "frames"))}
    assert list(whole) == [f"glass_{f:04d}.exr" for f in (1, 2, 3, 4)]
    for start, end, cpus in ((1, 2, 1), (3, 4, 3)):
        run_blender(blend, f"bpy.ops.caustic.render_animation(filepath='//chunks/glass_####', frame_start={start}, "
                           f"frame_end={end})", cpus)
    chunks = {name: (tmp_path / "chunks" / name).read_bytes() for name in sorted(os.listdir(tmp_path / "chunks"))}
    assert chunks == whole


# Flamenco's job compiler API, as far as the job type uses it (flamenco.blender.org, "Job Types").
FLAMENCO_HARNESS = r"""
function frameChunker(frames, size) {
    const [first, last] = frames.split("-").map(Number);
    const chunks = [];
    for (let start = first; start <= last; start += size) {
        const end = Math.min(start + size - 1, last);
        chunks.push(start == end ? `${start}` : `${start}-${end}`);
    }
    return chunks;
}
const author = {
    Task: (name, type) => ({ name, type, commands: [], addCommand(command) { this.commands.push(command); } }),
    Command: (type, parameters) => ({ type, parameters }),
};
const job = { settings: JSON.parse(process.argv[1]), tasks: [], addTask(task) { this.tasks.push(task); } };
compileJob(job);
console.log(JSON.stringify({ label: JOB_TYPE.label, tasks: job.tasks }));
"""


def flamenco_tasks(settings):
    """The tasks Flamenco compiles from examples/flamenco/caustics.js for a job of `settings`."""
    job_type = (REPO / "examples" / "flamenco" / "caustics.js").read_text()
    run = subprocess.run(["node", "-e", job_type + FLAMENCO_HARNESS, json.dumps(settings)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)["tasks"]


@pytest.mark.skipif(shutil.which("node") is None, reason="needs Node.js to run the Flamenco job type")
def test_the_flamenco_job_type_makes_a_task_per_chunk_that_renders_it(tmp_path):
    from test_animation import moving_glass
    settings = dict(mode="caustics", frames="1-3", chunk_size=2, render_output_path="//frames/it's_####",
                    bake_folder="//caustic_bake/", blendfile="/farm/shot.blend")
    tasks = flamenco_tasks(settings)
    assert [task["name"] for task in tasks] == ["caustics-1-2", "caustics-3"]
    for task in tasks:
        (command,) = task["commands"]
        assert command["type"] == "blender-render" and command["parameters"]["blendfile"] == "/farm/shot.blend"
    moving_glass(16, 12)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    for task in tasks:
        flag, expression = task["commands"][0]["parameters"]["args"]
        assert flag == "--python-expr"
        exec(expression, {})
    assert sorted(os.listdir(tmp_path / "frames")) == [f"it's_{f:04d}.exr" for f in (1, 2, 3)]

    baking = flamenco_tasks(dict(settings, mode="bake"))
    args = baking[1]["commands"][0]["parameters"]["args"]
    assert args[2:] == ["--render-output", "//frames/it's_####", "--frame-start", "3", "--frame-end", "3",
                        "--render-anim"]
    exec(args[1], {})
    assert sorted(os.listdir(tmp_path / "caustic_bake")) == ["Floor_0003.exr"]
