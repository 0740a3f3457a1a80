"""Batch rendering: what `blender -b scene.blend --python-expr
"import bpy; bpy.ops.caustic.render()"` does, with the bpy module: open a
saved file, render with the settings saved in it, write the image out. Also
the paper's scene script, run as Blender would run it."""

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np

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
