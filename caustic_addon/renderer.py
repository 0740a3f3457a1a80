"""A whole render: one Embree scene, the pass from the lamps (photons or
beams) into the illumination maps, then the eye pass. This is the engine's
entry point; the add-on and the CLI call `render` and nothing below it."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np

from .emission.mesh_lights import mesh_lights
from .emission.sky_lamps import lighting_casters
from .emission.world_sun import extract_sun
from .errors import SceneError
from .maps.cache import MapCache, lamp_pass_key
from .maps.illumination_map import IlluminationMap
from .maps.receivers import build_maps
from .memory import refusal
from .passes.beam import beam_pass
from .passes.camera_rays import image_view
from .passes.eye import HOLDOUT, PASSES, eye_pass
from .passes.lamp_pass import LampPassStats, lamps_in_glass
from .passes.photon import photon_pass
from .scene import AreaLight, MeshLight, RenderSettings, Scene, SunLight
from .scene.material_table import Materials
from .scene.validate import rough_caster_warnings, validate_scene
from .tracing.accelerator import Accelerator
from .tracing.hits import MISS
from .util import heap
from .util.parallel import Cancel, Monitor, Progress

# Share of the progress bar given to the pass from the lamps when both run.
_LAMP_SHARE = 0.6


@dataclass
class RenderResult:
    """image     (pixy, pixx, 4) float32 linear RGBA, row 0 at the top;
              alpha is 1 but where holdouts cut the pixel out
    passes    name -> (pixy, pixx, 3) float32: 'direct' (lamps), 'caustic'
              (illumination maps), 'ambient' (ambient term and the world);
              they sum to the image's RGB
    maps      receiver name -> IlluminationMap
    stats     counts and seconds per stage
    warnings  what the user should know about this render"""

    image: np.ndarray
    passes: dict[str, np.ndarray]
    maps: dict[str, IlluminationMap]
    stats: dict
    warnings: list[str] = field(default_factory=list)


def render(scene: Scene, settings: Optional[RenderSettings] = None, progress: Optional[Progress] = None,
           cancel: Optional[Cancel] = None, cache: Optional[MapCache] = None,
           key: Optional[str] = None) -> RenderResult:
    """Render `scene`. `progress(fraction, stage)` is called between chunks;
    `cancel()` returning True stops the render with `Cancelled`. With a
    `cache`, the pass from the lamps is skipped when an earlier render had
    the same geometry, lamps and lamp-pass settings (their `key`,
    maps.cache.lamp_pass_key, where the caller has it). Raises `SceneError`
    (naming the culprit) for scenes that cannot render."""
    settings = settings or RenderSettings()
    settings.validate()
    warnings = validate_scene(scene) + rough_caster_warnings(scene, settings.density)
    too_large = refusal(scene, settings)
    if too_large is not None:
        raise SceneError(too_large)
    heap.reuse_freed_memory()
    monitor = Monitor(progress, cancel)
    seconds = {}
    # (the emitting objects' lamps follow from the objects the key holds)
    key = (key or lamp_pass_key(scene, settings)) if cache is not None else None
    scene = replace(scene, lights=scene.lights + mesh_lights(scene))
    # an environment's sun is a lamp, and the rest of the world, the sky, is
    # suns of its regions (those that light the casters): their light
    # through the casters is in the maps
    sun, sky = extract_sun(scene.world)
    lamps = scene.lights + ([sun] if sun is not None else [])

    view = image_view(scene.camera) if settings.eye_pass else None
    cached = cache.get(key) if cache is not None else None
    if cached is not None and not all(imap.sees(view) for imap in cached[0].values()):
        cached = None
    cam = scene.camera
    buffers = {name: np.zeros((cam.pixx * cam.pixy, 3), dtype=np.float32) for name in (*PASSES, HOLDOUT)}
    rays_lamp_pass = rays_eye_pass = triangles = 0
    # a bake whose maps are kept needs no BVH
    if cached is not None and not settings.eye_pass:
        maps, lamp_stats, map_warnings = cached
        warnings += [w for w in map_warnings if w not in warnings]
    else:
        clock = time.perf_counter()
        accel = Accelerator(scene.objects, scene.extent(), settings.threads)
        try:
            warnings += accel.warnings
            materials = Materials.of(scene.objects, settings.bands)
            seconds["bvh"] = time.perf_counter() - clock

            clock = time.perf_counter()
            if cached is None:
                if cache is not None:
                    cache.make_room(key)
                warnings += lamps_in_glass(scene, accel) + lamps_on_surfaces(scene, accel)
                maps = build_maps(scene, settings, warnings, view)
                run_lamps = bool(maps) and bool(scene.casters) and settings.lamp_rays > 0
                share = (_LAMP_SHARE if settings.eye_pass else 1.0) if run_lamps else 0.0
                lamp_stats = LampPassStats()
                if run_lamps:
                    lamp_pass = beam_pass if settings.density == "beam" else photon_pass
                    lamps += lighting_casters(scene, sky, accel, lamps, settings.lamp_rays / materials.band_count)
                    lamp_stats = lamp_pass(scene, lamps, settings, accel, materials, maps, monitor, share)
                if cache is not None:
                    cache.put(key, (maps, lamp_stats, list(warnings)))
            else:
                maps, lamp_stats, map_warnings = cached
                warnings += [w for w in map_warnings if w not in warnings]
                share = 0.0
            rays_lamp_pass = accel.rays_cast
            seconds["lamp_pass"] = time.perf_counter() - clock

            clock = time.perf_counter()
            for imap in maps.values():
                imap.prepare()
            seconds["maps"] = time.perf_counter() - clock

            if settings.eye_pass:
                clock = time.perf_counter()
                buffers = eye_pass(scene, settings, accel, materials, maps, sky, monitor, share)
                seconds["eye"] = time.perf_counter() - clock
            rays_eye_pass, triangles = accel.rays_cast - rays_lamp_pass, int(accel.prim_offset[-1])
        finally:
            accel.close()

    passes = {}
    for name in PASSES:
        buf = buffers[name]
        bad = ~np.isfinite(buf)
        if bad.any():
            warnings.append(f"{int(bad.sum())} non-finite values in the {name} pass were set to 0")
            buf[bad] = 0.0
        passes[name] = buf.reshape(cam.pixy, cam.pixx, 3)
    image = np.empty((cam.pixy, cam.pixx, 4), dtype=np.float32)
    image[..., :3] = sum(passes[name] for name in PASSES)
    image[..., 3] = 1.0 - buffers[HOLDOUT].mean(axis=1).reshape(cam.pixy, cam.pixx)

    stats = {
        "lamp_rays": lamp_stats.lamp_rays,
        "lamp_rays_refined": lamp_stats.refined,
        "landed": lamp_stats.landed,
        "flux_landed_w": lamp_stats.flux_landed.tolist(),
        "rays_lamp_pass": rays_lamp_pass,
        "rays_eye_pass": rays_eye_pass,
        "seconds": seconds,
        "maps_cached": cached is not None,
        "triangles": triangles,
    }
    return RenderResult(image, passes, {m.name: m for m in maps.values()}, stats, warnings)


def lamps_on_surfaces(scene: Scene, accel: Accelerator) -> list[str]:
    """A warning for each point, spot or area lamp whose centre lies on a
    surface, within the tracing epsilon: its rays start on that surface and
    meet it at once, so it sends no light through the casters."""
    lamps = [light for light in scene.lights if not isinstance(light, (SunLight, MeshLight))]
    if not lamps:
        return []
    centres = np.array([light.center if isinstance(light, AreaLight) else light.position for light in lamps])
    warnings = []
    for light, obj in zip(lamps, accel.surface_at(centres).tolist()):
        if obj != MISS:
            warnings.append(f"light '{light.name}' lies on '{scene.objects[obj].body_name}' (within the tracing "
                            f"epsilon, {accel.epsilon:.2g} m): its rays start on that surface and stop there at "
                            "once, so it casts no caustics and may light nothing; move it off the surface")
    return warnings
