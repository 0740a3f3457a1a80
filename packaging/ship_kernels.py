"""The compiled kernels the zips carry, so that the first render after an
install loads them instead of compiling them (26 s on the 2-core machine).

    <python> packaging/ship_kernels.py compile FOLDER
    <python> packaging/ship_kernels.py strip ZIP...

`compile` compiles every kernel of the engine with this Python into FOLDER, the
engine imported under the name Blender gives it when a zip is installed
from disk (`bl_ext.user_default.caustics`), since a cached kernel refers
to its modules by name. `make package` runs it with each Python the zips
carry wheels for that this machine has; the kernels are compiled for the
platform's baseline CPU (caustic_addon/util/jit.py), so they serve every
machine of this platform. `strip` takes them out of the zips among ZIP of
other platforms than this machine's, which compile theirs in the
background when the add-on is enabled."""

from __future__ import annotations

import importlib
import os
import platform
import sys
import types
import zipfile
from pathlib import Path

from source_tree import PACKAGE, REPO


def engine_as_installed():
    """The engine, imported as `PACKAGE.caustic_addon` without the add-on
    around it (its __init__ would import bpy)."""
    for name, path in (("bl_ext", []), ("bl_ext.user_default", []), (PACKAGE, [str(REPO)])):
        package = types.ModuleType(name)
        package.__path__ = path
        sys.modules[name] = package
    return importlib.import_module(PACKAGE + ".caustic_addon")


def this_platform() -> str:
    """This machine's platform as the zips' names spell it (linux_x64, ...)."""
    machine = {"x86_64": "x64", "amd64": "x64", "arm64": "arm64", "aarch64": "arm64"}[platform.machine().lower()]
    return {"linux": "linux", "darwin": "macos", "win32": "windows"}[sys.platform] + "_" + machine


def strip(path: Path, folder: str = "kernels/") -> None:
    """Rewrite the zip at `path` without the entries under `folder`."""
    stripped = path.with_suffix(".stripped")
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(stripped, "w", zipfile.ZIP_DEFLATED) as target:
        for entry in source.infolist():
            if not entry.filename.startswith(folder):
                target.writestr(entry, source.read(entry), compress_type=entry.compress_type)
    os.replace(stripped, path)


if __name__ == "__main__":
    command, *paths = sys.argv[1:]
    if command == "compile":
        engine = engine_as_installed()
        engine.use_kernel_cache(paths[0])
        print(f"{engine.compile_kernels()} kernels for Python {sys.version_info[0]}.{sys.version_info[1]} "
              f"in {paths[0]}")
    else:
        for path in paths:
            if not path.endswith(f"-{this_platform()}.zip"):
                strip(Path(path))
