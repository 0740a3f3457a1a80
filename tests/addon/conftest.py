"""The add-on under the real bpy: registered once from the source tree, as
Blender imports an installed extension (packaging/source_tree.py), with
Blender's user folders apart from the user's own, and a factory fresh empty
file for every test."""

import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
HERE = str(Path(__file__).resolve().parent)
for folder in (HERE, str(REPO / "packaging")):
    if folder not in sys.path:
        sys.path.insert(0, folder)

# load_addon(): the add-on from the source tree, as Blender imports it installed
from source_tree import blender_user_folders, import_addon as load_addon  # noqa: E402

blender_user_folders()

import bpy  # noqa: E402
import pytest  # noqa: E402


def registered_addon():
    """The add-on, registered, its kernels compiled or loaded: the warming
    thread's compiles change the warnings filters, which
    warnings.catch_warnings (snapshot.py) does not guard across threads,
    and timings must not count them."""
    module = load_addon()
    module.register()
    module.jobs.kernels.wait()
    return module


@pytest.fixture(scope="session")
def addon():
    module = registered_addon()
    yield module
    # Blender 4.2's bpy module crashes at exit if an operator is still registered.
    module.unregister()


@pytest.fixture(autouse=True)
def factory(addon):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield


@pytest.fixture
def coarse_world_bakes(addon, monkeypatch):
    """World bakes of 512 x 256 pixels, a sixteenth of the add-on's, for
    the tests that look at where a bake's light is, not at a sun a pixel
    wide; no bake is kept across them."""
    bake = addon.export.world_bake
    monkeypatch.setattr(bake, "BAKE_WIDTH", 512)
    bake._bakes.clear()
    yield
    bake._bakes.clear()


class Reports:
    """What the operators reported since the last call (Blender prints
    'Warning: ...' and 'Info: ...' lines to stdout in the background)."""

    def __init__(self, capfd):
        self.capfd, self.last = capfd, ""

    def __call__(self) -> str:
        out, err = self.capfd.readouterr()
        self.last = out + err
        return self.last


@pytest.fixture
def reports(capfd):
    return Reports(capfd)


@pytest.fixture
def small_disk(tmp_path):
    """mount(size in bytes): a folder on a file system of its own (tmpfs) of
    that size, to fill up part-way through a run; skipped where mounting is
    not allowed."""
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
