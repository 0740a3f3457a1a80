"""glibc's malloc as the engine sets it where a render starts
(caustic_addon/util/heap.py) against glibc's default, inside Blender.

Render Caustic Animation of the animated pool (animation.py's scene,
1280 x 720, the add-on's defaults), each setting in a fresh Blender process,
twice, in turn. Seconds and CPU seconds a frame, page faults, kernel CPU
seconds and peak memory of the whole run.

    .venv/bin/python benchmarks/allocator.py [--frames 6] [--runs 2]
    .venv-4.2/bin/python benchmarks/allocator.py

Writes benchmarks/results/allocator.json, each Blender's figures beside the others'.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the repository root

from benchmarks import record  # noqa: E402

# A tunable that changes nothing: with it set, the engine leaves malloc alone (heap.tuned_by_environment).
DEFAULT_MALLOC = {"GLIBC_TUNABLES": "glibc.malloc.perturb=0"}


def one_run(frames: int) -> dict:
    """In this process: the pool's animation, and what the process spent on it."""
    import tempfile

    import bpy

    from benchmarks import animation

    animation.register_addon()
    animation.pool(Path(tempfile.mkdtemp()))
    before = resource.getrusage(resource.RUSAGE_SELF)
    run = animation.caustic_animation(frames)
    after = resource.getrusage(resource.RUSAGE_SELF)
    return dict(blender=bpy.app.version_string, seconds_per_frame=statistics.mean(run["seconds_per_frame"]),
                cpu_seconds_per_frame=statistics.mean(run["cpu_seconds_per_frame"]),
                page_faults=after.ru_minflt - before.ru_minflt, kernel_cpu_seconds=after.ru_stime - before.ru_stime,
                peak_resident_mb=after.ru_maxrss / 1024)


def measure(setting: str, frames: int) -> dict:
    env = dict(os.environ)
    env.pop("GLIBC_TUNABLES", None)
    if setting == "default":
        env.update(DEFAULT_MALLOC)
    done = subprocess.run([sys.executable, __file__, "--one", str(frames)], env=env, cwd=HERE,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_run(args.one)), flush=True)
        os._exit(0)  # past bpy's teardown, which Blender 4.2's module may crash in at exit
    runs = {"default": [], "engine": []}
    for _ in range(args.runs):
        for setting in runs:
            runs[setting].append(measure(setting, args.frames))
            print(setting, runs[setting][-1], flush=True)
    blender = runs["engine"][0]["blender"]
    figures = {setting: {key: statistics.mean(r[key] for r in rs) for key in rs[0] if key != "blender"}
               for setting, rs in runs.items()}
    blenders = record.read("allocator").get("blenders", {})
    blenders[blender] = figures
    record.write("allocator", dict(scene="animated pool, 1280x720, the add-on's defaults (animation.py)",
                                   frames=args.frames, runs=args.runs, blenders=blenders))


if __name__ == "__main__":
    main()
