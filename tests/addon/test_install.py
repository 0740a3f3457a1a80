"""The extension as users get it: `make package` builds the zips, each with
its platform's wheels and, for this platform, its compiled kernels, and
Blender's extension system installs one into a throw-away user folder,
where the engine runs on the zip's embreex and numba and compiles nothing."""

import fnmatch
import json
import os
import subprocess
import sys
import zipfile
from importlib.metadata import version
from pathlib import Path

import pytest
from test_manifest import MANIFEST, platform_of

from caustic_addon.tracing.embree import LIBRARY_PLACES

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
PYTHON_TAG = "cp{}{}".format(*sys.version_info[:2])


def wheel_files(platform: str) -> set[str]:
    """The file name of each wheel the manifest lists for a platform."""
    names = (Path(wheel).name for wheel in MANIFEST["wheels"])
    return {name for name in names if platform_of(name.removesuffix(".whl").split("-")[4].split(".")[0]) == platform}


@pytest.fixture(scope="module")
def zips() -> dict[str, Path]:
    """`make package`'s zip for each platform."""
    subprocess.run(["make", "-C", str(REPO), "package"], check=True, capture_output=True)
    return {platform: REPO / "dist" / f"caustics-{MANIFEST['version']}-{platform.replace('-', '_')}.zip"
            for platform in MANIFEST["platforms"]}


def test_each_zip_carries_the_wheels_of_its_platform_and_no_other(zips):
    for platform, path in zips.items():
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
        assert {Path(name).name for name in names if name.endswith(".whl")} == wheel_files(platform), platform
        # compiled kernels for this machine's platform only, for both Pythons
        kernels = {name.split(".")[-2] for name in names if name.startswith("kernels/") and name.endswith(".nbi")}
        assert kernels == ({"py311", "py313"} if platform == "linux-x64" else set()), platform


def test_each_zip_s_embreex_wheel_carries_embree_where_the_engine_loads_it_from(zips):
    """The engine casts through the libembree4 of embreex's wheel
    (tracing/embree.py): exactly one file of each platform's wheels sits
    where it looks."""
    for platform, path in zips.items():
        with zipfile.ZipFile(path) as archive:
            for name in (n for n in archive.namelist() if Path(n).name.startswith("embreex-")):
                with zipfile.ZipFile(archive.open(name)) as wheel:
                    found = [n for n in wheel.namelist() for folder, pattern in LIBRARY_PLACES
                             if fnmatch.fnmatch(n, f"{folder}/{pattern}") and "/" not in n[len(folder) + 1:]]
                assert len(found) == 1, (platform, name, found)


def test_zip_installs_with_its_wheels_and_renders(tmp_path, zips):
    user = tmp_path / "user"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user))
    run = subprocess.run([sys.executable, str(HERE / "install_check.py"), str(zips["linux-x64"])], env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    report = json.loads(next(line for line in run.stdout.splitlines()[::-1] if line.startswith("{")))
    assert report["installed"] == ["FINISHED"] and report["enabled"]
    assert Path(report["addon_file"]).is_relative_to(user / "extensions" / "user_default" / "caustics")
    for module in ("embreex_file", "embree_library", "numba_file", "numba_extension", "llvmlite_file",
                   "llvmlite_library"):
        assert Path(report[module]).is_relative_to(report["site_packages"]), (module, report[module])
    assert Path(report["site_packages"]).is_relative_to(user)
    # Blender picked the wheels of this Python out of the zip's two, and they
    # are the numba and llvmlite the tests run with in this venv.
    assert report["python_tag"] == PYTHON_TAG
    assert set(report["wheel_tags"]) == {"-".join(name.split("-")[:2]) for name in wheel_files("linux-x64")
                                         if name.split("-")[2] == PYTHON_TAG}
    assert {f"numba-{version('numba')}", f"llvmlite-{version('llvmlite')}"} <= set(report["wheel_tags"])
    for dist, tags in report["wheel_tags"].items():
        assert tags and all(tag.startswith(f"{PYTHON_TAG}-{PYTHON_TAG}-") for tag in tags), (dist, tags)
    assert report["numba_extension"].endswith(report["extension_suffix"])
    assert report["kernel"] == 14.0
    # every kernel of the engine, for this Python, came compiled in the zip
    assert report["kernels_compiled"] == 0 and report["kernels_loaded"] >= 39
    assert report["rendered"] == ["FINISHED"] and report["size"] == [32, 24] and report["max"] > 1.0
