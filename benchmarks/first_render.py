"""The first render after a fresh install: how long the user waits for
numba's kernels, against a render with them compiled or loaded from cache.

    .venv/bin/python benchmarks/first_render.py [dist/caustics-0.1.0-linux_x64.zip]

Installs the extension zip (`make package`) into a throw-away Blender user
folder, through Blender's own extension system, three times, each in a new
process, and times a 320x240 ball-lens render with the add-on's defaults:

- fresh, render at once: the render starts while the kernels still compile
  in the background, and waits for the ones it calls;
- fresh, render once the background compile is done (what a user who sets
  up a scene first sees), then a second render;
- enabled again over the same user folder: the kernels load from its cache.

Writes benchmarks/results/first_render.json.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO))  # the repository root

from benchmarks import record  # noqa: E402

MODULE = "bl_ext.user_default.caustics"

CHILD = r"""
import json, os, sys, time
site = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                    "python{}.{}".format(*sys.version_info[:2]), "site-packages")
os.makedirs(site, exist_ok=True)
sys.path.insert(0, site)
import bpy
sys.path.insert(0, sys.argv[3])
import blender_scenes as scenes
bpy.ops.wm.read_factory_settings(use_empty=True)
start = time.perf_counter()
if sys.argv[2] != "enable":
    bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default", enable_on_install=True)
else:
    bpy.ops.preferences.addon_enable(module="%(module)s")
enabled = time.perf_counter() - start
kernels = sys.modules["%(module)s.jobs.kernels"]
scenes.ball_lens_scene(320, 240, lamp_rays=40_000)
report = {"enable_s": enabled}
if sys.argv[2] != "at_once":
    start = time.perf_counter()
    kernels.wait()
    report["background_compile_left_s"] = time.perf_counter() - start
for name in ("first_render_s", "second_render_s"):
    start = time.perf_counter()
    bpy.ops.caustic.render()
    report[name] = time.perf_counter() - start
kernels.wait()
print(json.dumps(report))
sys.stdout.flush()
bpy.ops.preferences.addon_disable(module="%(module)s")
""" % {"module": MODULE}


def run(zip_path: Path, user: Path, mode: str) -> dict:
    """One fresh process: install (or enable) the extension under `user`, then render twice."""
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user))
    child = subprocess.run([sys.executable, "-c", CHILD, str(zip_path), mode, str(REPO / "tests" / "addon")],
                           env=env, capture_output=True, text=True, timeout=1800)
    if child.returncode != 0:
        raise SystemExit(child.stdout[-2000:] + child.stderr[-2000:])
    return json.loads(next(line for line in child.stdout.splitlines()[::-1] if line.startswith("{")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("zip", nargs="?", type=Path, help="the extension (default: the newest in dist/)")
    args = parser.parse_args()
    zip_path = args.zip or sorted((REPO / "dist").glob("caustics-*-linux_x64.zip"))[-1]
    with tempfile.TemporaryDirectory() as a, tempfile.TemporaryDirectory() as b:
        report = {
            "zip": zip_path.name,
            "fresh_render_at_once": run(zip_path, Path(a), "at_once"),
            "fresh_render_after_background_compile": run(zip_path, Path(b), "install"),
            "enabled_again_from_cache": run(zip_path, Path(b), "enable"),
        }
    print(json.dumps(report, indent=2))
    record.write("first_render", report)


if __name__ == "__main__":
    main()
