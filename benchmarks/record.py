"""Where every measurement keeps its figures: benchmarks/results/<name>.json,
stamped with when, where and at which commit they were measured.

    from benchmarks import record
    record.write("speed", {"photon_pass_s": 0.67, ...})
    record.fastest(3, lambda: render(scene, settings))  # seconds, the best of 3

`write` puts "date" (UTC, minutes), "machine" (CPU model, cores, OS,
Python) and "commit" (`git rev-parse --short HEAD`, "+dirty" when tracked
files differ from it) first, then the figures. benchmarks/report.py reads
the files back into benchmarks/README.md.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from datetime import datetime, timezone
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
REPO = RESULTS.parents[1]
STAMP = ("date", "machine", "commit")


def fastest(repeats: int, work) -> float:
    """The seconds of the fastest of `repeats` calls of `work()`."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return min(times)


def machine() -> str:
    """The CPU model, its cores, the OS and the Python that ran the measurement."""
    model = "unknown CPU"
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.machine()}, Python {platform.python_version()}"


def commit() -> str:
    """The checkout's short commit, "+dirty" when a tracked file differs
    from it; "unknown" outside a git checkout."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True, check=True).stdout.strip()

    try:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def stamp() -> dict:
    """{"date", "machine", "commit"} of a measurement made now."""
    return {"date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), "machine": machine(),
            "commit": commit()}


def read(name: str, folder: Path = RESULTS) -> dict:
    """The figures last written under `name`, stamp included ({} if none):
    for a measurement that adds to its last run's figures."""
    path = folder / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else {}


def write(name: str, figures: dict, folder: Path = RESULTS, indent: int = 2) -> Path:
    """Write `figures` to `folder`/<name>.json under a fresh stamp (any
    stamp they carry is replaced); returns the path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.json"
    body = {**stamp(), **{key: value for key, value in figures.items() if key not in STAMP}}
    path.write_text(json.dumps(body, indent=indent) + "\n")
    return path
