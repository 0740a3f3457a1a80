"""Batch rendering: what `blender -b scene.blend --python-expr
"import bpy; bpy.ops.caustic.render()"` does, with the bpy module: open a
saved file, render with the settings saved in it, write the image out. Also
the paper's scene script, run as Blender would run it."""

import importlib.util
import json
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
    assert props.last_lamp_rays == 30_000
    rendered = np.array(bpy.data.images["Caustic Render"].pixels[:], dtype=np.float32)
    assert rendered.max() > 1.0

    # The documented batch line: the output format comes from the scene's output settings.
    bpy.context.scene.render.image_settings.file_format = 'OPEN_EXR'
    bpy.context.scene.render.image_settings.color_depth = '32'
    assert bpy.ops.caustic.render(filepath="//render.exr") == {'FINISHED'}
    saved = bpy.data.images.load(str(tmp_path / "render.exr"))
    assert tuple(saved.size) == (48, 36)
    assert np.allclose(np.array(saved.pixels[:], dtype=np.float32), rendered, rtol=1e-5, atol=1e-6)


def test_the_demo_renders_the_paper_scene_three_ways(tmp_path):
    run = subprocess.run([sys.executable, str(REPO / "examples" / "demo.py"), "--out", str(tmp_path),
                          "--percentage", "10", "--samples", "4", "--reference-lamp-rays", "20000"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    figures = json.loads((tmp_path / "demo.json").read_text())["figures"]
    assert len(figures) == 3
    for name in ("demo_beams.exr", "demo_paper.exr", "demo_cycles.exr"):
        assert (tmp_path / name).stat().st_size > 0, name
    # the labelled picture needs matplotlib, which only the main venv has
    assert (tmp_path / "demo.png").exists() == (importlib.util.find_spec("matplotlib") is not None)
    # the default is nearer the converged render than the paper's map and than Cycles' MNEE
    assert figures["beams"]["relative_l2"] < min(figures["paper"]["relative_l2"], figures["cycles"]["relative_l2"])


def test_the_demo_fails_loudly(tmp_path):
    run = subprocess.run([sys.executable, str(REPO / "examples" / "demo.py"), "--out", str(tmp_path),
                          "--percentage", "nope"], capture_output=True, text=True, timeout=600)
    assert run.returncode != 0
    assert "--percentage" in run.stderr
