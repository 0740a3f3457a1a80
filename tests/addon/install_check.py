"""Run in a fresh interpreter with BLENDER_USER_RESOURCES set: install the
extension zip given as argv[1] through Blender's own extension system, prove
its embreex wheel is the one imported, render a small caustic scene with it,
and print one line of JSON for the test to read."""

import json
import os
import sys

site_packages = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                             "python{}.{}".format(*sys.version_info[:2]), "site-packages")
# Blender extracts the extension's wheels here; ahead of the venv on sys.path,
# the engine imports the bundled embreex and not the development one.
os.makedirs(site_packages, exist_ok=True)
sys.path.insert(0, site_packages)

import bpy  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_scenes as scenes  # noqa: E402

MODULE = "bl_ext.user_default.caustics"

bpy.ops.wm.read_factory_settings(use_empty=True)
installed = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default",
                                                     enable_on_install=True)
import embreex  # noqa: E402

scenes.ball_lens_scene(32, 24, lamp_rays=20_000, segments=32, rings=16)
rendered = bpy.ops.caustic.render()
image = bpy.data.images["Caustic Render"]
print(json.dumps({
    "installed": sorted(installed),
    "enabled": MODULE in bpy.context.preferences.addons,
    "addon_file": sys.modules[MODULE].__file__,
    "embreex_file": embreex.__file__,
    "site_packages": site_packages,
    "rendered": sorted(rendered),
    "size": list(image.size),
    "max": max(image.pixels[:]),
}))
sys.stdout.flush()
bpy.ops.preferences.addon_disable(module=MODULE)
