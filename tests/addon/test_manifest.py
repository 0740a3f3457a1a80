"""The manifest, as the Extensions platform reviews it: who maintains the
add-on and where it lives, and platforms that are exactly what each of its
packages' wheels serve, each named in README with the oldest OS all its
wheels run on."""

import re
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MANIFEST = tomllib.loads((REPO / "blender_manifest.toml").read_text())
README = (REPO / "README.md").read_text()
# The Pythons of the Blenders each platform runs: 3.11 for 4.2-5.0, 3.13 for
# 5.1 and later; Blender 4.5 LTS was the last for Intel Macs.
PYTHONS = {"linux-x64": {"cp311", "cp313"}, "windows-x64": {"cp311", "cp313"},
           "macos-arm64": {"cp311", "cp313"}, "macos-x64": {"cp311"}}


def platform_of(tag: str) -> str:
    if tag.startswith("manylinux") and tag.endswith("x86_64"):
        return "linux-x64"
    if tag == "win_amd64":
        return "windows-x64"
    assert tag.startswith("macosx"), tag
    return "macos-arm64" if tag.endswith("_arm64") else "macos-x64"


def oldest_os(tag: str) -> tuple[tuple[int, ...], str]:
    """The oldest OS a wheel's platform tag admits: its version, to compare,
    and its name as README words it."""
    if tag.startswith(("manylinux", "macosx")):
        major, minor = (int(part) for part in tag.split("_")[1:3])
        return (major, minor), ("glibc" if tag.startswith("manylinux") else "macOS") + f" {major}.{minor}"
    return (), "64-bit Windows"


def wheels() -> list[tuple[str, str, str, str]]:
    """(package, version, python tag, platform tag) of every wheel the
    manifest lists; a compressed tag set (a.b) counts by its oldest, first tag."""
    return [(*name.split("-")[:3], name.removesuffix(".whl").split("-")[4].split(".")[0])
            for name in (Path(w).name for w in MANIFEST["wheels"])]


def pinned(package: str) -> str:
    """The version every file of requirements/ pins for a package: the one
    each Blender of the test matrix runs."""
    versions = {line.split("==")[1] for path in (REPO / "requirements").glob("blender-*.txt")
                for line in path.read_text().splitlines() if line.startswith(package + "==")}
    assert len(versions) == 1, (package, versions)
    return versions.pop()


def test_maintainer_has_a_contact_and_the_add_on_a_website():
    assert re.fullmatch(r"[^<>]+ <[^@\s<>]+@[^@\s<>]+\.[a-z]+>", MANIFEST["maintainer"])
    assert re.fullmatch(r"https://[^\s]+", MANIFEST["website"])


def test_platforms_are_exactly_those_each_package_serves_with_every_python():
    served = {}
    for package, _, python, tag in wheels():
        served.setdefault(package, {}).setdefault(platform_of(tag), set()).add(python)
    assert set(served) == {"embreex", "numba", "llvmlite"}
    assert set(MANIFEST["platforms"]) == set(PYTHONS)
    for package, platforms in served.items():
        assert platforms == PYTHONS, package


def test_zips_bundle_the_versions_the_tests_run_but_on_intel_macs():
    """numba 0.62.1 and llvmlite 0.45.1 are the last with Intel-Mac wheels."""
    for package, version, _, tag in wheels():
        if platform_of(tag) == "macos-x64" and package != "embreex":
            assert version == {"numba": "0.62.1", "llvmlite": "0.45.1"}[package]
        else:
            assert version == pinned(package), (package, tag)


def test_readme_gives_each_zip_the_oldest_os_its_wheels_run_on():
    for platform in MANIFEST["platforms"]:
        needs = max(oldest_os(tag) for *_, tag in wheels() if platform_of(tag) == platform)[1]
        row = next((line for line in README.splitlines() if line.startswith(f"| {platform} |")), None)
        assert row is not None, f"README has no row for the {platform} zip"
        assert needs in row, row


def test_the_file_permission_names_every_kind_of_file_the_add_on_writes():
    """Blender shows the reason when the extension is installed: renders and
    animation frames, baked caustic images, the kernel cache (numba's, in
    the extension's user folder) and the Cycles comparison's render; at most
    64 characters, as Blender's manifest check allows."""
    reason = MANIFEST["permissions"]["files"]
    assert len(reason) <= 64
    for kind in ("renders", "baked caustics", "kernel cache", "Cycles comparison"):
        assert kind in reason, kind
