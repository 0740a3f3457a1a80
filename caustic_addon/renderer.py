"""A whole render: one Embree scene, the photon pass into illumination maps,
then the eye pass. This is the engine's entry point; the add-on and the CLI
call `render` and nothing below it."""

from __future__ import annotations

import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from functools import partial
from typing import Callable, Optional

import numpy as np

from .emission.beam_sources import beam_sources
from .emission.photons import make_emitters
from .emission.targets import Sphere
from .errors import Cancelled
from .maps.beam_map import BeamMap
from .maps.cache import MapCache, photon_pass_key
from .maps.charts import make_chart
from .maps.illumination_map import IlluminationMap, MapEstimate, auto_cell_size
from .passes.beam import band_beams
from .passes.camera_rays import eye_rays, pixel_offsets
from .passes.eye import PASSES, EyePass, EyeRays
from .passes.photon import TransportStats, trace_photons
from .scene import Light, RenderSettings, Scene, SunLight
from .scene.material_table import Materials
from .scene.validate import validate_scene
from .tracing.accelerator import Accelerator
from .tracing.hits import MISS

Progress = Callable[[float, str], None]
Cancel = Callable[[], bool]

# Share of the progress bar given to the photon pass when both passes run.
_FORWARD_SHARE = 0.6


@dataclass
class RenderResult:
    """image     (pixy, pixx, 4) float32 linear RGBA, row 0 at the top
    passes    name -> (pixy, pixx, 3) float32: 'direct' (lamps), 'caustic'
              (illumination maps), 'ambient' (ambient term and background);
              they sum to the image's RGB
    maps      receiver name -> IlluminationMap
    stats     counts and seconds per stage
    warnings  what the user should know about this render"""

    image: np.ndarray
    passes: dict[str, np.ndarray]
    maps: dict[str, IlluminationMap]
    stats: dict
    warnings: list[str] = field(default_factory=list)


class _Monitor:
    """Progress and cancel callbacks, checked between chunks."""

    def __init__(self, progress: Optional[Progress], cancel: Optional[Cancel]):
        self.progress, self.cancel = progress, cancel

    def step(self, fraction: float, stage: str) -> None:
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during the {stage}")
        if self.progress is not None:
            self.progress(min(max(fraction, 0.0), 1.0), stage)


def build_maps(scene: Scene, settings: RenderSettings, warnings: list[str]) -> dict[int, IlluminationMap]:
    """An empty illumination map for each receiver that can hold one."""
    estimate = MapEstimate(settings.k_nearest if settings.density in ("adaptive", "beam") else None)
    limit = settings.map_resolution_limit
    maps = {}
    for index, obj in enumerate(scene.objects):
        if not obj.is_receiver:
            continue
        chart = make_chart(obj)
        if chart is None:
            warnings.append(f"'{obj.name}' is curved and has no UV map: it receives no caustics")
            continue
        cell = auto_cell_size(chart, limit) if settings.map_scale is None else settings.map_scale / 1000.0
        if chart.size.max() / cell > limit:
            coarser = auto_cell_size(chart, limit)
            warnings.append(f"'{obj.name}': a map scale of {cell * 1000:.4g} mm needs more than {limit} cells "
                            f"across; using {coarser * 1000:.4g} mm")
            cell = coarser
        maps[index] = (BeamMap(obj.name, chart, cell, estimate, threads=settings.threads)
                       if settings.density == "beam" else IlluminationMap(obj.name, chart, cell, estimate))
    return maps


def targets_and_bounds(scene: Scene) -> tuple[list[Sphere], Sphere]:
    """The casters' (transparent and reflecting objects') bounding spheres,
    which lamps aim at, and the sphere around the whole scene."""
    lo, hi = scene.bounds()
    return ([Sphere.around(o.mesh.vertices) for o in scene.casters],
            Sphere(0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))))


def run_chunks(jobs: list[Callable[[], object]], threads: int, monitor: _Monitor, start: float, share: float,
               stage: str) -> list:
    """Run `jobs` with up to `threads` in flight, reporting progress from
    `start` to `start + share` and checking for cancel as each one ends.
    Two chunks in flight keep both cores busy: one traces in Embree (which
    releases the GIL) while the other shades in numpy. Returns the results
    in the jobs' order, whichever finishes first, so that whatever is summed
    from them is summed in the same order every time."""
    results = {}
    with ThreadPoolExecutor(threads) as pool:
        pending = {}
        try:
            for index, job in enumerate(jobs):
                pending[pool.submit(job)] = index
                if len(pending) < threads:
                    continue
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    results[pending.pop(future)] = future.result()
                monitor.step(start + share * len(results) / len(jobs), stage)
            for future, index in pending.items():
                results[index] = future.result()
                monitor.step(start + share * len(results) / len(jobs), stage)
        except BaseException:
            for future in pending:
                future.cancel()
            raise
    return [results[index] for index in range(len(jobs))]


def chunk(total: int, settings: RenderSettings) -> int:
    """Items per chunk: at most `chunk_size`, and few enough that each thread
    gets two chunks, so small renders use every core too: one chunk traces
    in Embree while the other shades in numpy."""
    return max(1, min(settings.chunk_size, -(-total // (2 * settings.threads))))


def lamp_medium(accel: Accelerator, light: Light) -> int:
    """The closed glass a lamp sits in, where its photons start; MISS for a
    sun (its photons start far upstream) or a lamp in air."""
    if isinstance(light, SunLight):
        return MISS
    return int(accel.medium_at(light.position[None])[0])


def forward_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
                 maps: dict[int, IlluminationMap], monitor: _Monitor, share: float) -> TransportStats:
    """Emit and trace every photon, chunk by chunk, into `maps`."""
    emitters = make_emitters(scene.lights, *targets_and_bounds(scene), settings.emission, settings.energy,
                             settings.lamp_rays, settings.seed)

    def job(emitter, start, stop, medium):
        return trace_photons(accel, materials, maps, emitter.emit(start, stop), settings.max_depth, settings.seed,
                             medium)

    jobs = []
    for emitter in emitters:
        size, medium = chunk(emitter.count, settings), lamp_medium(accel, emitter.light)
        jobs += [partial(job, emitter, start, min(start + size, emitter.count), medium)
                 for start in range(0, emitter.count, size)]
    stats = TransportStats()
    for chunk_stats in run_chunks(jobs, settings.threads, monitor, 0.0, share, "photon pass"):
        stats.add(chunk_stats)
    stats.emitted = sum(e.count for e in emitters)
    return stats


def beam_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
              maps: dict[int, IlluminationMap], monitor: _Monitor, share: float) -> TransportStats:
    """Trace every source's grid in bands of rows into beams on `maps`, once
    per wavelength band, with the photon count shared among them.
    Neighbouring bands of rows share a row, so every grid triangle is in one."""
    count = materials.band_count
    sources = beam_sources(scene.lights, *targets_and_bounds(scene), settings.energy, settings.lamp_rays // count)
    jobs = []
    for source in sources:
        # one band of rows per thread, of at most `chunk_size` points: a
        # band's cost is mostly numpy work per bounce and refinement level,
        # whatever its paths, so fewer bands are faster (measured on the ball
        # lens: 0.19 s against 0.29 s for two per thread)
        rows = max(1, min(settings.chunk_size // source.grid, -(-(source.grid - 1) // settings.threads)))
        medium = lamp_medium(accel, source.light)
        jobs += [partial(band_beams, source, first, min(first + rows + 1, source.grid), accel, materials, maps,
                         settings.max_depth, medium, settings.beam_refinement, band)
                 for band in range(count) for first in range(0, source.grid - 1, rows)]
    stats = TransportStats()
    for part in run_chunks(jobs, settings.threads, monitor, 0.0, share, "photon pass"):
        for obj, (corners, irradiance) in part.beams.items():
            maps[obj].add_beams(corners, irradiance)
        for obj, (xy, flux, scale) in part.photons.items():
            maps[obj].add_photons(xy, flux, scale)
        stats.rays += part.rays
        stats.emitted += part.paths
        stats.refined += part.refined
        stats.flux_landed = stats.flux_landed + part.flux_landed
    stats.landed = sum(m.beams for m in maps.values())
    return stats


def eye_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
             maps: dict[int, IlluminationMap], monitor: _Monitor, start: float) -> dict[str, np.ndarray]:
    """Trace `spp` eye rays through every pixel, chunk by chunk. Returns the
    pass buffers, each (pixels, 3)."""
    cam = scene.camera
    pixels = cam.pixx * cam.pixy
    offsets = pixel_offsets(settings.spp, settings.seed)
    samples = pixels * settings.spp

    camera_medium = int(accel.medium_at(cam.position[None])[0])
    size = chunk(samples, settings)

    def job(first):
        sample = np.arange(first, min(first + size, samples))
        pixel = sample // settings.spp
        offset = offsets[sample % settings.spp]
        origins, dirs = eye_rays(cam, pixel, offset)
        weight = np.full((len(sample), 3), 1.0 / settings.spp)
        # each sample stands for a square stratum of its pixel, 1/spp of its area
        tracer = EyePass(accel, scene, materials, maps, settings.energy, settings.max_depth,
                         1.0 / np.sqrt(settings.spp), pixel[0], pixel[-1] + 1)
        tracer.trace(EyeRays(origins, dirs, weight, pixel, np.full(len(sample), camera_medium), primary=True))
        return tracer

    jobs = [partial(job, first) for first in range(0, samples, size)]
    buffers = {name: np.zeros((pixels, 3)) for name in PASSES}
    for tracer in run_chunks(jobs, settings.threads, monitor, start, 1.0 - start, "eye pass"):
        for name in PASSES:
            buffers[name][tracer.first_pixel:tracer.end_pixel] += tracer.buffers[name]
    return buffers


def render(scene: Scene, settings: Optional[RenderSettings] = None, progress: Optional[Progress] = None,
           cancel: Optional[Cancel] = None, cache: Optional[MapCache] = None) -> RenderResult:
    """Render `scene`. `progress(fraction, stage)` is called between chunks;
    `cancel()` returning True stops the render with `Cancelled`. With a
    `cache`, the photon pass is skipped when an earlier render had the same
    geometry, lamps and photon settings. Raises `SceneError` (naming the
    culprit) for scenes that cannot render."""
    settings = settings or RenderSettings()
    settings.validate()
    warnings = validate_scene(scene)
    monitor = _Monitor(progress, cancel)
    seconds = {}

    clock = time.perf_counter()
    accel = Accelerator(scene.objects, scene.extent(), settings.threads)
    try:
        warnings += accel.warnings
        materials = Materials.of(scene.objects, settings.bands)
        seconds["bvh"] = time.perf_counter() - clock

        clock = time.perf_counter()
        key = photon_pass_key(scene, settings) if cache is not None else None
        cached = cache.get(key) if cache is not None else None
        if cached is None:
            maps = build_maps(scene, settings, warnings)
            run_forward = bool(maps) and bool(scene.casters) and settings.lamp_rays > 0
            share = _FORWARD_SHARE if run_forward else 0.0
            photon_stats = TransportStats()
            if run_forward:
                trace = beam_pass if settings.density == "beam" else forward_pass
                photon_stats = trace(scene, settings, accel, materials, maps, monitor, share)
            if cache is not None:
                cache.put(key, (maps, photon_stats, list(warnings)))
        else:
            maps, photon_stats, map_warnings = cached
            warnings += [w for w in map_warnings if w not in warnings]
            share = 0.0
        rays_forward = accel.rays_cast
        seconds["lamp_pass"] = time.perf_counter() - clock

        clock = time.perf_counter()
        for imap in maps.values():
            imap.prepare()
        seconds["maps"] = time.perf_counter() - clock

        clock = time.perf_counter()
        buffers = eye_pass(scene, settings, accel, materials, maps, monitor, share)
        seconds["eye"] = time.perf_counter() - clock
    finally:
        accel.close()

    cam = scene.camera
    passes = {}
    for name in PASSES:
        buf = buffers[name]
        bad = ~np.isfinite(buf)
        if bad.any():
            warnings.append(f"{int(bad.sum())} non-finite values in the {name} pass were set to 0")
            buf[bad] = 0.0
        passes[name] = buf.reshape(cam.pixy, cam.pixx, 3).astype(np.float32)
    image = np.ones((cam.pixy, cam.pixx, 4), dtype=np.float32)
    image[..., :3] = sum(passes[name] for name in PASSES)

    stats = {
        "lamp_rays": photon_stats.emitted,
        "lamp_rays_refined": photon_stats.refined,
        "landed": photon_stats.landed,
        "flux_landed_w": photon_stats.flux_landed.tolist(),
        "rays_lamp_pass": rays_forward,
        "rays_eye_pass": accel.rays_cast - rays_forward,
        "seconds": seconds,
        "maps_cached": cached is not None,
        "triangles": int(len(accel.owner)),
    }
    return RenderResult(image, passes, {m.name: m for m in maps.values()}, stats, warnings)
