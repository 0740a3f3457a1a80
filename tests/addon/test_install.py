"""The extension as users get it: `make package` builds the zips, and
Blender's extension system installs one into a throw-away user folder."""

import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]


def test_zip_installs_with_its_wheel_and_renders(tmp_path):
    subprocess.run(["make", "-C", str(REPO), "package"], check=True, capture_output=True)
    zips = sorted((REPO / "dist").glob("caustics-*-linux_x64.zip"))
    assert zips, "make package made no linux-x64 zip"
    user = tmp_path / "user"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user))
    run = subprocess.run([sys.executable, str(HERE / "install_check.py"), str(zips[-1])], env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    report = json.loads(next(line for line in run.stdout.splitlines()[::-1] if line.startswith("{")))
    assert report["installed"] == ["FINISHED"] and report["enabled"]
    assert Path(report["addon_file"]).is_relative_to(user / "extensions" / "user_default" / "caustics")
    assert Path(report["embreex_file"]).is_relative_to(report["site_packages"])
    assert report["rendered"] == ["FINISHED"] and report["size"] == [32, 24] and report["max"] > 1.0
