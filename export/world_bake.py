"""A world only Cycles can evaluate (a Sky Texture, a rotated or mixed
environment, any tree but a Background with a plain colour or image) baked
to a lat-long image: the world rendered alone, in a scene of its own,
through Cycles' equirectangular camera turned so that the image is in the
mapping `caustic_addon.emission.environment` reads (+Z the top row, +X the
middle column). A bake is kept while the world's nodes stay as they are."""

from __future__ import annotations

import math
from typing import Optional

import bpy
import numpy as np

from .cycles_still import cycles_enabled, render_still
from .node_fingerprint import fingerprint
from .overrides import Overrides

# The Nishita sky's sun (0.545 degrees) is 3 pixels across.
BAKE_WIDTH = 2048
# Box-filtered samples per pixel: enough to give a 3-pixel sun its area.
BAKE_SAMPLES = 16

# world name -> (its nodes' fingerprint, its bake (h, w, 3))
_bakes: dict[str, tuple[tuple, np.ndarray]] = {}


def _render(world) -> np.ndarray:
    scene = bpy.data.scenes.new(f"Caustics: baking the world '{world.name}'")
    camera = bpy.data.cameras.new(scene.name)
    camera.type, camera.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    eye = bpy.data.objects.new(scene.name, camera)
    try:
        scene.collection.objects.link(eye)
        eye.rotation_euler = (0.5 * math.pi, 0.0, -0.5 * math.pi)
        scene.camera, scene.world = eye, world
        render, cycles = scene.render, scene.cycles
        render.engine = 'CYCLES'
        render.resolution_x, render.resolution_y, render.resolution_percentage = BAKE_WIDTH, BAKE_WIDTH // 2, 100
        cycles.device, cycles.samples, cycles.use_denoising = 'CPU', BAKE_SAMPLES, False
        cycles.pixel_filter_type, cycles.filter_width = 'BOX', 1.0
        with Overrides() as overrides:
            # the world's own switch for camera rays would bake it black
            overrides.set(world.cycles_visibility, "camera", True)
            pixels, _ = render_still(scene, overrides)
    finally:
        bpy.data.objects.remove(eye)
        bpy.data.cameras.remove(camera)
        bpy.data.scenes.remove(scene)
    return pixels[..., :3].astype(np.float64)


def bake_world(world, warnings: list[str]) -> Optional[np.ndarray]:
    """(h, w, 3) W/(m^2 sr) the world sends from each direction, or None
    (with a warning naming the world) when Cycles cannot bake it."""
    key = fingerprint(world.node_tree)
    kept = _bakes.get(world.name)
    if kept is not None and kept[0] == key:
        return kept[1]
    if not cycles_enabled():
        warnings.append(f"world '{world.name}': its nodes need Cycles to bake them, and the Cycles add-on is "
                        "disabled; the world is black")
        return None
    if bpy.app.is_job_running('RENDER'):
        warnings.append(f"world '{world.name}': its nodes need a Cycles bake, which cannot run while Blender "
                        "renders; the world is black")
        return None
    radiance = _render(world)
    _bakes.clear()
    _bakes[world.name] = (key, radiance)
    return radiance
