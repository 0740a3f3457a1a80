"""The backward pass: Whitted ray tracing from the eye (the paper's backward
ray tracing), with the illumination maps' light on the receivers.

Where a camera ray meets a flat receiver directly, the caustic is averaged,
not read at one point: a caustic's folds are singular, and point samples of
them alias. The beams' light is their exact mean over the part of the pixel
that sees the receiver (maps/screen_layer.py), the fallback photons' their
mean over the footprint of the ray's pixel stratum. Seen through glass or
in a mirror, the caustic is averaged over the footprint that the ray's
differentials carry there, in the pixels the edge pass refines (EyeTracer).

At an opaque surface: ambient * albedo, plus direct light from each lamp and
from the world (direct_light.py), plus caustic irradiance E_c * albedo / pi
read from the receiver's map, which holds the lamps' and the sky's light
through the casters, and what the point's lobes reflect of the sky through
them (world_paths.py), both in the caustic pass. Under a Principled BSDF's
layers (coat, metal, specular layer) the albedo is the base colour times
the share they leave it toward the eye, and its emission what the coat
leaves (optics/layers.py); their lobes reflect the lamps and the world,
but not the caustic, whose directions the map does not keep.

At a dielectric: both the reflected ray (weight F) and the refracted ray
(weight 1 - F) carry on, each times the glass's tint for what it did and
Beer-Lambert absorption inside, the refracted one's radiance scaled by
(n_from / n_to)^2 (optics.specular.radiance_scale1), up to `max_depth`
bounces. At a reflector the reflected
ray carries on, times the reflectance colour. A branch fainter than
ROULETTE_WEIGHT of its camera ray plays Russian roulette as `split` writes
it (bounce.Roulette): the faint internal reflections that make most of a
glass's tree stop, and the mean stays. At a rough surface both branches
leave about one GGX microfacet normal per eye sample (bounce.facets), the
pixel's samples stratified over the visible normals, so rough glass and
metal look rough, and lamps add their highlights there by next-event
estimation (direct_light.py), as in Cycles. A ray that leaves the scene sees
the world. Eye rays refract with a dispersive glass's IOR at 587.6 nm: the
caustics it throws are spectral (photon pass), the view through it is not.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np

from ..emission.environment import Environment, environment_of
from ..emission.radiometry import is_delta
from ..maps.charts import PlaneChart
from ..maps.illumination_map import IlluminationMap
from ..sampling.hash import stream_key
from ..scene import MeshLight, RenderSettings, Scene, World
from ..scene.material_table import Materials
from ..tracing.accelerator import CAMERA, Accelerator
from ..tracing.hits import MISS, Hits
from ..util.jit import kernel
from ..util.parallel import Monitor, chunk_size, run_chunks
from ..util.rows import take, take_rows
from ..util.vectors import max_channel
from .bounce import Roulette, facets, multiscatter, split, trace
from .interface import Interface
from .camera_rays import camera_footprints, eye_rays, pixel_offsets, ray_differentials
from .direct_light import direct_radiance, rough_specular_radiance, strata, world_light
from .paths import Paths, relative_floor
from .seen_lamps import lamps_met
from .world_paths import WorldThroughCasters

PASSES = ("direct", "caustic", "ambient")
# The buffer of each pixel's share cut out by holdouts (its alpha is 1 minus it).
HOLDOUT = "holdout"
# Hash streams of the rotations of a pixel's microfacet strata: two a bounce.
_FACET_STREAM = 1 << 17
# Hash streams of the Russian roulette of faint branches: one a bounce.
_ROULETTE_STREAM = 1 << 19
# An eye branch fainter than this share of its camera ray plays Russian roulette.
ROULETTE_WEIGHT = 0.05
# Neighbours whose light differs by more than this share of the brighter
# one sit across an edge (a shadow's, or one seen through glass).
EDGE_CONTRAST = 0.2


class EyeTracer:
    """The eye pass's choices in the bounce (bounce.trace), for the eye rays
    of the flat pixels `pixels (m,)`: the world where a ray escapes, shading
    where it meets an opaque surface, both branches at a specular one, where
    camera rays meeting a holdout stop. A path's id is its eye sample, `spp`
    to a pixel: local pixel * spp + stratum. Pass buffers, the holdout's
    among them, are each (m, 3); `first (m spp,)` is the object each camera
    ray meets first (MISS where it leaves the scene). A camera ray (one
    with no specular event yet) stands for a square stratum of its pixel, of
    side 1 / sqrt(spp) pixels. `holdout (objects,)` bool per object.

    The extra-sampling pass over the pixels whose samples disagree
    (`edge_pass`) casts all of a small lamp's shadow rays, and its eye rays
    carry ray differentials through their specular bounces
    (differentials.py), so that a flat receiver's caustic seen through
    glass or in a mirror is its footprint's mean there too: a curved lens
    magnifies a caustic's sharp lines past its pixels, and their point
    samples disagree. Elsewhere the samples agree, and the differentials
    would cost the pass about 30% more for nothing (a pool's caustic through
    its water changes by 0.02%)."""

    def __init__(self, accel: Accelerator, scene: Scene, materials: Materials, maps: dict[int, IlluminationMap],
                 environment: Environment, sky_paths: WorldThroughCasters | None, settings: RenderSettings,
                 pixels: np.ndarray, spp: int, holdout: np.ndarray, edge_pass: bool = False):
        self.accel, self.scene, self.materials, self.maps = accel, scene, materials, maps
        self.holdout, self.adaptive_shadows = holdout, not edge_pass
        self.environment, self.sky_paths, self.settings = environment, sky_paths, settings
        self.dark_world = scene.world.is_black
        # a mesh light is seen as the emission of its own faces
        self.sized_lamps = [light for light in scene.lights if not is_delta(light) and not isinstance(light, MeshLight)]
        self.energy, self.spp = settings.energy, spp
        self.stratum = 1.0 / math.sqrt(spp)
        self.pixels = np.ascontiguousarray(pixels, dtype=np.int64)
        self.far = 4.0 * scene.extent() + float(np.abs(scene.camera.position).max())
        self.buffers = {name: np.zeros((len(pixels), 3)) for name in (*PASSES, HOLDOUT)}
        self.first = np.full(len(pixels) * spp, MISS)
        self.footprints = edge_pass and any(isinstance(imap.chart, PlaneChart) for imap in maps.values())

    def _add(self, name: str, ids: np.ndarray, weight: np.ndarray, radiance: np.ndarray) -> None:
        """Add `weight * radiance (n,3)` of the eye samples `ids (n,)` to
        their pixels' rows of pass buffer `name`."""
        _accumulate(self.buffers[name], np.ascontiguousarray(ids, dtype=np.int64), self.spp,
                    np.ascontiguousarray(weight, dtype=np.float64), np.ascontiguousarray(radiance, dtype=np.float64))

    def _samples(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(local, pixel, stratum), each (n,), of the eye samples `ids (n,)`:
        the pixel's row in the buffers, its flat index in the image (which
        the hash streams take, so that chunks do not share strata), and the
        sample's stratum in it."""
        local = ids // self.spp
        return local, np.take(self.pixels, local), ids % self.spp

    def _met(self, rays: Paths, hits: Hits) -> None:
        camera = ~rays.specular
        self.first[rays.ids[camera]] = hits.obj[camera]
        self._lamps_met(rays, hits.t)

    def _lamps_met(self, rays: Paths, reach: np.ndarray) -> None:
        """The lamps with a size that `rays` meet before `reach (n,)`, into
        the direct pass: seen straight on, in smooth surfaces, and by the
        rays a rough caster drew, these weighed against the lamp samples of
        its highlights (`_highlights`) by multiple importance sampling."""
        if not self.sized_lamps or not len(rays):
            return
        radiance = lamps_met(self.sized_lamps, self.energy, rays.origins, rays.dirs, reach, rays.kind, rays.pdf,
                             self.settings.lamp_samples)
        self._add("direct", rays.ids, rays.weight, radiance)

    def _after_smooth(self, rays: Paths) -> np.ndarray:
        """(n,) bool: the rays from the camera or a smooth surface, which see
        emitting faces; a rough surface's samples of a mesh light hold the
        light its rays would meet there."""
        after = self.accel.owners(np.maximum(rays.surface, 0))
        return (rays.surface == MISS) | (np.take(self.materials.alpha, after) <= 0.0)

    def escaped(self, rays: Paths) -> None:
        self._lamps_met(rays, np.full(len(rays), np.inf))
        if not self.dark_world:
            self._add("ambient", rays.ids, rays.weight, self.environment.radiance(rays.dirs))

    def _cut_out(self, rays: Paths, hits: Hits) -> np.ndarray:
        """(n,) bool: the camera rays that met a holdout, their weight added
        to the holdout buffer."""
        cut = np.take(self.holdout, hits.obj) & (rays.kind == CAMERA)
        if cut.any():
            here = rays.select(cut)
            self._add(HOLDOUT, here.ids, here.weight, np.ones((len(here), 3)))
        return cut

    def arrived(self, rays: Paths, hits: Hits) -> None:
        self._met(rays, hits)
        cut = self._cut_out(rays, hits)
        if cut.any():
            rays, hits = rays.select(~cut), hits.select(~cut)
        if len(rays) == 0:
            return
        m, accel = self.materials, self.accel
        view = -rays.dirs
        facing = accel.face_normals(hits.obj, hits.prim)
        _turn_toward(facing, view)
        shading = np.ascontiguousarray(accel.shading_normal(hits.obj, hits.prim, hits.u, hits.v))
        cos_view = _turn_toward(shading, view)
        triangle = hits.prim - np.take(accel.prim_offset, hits.obj)
        albedo = m.albedo_at(hits.obj, triangle, hits.u, hits.v, hits.points)
        lobes, share, emitted = m.layers_at(hits.obj, cos_view, albedo)
        diffuse = albedo * share

        points, settings = hits.points, self.settings
        _, pixel, stratum = self._samples(rays.ids)
        direct = direct_radiance(accel, self.scene.lights, self.energy, points, shading, facing, view, diffuse,
                                 lobes, self.far, pixel, stratum, settings.lamp_samples, settings.seed,
                                 self.adaptive_shadows, self.spp)
        emission = np.take(m.emission, hits.obj, axis=0) * emitted * self._after_smooth(rays)[:, None]
        self._add("direct", rays.ids, rays.weight, direct + emission)
        caustic = np.zeros((len(rays), 3))
        for index, imap in self.maps.items():
            on_map = hits.obj == index
            if not on_map.any():
                continue
            here, at = rays.select(on_map), hits.select(on_map)
            irradiance = self._caustic(imap, index, here, at, pixel[on_map])
            caustic[on_map] = irradiance * take_rows(on_map, diffuse)[0] / math.pi
        ambient = self.scene.ambient * diffuse
        if not self.dark_world:
            chance = None
            if self.sky_paths is not None:
                glossy = sum((max_channel(lobe.gain) + max_channel(lobe.metal) for lobe in lobes), np.zeros(len(rays)))
                chance = self.sky_paths.chances(glossy, direct + caustic)
            seen, through = world_light(accel, self.environment, points, shading, facing, view, lobes, self.far,
                                        pixel, stratum, settings.world_samples, settings.seed, self.sky_paths,
                                        rays.medium, hits.prim, chance)
            ambient = ambient + seen.irradiance * diffuse / math.pi + seen.glossy
            caustic += through
        self._add("ambient", rays.ids, rays.weight, ambient)
        self._add("caustic", rays.ids, rays.weight, caustic)

    def _caustic(self, imap: IlluminationMap, index: int, rays: Paths, hits: Hits, pixel: np.ndarray) -> np.ndarray:
        """(n,3) the caustic irradiance that `rays` see at their `hits` on
        receiver `index`, from eye samples in image pixels `pixel (n,)`.
        On a flat receiver it is the mean over each ray's footprint: camera
        rays' from the camera's differentials (the beams' exactly, from the
        screen layer), the others' from the differentials they carried
        through their specular bounces (differentials.py). Elsewhere, and
        where a footprint misses the receiver's plane, a point sample. The
        map holds the basic irradiance of the medium the light arrived
        through (bounce.on_maps), and the rays' medium gives back its n^2."""
        xy = imap.chart.coords(hits.prim - self.accel.prim_offset[index], hits.u, hits.v, hits.points)
        irradiance = np.empty((len(xy), 3))
        spread = np.zeros(len(xy), dtype=bool)
        if isinstance(imap.chart, PlaneChart):
            primary = np.flatnonzero(~rays.specular)
            if len(primary):
                lo, hi, ok = camera_footprints(self.scene.camera, imap.chart, take(rays.origins, primary),
                                               take(rays.dirs, primary), self.stratum)
                spread[primary[ok]] = True
                irradiance[primary[ok]] = imap.seen_mean(np.take(pixel, primary[ok]), lo[ok], hi[ok])
            if rays.d_origins is not None and rays.specular.any():
                seen = np.flatnonzero(rays.specular)
                lo, hi, ok = imap.chart.footprint(*(np.take(a, seen, axis=0) for a in (
                    rays.origins, rays.dirs, rays.d_origins, rays.d_dirs)), self.stratum)
                spread[seen[ok]] = True
                irradiance[seen[ok]] = imap.mean_over(lo[ok], hi[ok])
        irradiance[~spread] = imap.irradiance_at(xy[~spread])
        if (rays.medium != MISS).any():
            irradiance *= (self.materials.medium_ior(rays.medium) ** 2)[:, None]
        return irradiance

    def scattered(self, rays: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        self._met(rays, hits)
        cut = self._cut_out(rays, hits)
        if cut.any():
            rays, hits, surface = rays.select(~cut), hits.select(~cut), surface.select(~cut)
        if rays.d_origins is None and self.footprints:
            d_origins, d_dirs = ray_differentials(self.scene.camera, rays.dirs)
            rays = replace(rays, d_origins=d_origins.astype(np.float32), d_dirs=d_dirs.astype(np.float32))
        _, pixel, stratum = self._samples(rays.ids)
        if surface.rough.any():
            self._highlights(rays, hits, surface, depth < self.settings.max_depth)
            uv = strata(pixel, stratum, _FACET_STREAM + 2 * depth, self.settings.seed)
            surface = facets(surface, rays.dirs, self.materials, hits.obj, uv)
        roulette = Roulette(ROULETTE_WEIGHT, pixel * self.spp + stratum,
                            stream_key(_ROULETTE_STREAM + depth, self.settings.seed), self.spp)
        return split(self.accel, self.materials, rays, hits, surface, carries_light=False, roulette=roulette)

    def _highlights(self, rays: Paths, hits: Hits, surface: Interface, branches_traced: bool) -> None:
        """The lamps' direct light on the rough rows of `surface`, into the
        direct pass, times Multiscatter GGX's factor; weighed against the
        rays the bounce draws there where they are traced (`branches_traced`:
        not after the last bounce)."""
        if not self.scene.lights:
            return
        rows = np.flatnonzero(surface.rough)
        m, obj = self.materials, hits.obj[rows]
        ids = rays.ids[rows]
        _, pixel, stratum = self._samples(ids)
        tints = (np.take(m.reflection_tint, obj, axis=0), np.take(m.transmission_tint, obj, axis=0))
        radiance = rough_specular_radiance(
            self.accel, self.scene.lights, self.energy, np.take(surface.points, rows, axis=0),
            np.take(surface.shading, rows, axis=0), np.take(surface.facing, rows, axis=0),
            -np.take(rays.dirs, rows, axis=0), surface.alpha[rows], surface.eta[rows], m.reflector[obj], tints,
            self.far, pixel, stratum, self.settings.lamp_samples, self.settings.seed, branches_traced)
        factor = multiscatter(surface, m, hits.obj, rays.dirs, rays.dirs, np.zeros(len(rays), dtype=bool), False)
        self._add("direct", ids, np.take(rays.weight, rows, axis=0), np.take(factor, rows, axis=0) * radiance)


@kernel("void(f8[:, ::1], i8[::1], i8, f8[:, ::1], f8[:, ::1])")
def _accumulate(buffer, ids, spp, weight, radiance):
    """buffer[ids[i] // spp] += weight[i] radiance[i], channel by channel,
    in the order of the rows: `buffer (m,3)`, `ids (n,)` eye samples."""
    for i in range(len(ids)):
        row = ids[i] // spp
        for c in range(3):
            buffer[row, c] += weight[i, c] * radiance[i, c]


@kernel("f8[::1](f8[:, ::1], f8[:, ::1])")
def _turn_toward(normals, view):
    """Flip, in place, each of `normals (n,3)` that faces away from `view
    (n,3)` (n.v < 0); returns (n,) n.v of the normals turned."""
    cos = np.empty(len(normals))
    for i in range(len(normals)):
        c = normals[i, 0] * view[i, 0] + normals[i, 1] * view[i, 1] + normals[i, 2] * view[i, 2]
        if c < 0.0:
            for k in range(3):
                normals[i, k] = -normals[i, k]
            c = -c
        cos[i] = c
    return cos


def edge_pixels(first: np.ndarray, shown: np.ndarray, contrast: float = EDGE_CONTRAST) -> np.ndarray:
    """(h,w) bool: the pixels whose samples disagree, the pixels an
    extra-sampling pass antialiases. Samples disagree where a pixel's camera
    rays meet different objects, or meet another object than a neighbour's
    (a silhouette between them), or where what it shows differs from a
    neighbour's by more than `contrast` of the brighter (a shadow's edge,
    or an edge seen through glass). `first (h,w,s)` the object each of a
    pixel's s camera rays meets first; `shown (h,w)` the pixels' light (max
    channel), but for the caustic of a receiver seen directly, which is
    already the mean over the pixel's footprint (`shown_light`)."""
    edge = np.zeros(shown.shape, dtype=bool)
    _edge_pixels(np.ascontiguousarray(first, dtype=np.int64), np.ascontiguousarray(shown, dtype=np.float64),
                 float(contrast), edge)
    return edge


@kernel("void(i8[:, :, ::1], f8[:, ::1], f8, b1[:, ::1])")
def _edge_pixels(first, shown, contrast, edge):
    """edge_pixels into `edge (h,w)`, all False on entry: a pixel's own
    samples, then each pair of neighbours across and down."""
    h, w, spp = first.shape
    for y in range(h):
        for x in range(w):
            for k in range(1, spp):
                if first[y, x, k] != first[y, x, 0]:
                    edge[y, x] = True
            for dy, dx in ((0, 1), (1, 0)):
                v, u = y + dy, x + dx
                if v < h and u < w:
                    a, b = shown[y, x], shown[v, u]
                    if first[y, x, 0] != first[v, u, 0] or abs(a - b) > contrast * max(a, b):
                        edge[y, x] = edge[v, u] = True


def shown_light(first: np.ndarray, buffers: dict[str, np.ndarray], specular_surface: np.ndarray) -> np.ndarray:
    """(m,) what each of m pixels shows (max channel of its passes' sum),
    its caustic counted only in the share of its samples `first (m,s)`
    that met a specular surface first (`specular_surface (objects,)`): the
    caustic a camera ray sees on a receiver is already its footprint's mean.
    `buffers` the pass buffers, (m,3) float32 each."""
    out = np.empty(len(first))
    _shown_light(np.ascontiguousarray(first, dtype=np.int64), buffers["direct"], buffers["ambient"],
                 buffers["caustic"], np.ascontiguousarray(specular_surface, dtype=bool), out)
    return out


@kernel("void(i8[:, ::1], f4[:, ::1], f4[:, ::1], f4[:, ::1], b1[::1], f8[::1])")
def _shown_light(first, direct, ambient, caustic, specular_surface, out):
    """shown_light into `out (m,)`; a channel that is not a number makes
    the pixel's light not a number, as numpy's max would."""
    spp = first.shape[1]
    for p in range(len(first)):
        through = 0.0
        for k in range(spp):
            o = first[p, k]
            if o != MISS and specular_surface[o]:
                through += 1.0
        share = through / spp
        light = direct[p, 0] + ambient[p, 0] + caustic[p, 0] * share
        for c in range(1, 3):
            v = direct[p, c] + ambient[p, c] + caustic[p, c] * share
            if v > light or v != v:
                light = v
        out[p] = light


def camera_radiance_scale(materials: Materials, camera_medium: int) -> float:
    """What a camera inside glass or water (object `camera_medium`, MISS in
    the air) records of the radiance there: the basic radiance L / n^2
    (Veach 1997, sec. 5.2), as Cycles, whose paths take no factor at
    refractions, renders it; the eye's refracted rays scale radiance from
    the camera's medium on (specular.radiance_scale1), so a floor seen from
    under water is as bright as from above it, less the Fresnel losses."""
    if camera_medium == MISS or not materials.dielectric[camera_medium]:
        return 1.0
    return 1.0 / float(materials.ior[camera_medium]) ** 2


def eye_pass(scene: Scene, settings: RenderSettings, accel: Accelerator, materials: Materials,
             maps: dict[int, IlluminationMap], sky: World, monitor: Monitor, start: float) -> dict[str, np.ndarray]:
    """Trace `spp` eye rays through every pixel, chunk by chunk, reporting
    progress from `start` to 1; then, with `edge_samples`, trace that many
    again through each pixel whose samples disagree (`edge_pixels`: a
    silhouette, a shadow's edge, an edge seen through glass), which replace
    its first ones and cast all of a small lamp's shadow rays. The world's
    light through the casters is the `sky`'s, the world without its sun.
    Returns the pass buffers and the holdout's, each (pixels, 3) float32."""
    cam = scene.camera
    pixels = cam.pixx * cam.pixy
    camera_media = tuple(int(m[0]) for m in accel.media_at(cam.position[None]))
    seen = camera_radiance_scale(materials, camera_media[0])
    environment = environment_of(scene.world)
    sky_paths = None
    if materials.specular_surface.any() and not sky.is_black and materials.stacks:
        sky_paths = WorldThroughCasters(accel, materials, environment_of(sky), settings.max_depth, settings.seed)
    holdout = np.array([o.visibility.holdout for o in scene.objects], dtype=bool)
    edges = settings.edge_samples > settings.spp
    main_share = (1.0 - start) * (0.8 if edges else 1.0)

    def trace_pixels(pixel_list: np.ndarray, spp: int, begin: float, share: float, stage: str, edge_pass: bool):
        """Buffers (m,3) by pass and the first objects (m spp,) of `spp`
        samples in each of the pixels `pixel_list (m,)`, as the main pass
        or the edge pass traces them (EyeTracer)."""
        offsets = pixel_offsets(spp, settings.seed)
        per_job = max(1, chunk_size(len(pixel_list) * spp, settings.chunk_size, settings.threads) // spp)

        def job(first: int):
            local = np.arange(first, min(first + per_job, len(pixel_list)))
            sample = (local[:, None] * spp + np.arange(spp)).ravel()
            pixel = np.take(pixel_list, sample // spp)
            origins, dirs = eye_rays(cam, pixel, offsets[sample % spp])
            weight = np.full((len(sample), 3), seen / spp)
            tracer = EyeTracer(accel, scene, materials, maps, environment, sky_paths, settings, pixel_list[local],
                               spp, holdout, edge_pass)
            trace(accel, materials, Paths.start(origins, dirs, weight, sample - first * spp, camera_media,
                                                relative_floor(weight), camera=True), settings.max_depth, tracer)
            return first, tracer

        # float32, as the image keeps them: a chunk's tracer sums each pixel's samples in float64
        buffers = {name: np.zeros((len(pixel_list), 3), dtype=np.float32) for name in (*PASSES, HOLDOUT)}
        first_objects = np.full(len(pixel_list) * spp, MISS)

        def add(done) -> None:
            first, tracer = done
            end = first + len(tracer.pixels)
            for name in buffers:
                buffers[name][first:end] += tracer.buffers[name]
            first_objects[first * spp:end * spp] = tracer.first

        jobs = [partial(job, first) for first in range(0, len(pixel_list), per_job)]
        run_chunks(jobs, settings.threads, monitor, begin, share, stage, add)
        return buffers, first_objects

    buffers, first = trace_pixels(np.arange(pixels), settings.spp, start, main_share, "eye pass", False)
    if edges and pixels > 1:
        shown = shown_light(first.reshape(pixels, settings.spp), buffers, materials.specular_surface)
        refine = np.flatnonzero(edge_pixels(first.reshape(cam.pixy, cam.pixx, settings.spp),
                                            shown.reshape(cam.pixy, cam.pixx)))
        if len(refine):
            extra, _ = trace_pixels(refine, settings.edge_samples, start + main_share, 1.0 - start - main_share,
                                    "eye pass", True)
            for name in buffers:
                buffers[name][refine] = extra[name]
        else:
            monitor.step(1.0, "eye pass")
    return buffers
