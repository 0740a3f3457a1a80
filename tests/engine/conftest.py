"""Shared setup for the engine tests."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

# The benchmarks' scenes and references are imported as packages of the
# repository root (pytest.ini's pythonpath): `from benchmarks.scenes import
# ball_lens`, `from benchmarks.references import reference`. This folder's
# own helpers (scenes.py) are imported by name.
HERE = str(Path(__file__).resolve().parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)


def pytest_collection_modifyitems(items):
    """A test that compiles every kernel afresh runs first: it seeds the
    engine's cache with what it compiled, so the tests after it, and the
    command lines they start, load their kernels instead of compiling them
    again."""
    items.sort(key=lambda item: item.get_closest_marker("compiles_every_kernel") is None)


@pytest.fixture
def small_disk(tmp_path):
    """mount(size in bytes): a folder on a file system of its own (tmpfs) of
    that size, to fill up; skipped where mounting is not allowed."""
    folder = tmp_path / "disk"
    folder.mkdir()
    mounted = []

    def mount(size):
        kib = -(-size // 4096) * 4
        if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={kib}k", "tmpfs", str(folder)],
                          capture_output=True).returncode != 0:
            pytest.skip("mounting a small tmpfs needs root")
        mounted.append(folder)
        return folder

    yield mount
    for path in mounted:
        subprocess.run(["umount", str(path)], check=True)


@pytest.fixture
def fill_disk():
    """fill(folder, leave): a file "filler" in `folder` that leaves `leave` bytes free on its file system."""

    def fill(folder, leave: int) -> None:
        free = shutil.disk_usage(folder).free
        with open(folder / "filler", "wb") as out:
            out.write(b"\0" * max(0, free - leave))

    return fill
