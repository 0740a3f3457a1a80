"""A grid of glass ico-spheres (80 triangles each) that Geometry Nodes
instance over a floor, 1,000 to 1,000,000 of them, under a point lamp,
rendered with Render Caustics at 320x240 and the scene's defaults, each
count in a process of its own.

    .venv/bin/python benchmarks/instances.py [--counts 1000 10000 100000 1000000]

Recorded per count: the render's seconds as the operator takes them (the
scene read, the engine, the image written), the scene read's share, the
engine's own time, the triangles, and the process's peak resident memory
over what it held before the render. Writes benchmarks/results/instances.json.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks import record  # noqa: E402

GRID_M = 3.0  # the grid's side; each sphere's radius is 0.4 of its spacing
SUBDIVISIONS = 2  # Blender's default ico-sphere: 80 triangles


def measure(count: int) -> dict:
    """One count's figures, in this process (a child of main)."""
    import math
    import resource

    sys.path.insert(0, str(REPO / "tests" / "addon"))
    import bpy

    import blender_scenes as scenes
    import conftest

    addon = conftest.registered_addon()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    side = math.ceil(math.sqrt(count))
    spacing = GRID_M / (side - 1)
    scenes.add_plane(6.0, scenes.diffuse_material())
    holder = scenes.scatter(side, spacing, size=0.4 * spacing)
    holder.modifiers[0].node_group.nodes['Ico Sphere'].inputs['Subdivisions'].default_value = SUBDIVISIONS
    holder.location.z = 0.5
    scenes.add_point_light((0.0, 0.0, 3.0), 1000.0)
    scenes.add_camera((0.0, -4.5, 3.5), target=(0.0, 0.3, 0.0))
    scenes.set_resolution(320, 240)
    start = time.perf_counter()
    read = addon.export.read_scene(bpy.context)
    read_s = time.perf_counter() - start
    triangles = sum(o.mesh.triangle_count for o in read.scene.objects if o.is_caster)
    del read
    before_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    render_s = time.perf_counter() - start
    peak_mb = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before_kb) / 1024
    addon.unregister()
    return {"instances": side * side, "triangles": triangles, "render_s": render_s, "read_s": read_s,
            "peak_growth_mb": peak_mb}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[1_000, 10_000, 100_000, 1_000_000])
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print("FIGURES", json.dumps(measure(args.child)))
        return
    runs = {}
    for count in args.counts:
        out = subprocess.run([sys.executable, __file__, "--child", str(count)], capture_output=True, text=True,
                             check=True).stdout
        figures = json.loads(next(line for line in out.splitlines() if line.startswith("FIGURES"))[8:])
        figures["engine_s"] = float(re.search(r"Caustics rendered in ([0-9.]+) s", out).group(1))  # its report
        runs[f"{figures['instances']:,}"] = figures
        print(count, figures, flush=True)
    record.write("instances", {"resolution": [320, 240], "subdivisions": SUBDIVISIONS, "runs": runs})


if __name__ == "__main__":
    main()
