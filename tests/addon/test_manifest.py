"""The manifest, as the Extensions platform reviews it: who maintains the
add-on and where it lives, and platforms that are exactly what its wheels
serve, each named in README with the oldest OS its wheels run on."""

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


def oldest_os(tag: str) -> str:
    """The oldest OS a wheel's platform tag admits, as README words it."""
    if tag.startswith("manylinux"):
        return "glibc " + ".".join(tag.split("_")[1:3])
    if tag.startswith("macosx"):
        return "macOS " + ".".join(tag.split("_")[1:3])
    return "64-bit Windows"


def wheels() -> list[tuple[str, str]]:
    """(python tag, platform tag) of every wheel the manifest lists; a
    compressed tag set (a.b) counts by its oldest, first tag."""
    return [(name.split("-")[2], name.removesuffix(".whl").split("-")[4].split(".")[0])
            for name in (Path(w).name for w in MANIFEST["wheels"])]


def test_maintainer_has_a_contact_and_the_add_on_a_website():
    assert re.fullmatch(r"[^<>]+ <[^@\s<>]+@[^@\s<>]+\.[a-z]+>", MANIFEST["maintainer"])
    assert re.fullmatch(r"https://[^\s]+", MANIFEST["website"])


def test_platforms_are_exactly_those_the_wheels_serve_with_every_python():
    served = {}
    for python, tag in wheels():
        served.setdefault(platform_of(tag), set()).add(python)
    assert set(MANIFEST["platforms"]) == set(served) == set(PYTHONS)
    assert served == PYTHONS


def test_readme_gives_each_zip_the_oldest_os_its_wheels_run_on():
    for platform in MANIFEST["platforms"]:
        needs = {oldest_os(tag) for _, tag in wheels() if platform_of(tag) == platform}
        assert len(needs) == 1, (platform, needs)
        row = next((line for line in README.splitlines() if line.startswith(f"| {platform} |")), None)
        assert row is not None, f"README has no row for the {platform} zip"
        assert needs.pop() in row, row
