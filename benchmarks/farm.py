"""The render farm's overhead per chunk: the add-on's Flamenco job type on
the test farm (tests/addon/farm.py: a Flamenco 3.8.5 Manager and Workers on
127.0.0.1, shared storage on the local disk), against one local run.

    .venv/bin/python benchmarks/farm.py [--repeats 2]

The shot: the add-on's tests' moving glass, 6 frames at 64x48 (Caustics
mode). Measured, each the fastest of `repeats`:

- one local Render Caustic Animation of the 6 frames, in a process of its
  own (`blender -b shot.blend --python-expr ...`, the bpy module), and that
  process's start alone (bpy, the add-on and the file, no render);
- the job on one Worker in chunks of 6, 2 and 1 frames: seconds from
  submission to the job's completion. The overhead per chunk is the job's
  time less the local run's, over the number of chunks: a process start,
  and Flamenco's own pace: a Worker asks for its next task 2 s after it
  finished one, and 20 s after it was told there is none (its
  state_awake.go), and sends its log and status back as it goes;
- the same job in chunks of 2 on two Workers: an idle Worker that was
  told "no task" just before the job came sleeps out its 20 s, so the
  first may have done most chunks by then.

Writes benchmarks/results/farm.json.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402

import conftest  # noqa: E402
import farm  # noqa: E402
from benchmarks import record  # noqa: E402
from test_animation import moving_glass  # noqa: E402

RENDER = "import bpy; bpy.ops.caustic.render_animation(filepath='//local/glass_####')"


def local(blend: str, expression: str) -> None:
    subprocess.run([sys.executable, str(farm.HERE / "farm_blender.py"), "-b", blend, "--python-expr", expression],
                   check=True, capture_output=True, timeout=600)


def job_seconds(the_farm: farm.Farm, blend: str, chunk_size: int) -> float:
    start = time.perf_counter()
    job = the_farm.submit(dict(mode="caustics", frames="1-6", chunk_size=chunk_size,
                               render_output_path=f"//farm_{chunk_size}/glass_####", blendfile=blend))
    status = the_farm.wait(job)
    if status != "completed":
        raise RuntimeError(f"the job {status}")
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    if farm.missing():
        sys.exit(farm.missing())
    addon = conftest.load_addon()
    addon.register()
    with tempfile.TemporaryDirectory() as folder:
        the_farm = farm.Farm(Path(folder), workers=1)
        try:
            bpy.ops.wm.read_factory_settings(use_empty=True)
            moving_glass(64, 48)
            bpy.context.scene.frame_end = 6
            blend = str(the_farm.shared / "shot.blend")
            bpy.ops.wm.save_as_mainfile(filepath=blend)
            local(blend, RENDER)  # the kernels compiled for this engine, once
            figures = {"local_run_s": record.fastest(args.repeats, lambda: local(blend, RENDER)),
                       "process_start_s": record.fastest(args.repeats, lambda: local(blend, "pass")),
                       "one_worker": {}}
            time.sleep(6)  # the Worker has signed on
            for chunk_size in (6, 2, 1):
                seconds = record.fastest(args.repeats, lambda: job_seconds(the_farm, blend, chunk_size))
                chunks = 6 // chunk_size
                figures["one_worker"][chunk_size] = {
                    "chunks": chunks, "job_s": seconds,
                    "overhead_per_chunk_s": (seconds - figures["local_run_s"]) / chunks}
            the_farm.start_worker("worker-2")
            time.sleep(6)
            figures["two_workers_chunks_of_2_s"] = record.fastest(args.repeats, lambda: job_seconds(the_farm, blend, 2))
        finally:
            the_farm.close()
            addon.unregister()
    record.write("farm", figures)
    print(f"local run of 6 frames: {figures['local_run_s']:.2f} s (a process start alone "
          f"{figures['process_start_s']:.2f} s)")
    for chunk_size, r in figures["one_worker"].items():
        print(f"one Worker, chunks of {chunk_size}: {r['job_s']:.2f} s, {r['overhead_per_chunk_s']:.2f} s a chunk "
              "over the local run")
    print(f"two Workers, chunks of 2: {figures['two_workers_chunks_of_2_s']:.2f} s")


if __name__ == "__main__":
    main()
