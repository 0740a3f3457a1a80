"""The forward pass: photons from the lamps through the dielectrics and off
the reflectors, in any order, onto the receivers' illumination maps.

At a dielectric a photon reflects with the Fresnel probability F and refracts
otherwise, keeping its flux: Russian roulette with the exact probability, so
the estimate stays unbiased with a single path per photon. At a rough
surface it first draws a GGX normal visible from its direction and makes
that choice there (bounce.facets), as Cycles samples its glass and glossy
BSDFs; its flux keeps G2/G1 and Multiscatter GGX's factor (taken, as
Cycles does, on the eye's side: at the direction it leaves along). At a reflector it
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
from ..optics.specular import radiance_scale1
from ..sampling.hash import hash_uniform, hash_uniform1, stream_key
from ..scene import Light, RenderSettings, Scene
from ..scene.material_table import MATERIAL_TYPES, Materials
from ..tracing.accelerator import GEOMETRY_TYPES, Accelerator, offset1
from ..tracing.hits import HIT_TYPES, MISS, Hits
from ..util.parallel import Monitor, chunk_size, run_chunks
from ..util.jit import inline, kernel, named_kernel
from ..util.rows import contiguous, take
from ..util.vectors import DIVISION_FLOOR, max_channel, max_channel1, row, set_row
from .bounce import crossed_media1, facets, multiscatter, on_maps, scatter, scatter1, trace, transmission1
from .interface import INTERFACE_TYPES, Interface
from .lamp_pass import JobResult, LampPassStats, deliverer, lamp_media
from .paths import PATH_TYPES, Paths

# Below this fraction of its starting flux (max channel), a photon plays
# Russian roulette and survives with probability flux / threshold.
ROULETTE_FRACTION = 0.05
# The first of the random streams a photon draws its microfacet normals
# from, two a bounce, past those of its Fresnel choices and roulette.
FACET_STREAM = 1 << 16


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
        for obj, rows, xy, scale, _, basic in on_maps(self.accel, self.materials, self.maps, paths, hits):
            self.deposits.add_photons(obj, xy, np.take(paths.weight, rows, axis=0) * basic[:, None], scale)
            self.landed += len(rows)

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        return one_branch(self.accel, self.materials, paths, hits, surface, paths.ids, depth, self.seed, 0, True)


def one_branch(accel: Accelerator, materials: Materials, paths: Paths, hits: Hits, surface: Interface,
               draws: np.ndarray, depth: int, seed: int, stream: int, carries_light: bool) -> Paths:
    """The paths that go on from their specular hits at bounce `depth`,
    each along one branch: reflected with its Fresnel probability, else
    refracted, about a GGX normal where the surface is rough, then Russian
    roulette (`_photon_bounces`); an eye ray's (not `carries_light`)
    refractions scale the radiance it carries (specular.radiance_scale1). A path's random numbers hash its id in
    `draws (n,)` with streams from `stream` on and `seed`; Multiscatter
    GGX's factor is taken on the eye's side (bounce.multiscatter) of light
    if `carries_light`, else of an eye ray."""
    rough = surface.rough.any()
    if rough:
        uv = np.stack([hash_uniform(draws, stream + FACET_STREAM + 2 * depth + k, seed) for k in (0, 1)], axis=1)
        surface = facets(surface, paths.dirs, materials, hits.obj, uv)
    reflect_key, roulette_key = (np.uint64(stream_key(stream + 2 * depth + k, seed)) for k in (0, 1))
    factor = np.zeros((0, 3))
    if rough:
        reflect = hash_uniform(draws, stream + 2 * depth, seed) < surface.fresnel
        dirs, crossed, _ = scatter(surface, paths.dirs, reflect)
        factor = multiscatter(surface, materials, hits.obj, paths.dirs, dirs, crossed, carries_light)
    n, f8, i8 = len(paths), np.float64, np.int64
    out = dict(out_origins=np.empty((n, 3)), out_dirs=np.empty((n, 3)), out_weight=np.empty((n, 3)),
               out_medium=np.empty(n, dtype=i8), out_outer=np.empty(n, dtype=i8), source=np.empty(n, dtype=i8))
    count = _photon_bounces(
        dirs=contiguous(paths.dirs, f8), weight=contiguous(paths.weight, f8), medium=contiguous(paths.medium, i8),
        outer=contiguous(paths.outer, i8), floor=contiguous(paths.floor, f8), draws=contiguous(draws, i8),
        obj=contiguous(hits.obj, i8), points=contiguous(surface.points, f8), facing=contiguous(surface.facing, f8),
        shading=contiguous(surface.shading, f8), scattering=contiguous(surface.scattering, f8),
        eta=contiguous(surface.eta, f8), fresnel=contiguous(surface.fresnel, f8), alpha=contiguous(surface.alpha, f8),
        beyond=contiguous(surface.beyond, i8), beneath=contiguous(surface.beneath, i8),
        joined=contiguous(surface.joined, i8),
        reflection_tint=materials.reflection_tint, transmission_tint=materials.transmission_tint,
        factor=contiguous(factor, f8), radiance=not carries_light, epsilon=accel.epsilon, reflect_key=reflect_key,
        roulette_key=roulette_key, **out)
    origins, dirs, weight, medium, outer, source = (out[name][:count] for name in out)
    return Paths(origins, dirs, weight, medium, outer, take(paths.ids, source), take(paths.floor, source),
                 np.ones(count, dtype=bool), None if paths.band is None else take(paths.band, source),
                 kind=None if paths.kind is None else take(paths.kind, source), surface=take(hits.prim, source))


@inline
def roulette1(peak, threshold, xi):
    """(divisor, alive) of Russian roulette on a photon whose flux (max
    channel) `peak` is below `threshold`: it survives with probability q =
    peak / threshold, its flux divided by q (at least DIVISION_FLOOR), for
    the uniform random number `xi`; above the threshold it goes on as it
    is. A photon without flux stops."""
    if not peak < threshold:
        return 1.0, peak > 0.0
    q = peak / threshold
    alive = xi < q
    return (max(q, DIVISION_FLOOR) if alive else 1.0), alive and peak > 0.0


@named_kernel("i8", PATH_TYPES, HIT_TYPES, INTERFACE_TYPES, MATERIAL_TYPES, GEOMETRY_TYPES,
              {"draws": "i8[::1]", "factor": "f8[:, ::1]", "radiance": "b1", "reflect_key": "u8",
               "roulette_key": "u8", "source": "i8[::1]"})
def _photon_bounces(dirs, weight, medium, outer, floor, draws, obj, points, facing, shading, scattering, eta,
                    fresnel, alpha, beyond, beneath, joined, reflection_tint, transmission_tint, factor, radiance,
                    epsilon, reflect_key, roulette_key, out_origins, out_dirs, out_weight, out_medium, out_outer,
                    source):
    """one_branch's rows: each path reflects where
    hash_uniform1(draw, reflect_key) < its Fresnel reflectance, else refracts
    (bounce.scatter1), its weight times the surface's tint for what it did,
    where it carries `radiance` and refracted times radiance_scale1, times
    what scatter1 keeps and, where `factor (n,3)` is given (else (0,3)),
    the multiscatter factor; then roulette1 with hash_uniform1(draw, roulette_key). The
    survivors go into the out_ arrays, in order, epsilon off the surface
    (offset1), `source` the row each comes from; returns how many."""
    count = 0
    for i in range(len(dirs)):
        o, d = obj[i], row(dirs, i)
        mirror = hash_uniform1(draws[i], reflect_key) < fresnel[i]
        out, crossed, kept = scatter1(d, row(scattering, i), row(facing, i), row(shading, i), eta[i], alpha[i],
                                      mirror)
        if kept == 0.0:
            continue
        c = transmission1(transmission_tint, o, joined[i]) if crossed else row(reflection_tint, o)
        s = radiance_scale1(eta[i]) if radiance and crossed else 1.0
        w = (weight[i, 0] * (c[0] * s), weight[i, 1] * (c[1] * s), weight[i, 2] * (c[2] * s))
        if len(factor):
            w = (w[0] * (kept * factor[i, 0]), w[1] * (kept * factor[i, 1]), w[2] * (kept * factor[i, 2]))
        divisor, alive = roulette1(max_channel1(w), floor[i], hash_uniform1(draws[i], roulette_key))
        if not alive:
            continue
        set_row(out_origins, count, offset1(row(points, i), row(facing, i), out, epsilon))
        set_row(out_dirs, count, out)
        set_row(out_weight, count, (w[0] / divisor, w[1] / divisor, w[2] / divisor))
        out_medium[count], out_outer[count] = crossed_media1(crossed, beyond[i], beneath[i], medium[i], outer[i])
        source[count] = i
        count += 1
    return count


def trace_photons(accel: Accelerator, materials: Materials, maps: dict, photons: Photons, max_depth: int,
                  seed: int, start_media: tuple[int, int] = (MISS, MISS)) -> JobResult:
    """Trace one batch of photons, which start inside the objects
    `start_media` (Paths.start), to where they land on `maps` (receiver object index ->
    map). Each carries its wavelength band's share of the flux, K times the
    band's weight."""
    band = photon_band(photons.ids, materials.band_count, seed)
    flux = photons.flux * (materials.band_count * materials.band_weights[band])
    tracer = PhotonTracer(accel, materials, maps, seed)
    paths = Paths.start(photons.origins, photons.dirs, flux, photons.ids, start_media,
                        ROULETTE_FRACTION * max_channel(flux), band)
    trace(accel, materials, paths, max_depth, tracer)
    deposits = tracer.deposits
    return JobResult(deposits, LampPassStats(len(photons.ids), 0, tracer.landed, deposits.flux))


def photon_jobs(emitters: list[Emitter], accel: Accelerator, materials: Materials, maps: dict,
                settings: RenderSettings) -> list:
    """Jobs for util.parallel.run_chunks that trace the emitters' photons,
    chunk by chunk, each from the medium its lamp is in."""

    def job(emitter: Emitter, start: int, stop: int, media: tuple[int, int]) -> JobResult:
        return trace_photons(accel, materials, maps, emitter.emit(start, stop), settings.max_depth, settings.seed,
                             media)

    jobs = []
    for emitter in emitters:
        size = chunk_size(emitter.count, settings.chunk_size, settings.threads)
        media = lamp_media(accel, emitter.light)
        jobs += [partial(job, emitter, start, min(start + size, emitter.count), media)
                 for start in range(0, emitter.count, size)]
    return jobs


def photon_pass(scene: Scene, lights: list[Light], settings: RenderSettings, accel: Accelerator,
                materials: Materials, maps: dict, monitor: Monitor, share: float) -> LampPassStats:
    """Emit and trace every photon of the `lights`, chunk by chunk, onto `maps`."""
    emitters = make_emitters(lights, *casters_and_bounds(scene), settings.emission, settings.energy,
                             settings.lamp_rays, settings.seed)
    stats, deliver = deliverer(maps)
    jobs = photon_jobs(emitters, accel, materials, maps, settings)
    run_chunks(jobs, settings.threads, monitor, 0.0, share, "photon pass", deliver)
    stats.lamp_rays = sum(e.count for e in emitters)
    return stats
