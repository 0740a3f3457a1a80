"""Run in a fresh interpreter with BLENDER_USER_RESOURCES set: install the
extension zip given as argv[1] through Blender's own extension system, prove
its embreex (and the Embree library in its wheel), numba and llvmlite
wheels are the ones imported (the venv has its own copies) and that numba
compiles with them, count the engine's kernels loaded from the zip's
compiled ones and those compiled here, render a small caustic scene, and
print one line of JSON for the test to read."""

import glob
import importlib.machinery
import json
import os
import sys
import time

site_packages = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                             "python{}.{}".format(*sys.version_info[:2]), "site-packages")
# Blender extracts the extension's wheels here; ahead of the venv on sys.path,
# the engine imports the bundled embreex and numba, not the development ones;
# so nothing but bpy is imported before the install (a module imported
# earlier would stay the venv's).
os.makedirs(site_packages, exist_ok=True)
sys.path.insert(0, site_packages)

import bpy  # noqa: E402

MODULE = "bl_ext.user_default.caustics"

bpy.ops.wm.read_factory_settings(use_empty=True)
clock = time.perf_counter()
installed = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default",
                                                     enable_on_install=True)
sys.modules[MODULE + ".jobs.kernels"].wait()
kernels_ready = time.perf_counter() - clock
kernel_stats = [declared.compiled().stats for declared in sys.modules[MODULE + ".caustic_addon.util.jit"]._KERNELS]
import embreex  # noqa: E402
import llvmlite.binding.ffi  # noqa: E402
import numba  # noqa: E402
import numba._helperlib  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_scenes as scenes  # noqa: E402


@numba.njit(nogil=True)
def _sum_of_squares(values):
    total = 0.0
    for value in values:
        total += value * value
    return total


def wheel_tags() -> dict[str, list[str]]:
    """Each dist-info Blender extracted: its name-version and its wheel's tags."""
    tags = {}
    for path in glob.glob(os.path.join(site_packages, "*.dist-info", "WHEEL")):
        with open(path, encoding="utf8") as wheel:
            tags[os.path.basename(os.path.dirname(path)).removesuffix(".dist-info")] = sorted(
                line.split(":", 1)[1].strip() for line in wheel if line.startswith("Tag:"))
    return tags


scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
rendered = bpy.ops.caustic.render()
image = bpy.data.images["Caustic Render"]
print(json.dumps({
    "installed": sorted(installed),
    "enabled": MODULE in bpy.context.preferences.addons,
    "addon_file": sys.modules[MODULE].__file__,
    "embreex_file": embreex.__file__,
    "embree_library": str(sys.modules[MODULE + ".caustic_addon.tracing.embree"].library_path()),
    "numba_file": numba.__file__,
    "numba_extension": numba._helperlib.__file__,
    "llvmlite_file": llvmlite.__file__,
    "llvmlite_library": llvmlite.binding.ffi.lib._name,
    "extension_suffix": importlib.machinery.EXTENSION_SUFFIXES[0],
    "python_tag": "cp{}{}".format(*sys.version_info[:2]),
    "wheel_tags": wheel_tags(),
    "kernel": _sum_of_squares(np.arange(4.0)),
    "kernels_loaded": sum(sum(stats.cache_hits.values()) for stats in kernel_stats),
    "kernels_compiled": sum(sum(stats.cache_misses.values()) for stats in kernel_stats),
    "kernels_ready_seconds": kernels_ready,
    "site_packages": site_packages,
    "rendered": sorted(rendered),
    "size": list(image.size),
    "max": max(image.pixels[:]),
}))
sys.stdout.flush()
bpy.ops.preferences.addon_disable(module=MODULE)
