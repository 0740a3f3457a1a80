"""The forward pass: photons from the lamps through the dielectrics and off
the reflectors, in any order, onto the receivers' illumination maps.

At a dielectric a photon reflects with the Fresnel probability F and refracts
otherwise, keeping its flux: Russian roulette with the exact probability, so
the estimate stays unbiased with a single path per photon. At a reflector it
always reflects, r = d - 2 (d.n) n, its flux times the reflectance colour
(Russian roulette ends the photons it dims below ROULETTE_FRACTION, keeping
the expected flux). Inside a medium
its flux falls by Beer-Lambert over each segment. A photon lands in a
receiver's map only after at least one specular event; the eye pass computes
direct light exactly, so nothing is counted twice.

When a material disperses, each photon carries one of K wavelength bands
(spectrum.photon_band, stratified over its id), refracts with that band's
IOR, and its flux is multiplied by K times the band's RGB weight: the K
weights sum to (1,1,1), so the expected flux is unchanged and the photon
count, and the cost, stay the same.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from ..emission.aims import casters_and_bounds
from ..emission.photons import Emitter, Photons, make_emitters
from ..maps.deposits import Deposits
from ..optics.spectrum import photon_band
from ..sampling.hash import hash_uniform
from ..scene import RenderSettings, Scene
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS, Hits
from ..util.parallel import Monitor, chunk_size, run_chunks
from ..util.vectors import DIVISION_FLOOR, max_channel
from .bounce import Interface, crossed_medium, on_maps, scatter, trace
from .lamp_pass import JobResult, LampPassStats, deliverer, lamp_medium
from .paths import Paths

# Below this fraction of its starting flux (max channel), a photon plays
# Russian roulette and survives with probability flux / threshold.
ROULETTE_FRACTION = 0.05


class PhotonTracer:
    """The photon pass's choices in the bounce (bounce.trace): land on the
    receivers' maps after a specular event; at a specular hit, reflect with
    probability F, else refract, then play Russian roulette. A photon's
    random numbers come from its id, bounce and `seed`."""

    def __init__(self, accel: Accelerator, materials: Materials, maps: dict, seed: int):
        self.accel, self.materials, self.maps, self.seed = accel, materials, maps, seed
        self.deposits = Deposits()
        self.landed = 0

    def escaped(self, paths: Paths) -> None:
        pass

    def arrived(self, paths: Paths, hits: Hits) -> None:
        for obj, rows, xy, scale, _ in on_maps(self.accel, self.maps, paths, hits):
            self.deposits.add_photons(obj, xy, np.take(paths.weight, rows, axis=0), scale)
            self.landed += len(rows)

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        dirs, crossed = scatter(surface, paths.dirs, hash_uniform(paths.ids, 2 * depth, self.seed) < surface.fresnel)
        weight = paths.weight * np.take(self.materials.color, hits.obj, axis=0)
        weight, alive = roulette(weight, paths.floor, hash_uniform(paths.ids, 2 * depth + 1, self.seed))
        paths = Paths(self.accel.offset(surface.points, surface.facing, dirs), dirs, weight,
                      crossed_medium(surface, crossed, hits.obj, paths.medium), paths.ids, paths.floor,
                      np.ones(len(paths), dtype=bool), paths.band, surface=hits.prim)
        return paths.select(alive)


def trace_photons(accel: Accelerator, materials: Materials, maps: dict, photons: Photons, max_depth: int,
                  seed: int, start_medium: int = MISS) -> JobResult:
    """Trace one batch of photons, which start inside object `start_medium`
    (MISS: in air), to where they land on `maps` (receiver object index ->
    map). Each carries its wavelength band's share of the flux, K times the
    band's weight."""
    band = photon_band(photons.ids, materials.band_count, seed)
    flux = photons.flux * (materials.band_count * materials.band_weights[band])
    tracer = PhotonTracer(accel, materials, maps, seed)
    paths = Paths.start(photons.origins, photons.dirs, flux, photons.ids, start_medium,
                        ROULETTE_FRACTION * max_channel(flux), band)
    trace(accel, materials, paths, max_depth, tracer)
    deposits = tracer.deposits
    return JobResult(deposits, LampPassStats(len(photons.ids), 0, tracer.landed, deposits.flux))


def photon_jobs(emitters: list[Emitter], accel: Accelerator, materials: Materials, maps: dict,
                settings: RenderSettings) -> list:
    """Jobs for util.parallel.run_chunks that trace the emitters' photons,
    chunk by chunk, each from the medium its lamp is in."""

    def job(emitter: Emitter, start: int, stop: int, medium: int) -> JobResult:
        return trace_photons(accel, materials, maps, emitter.emit(start, stop), settings.max_depth, settings.seed,
                             medium)

    jobs = []
    for emitter in emitters:
        size = chunk_size(emitter.count, settings.chunk_size, settings.threads)
        medium = MISS if emitter.light is None else lamp_medium(accel, emitter.light)
        jobs += [partial(job, emitter, start, min(start + size, emitter.count), medium)
                 for start in range(0, emitter.count, size)]
    return jobs


def photon_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
                maps: dict, monitor: Monitor, share: float) -> LampPassStats:
    """Emit and trace every photon, chunk by chunk, onto `maps`."""
    emitters = make_emitters(scene.lights, scene.world, *casters_and_bounds(scene), settings.emission,
                             settings.energy, settings.lamp_rays, settings.seed)
    stats, deliver = deliverer(maps)
    jobs = photon_jobs(emitters, accel, materials, maps, settings)
    run_chunks(jobs, settings.threads, monitor, 0.0, share, "photon pass", deliver)
    stats.lamp_rays = sum(e.count for e in emitters)
    return stats


def roulette(flux: np.ndarray, threshold: np.ndarray, xi: np.ndarray):
    """Russian roulette on photons whose flux (max channel) is below
    `threshold (n,)`: survive with probability q = flux / threshold, flux
    /= q. `xi (n,)` are uniform random numbers. Returns (flux (n,3), alive
    (n,) bool)."""
    peak = max_channel(flux)
    low = peak < threshold
    if not low.any():
        return flux, np.ones(len(flux), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(low, peak / threshold, 1.0)
    alive = ~low | (xi < q)
    flux = flux / np.where(alive, np.maximum(q, DIVISION_FLOOR), 1.0)[:, None]
    return flux, alive & (peak > 0.0)

