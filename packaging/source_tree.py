"""The extension in this source tree, imported as Blender imports it once
installed from a zip: as `bl_ext.user_default.caustics`. The add-on then
keeps its compiled kernels in Blender's user folder for the extension, which
it seeds from the ones `make package` compiled under that name (kernels/),
so the tests, the demo and the benchmarks compile nothing that the zips
already carry. No bpy here: `blender_user_folders()` must run before bpy is
imported."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import os
import sys
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGE = "bl_ext.user_default." + tomllib.loads((REPO / "blender_manifest.toml").read_text())["id"]


def blender_user_folders() -> None:
    """Blender's user folders (preferences, extensions and their user
    folders) in .blender-user/<bpy version> of this tree, apart from the
    user's own Blender's, unless BLENDER_USER_RESOURCES names others; each
    Blender of the test matrix has its own, so two suites side by side
    never seed one folder together. Inside Blender, or once bpy is
    imported, its folders are set already: nothing changes."""
    if "bpy" in sys.modules:
        return
    os.environ.setdefault("BLENDER_USER_RESOURCES",
                          str(REPO / ".blender-user" / importlib.metadata.version("bpy")))


def import_addon():
    """The add-on from this tree as module PACKAGE (imported once, not
    registered); Blender's `bl_ext.user_default` package must exist, as it
    does once bpy is imported."""
    if PACKAGE in sys.modules:
        return sys.modules[PACKAGE]
    spec = importlib.util.spec_from_file_location(PACKAGE, REPO / "__init__.py",
                                                  submodule_search_locations=[str(REPO)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[PACKAGE] = module
    spec.loader.exec_module(module)
    return module
