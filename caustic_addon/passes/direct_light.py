"""Direct light at opaque surface points and at rough casters, with shadow rays: from each lamp
(emission/lamp_samples.py) and from the world.

Radiance leaving a point toward the eye v, per sample of a lamp bringing
irradiance E at normal incidence along the unit vector l:

    L = E cos(theta_l) diffuse / pi + E f_s(v, l) cos(theta_l)

the Lambert term of the diffuse base (what a Cycles Diffuse BSDF returns;
under a Principled BSDF's layers, its base colour times the share they
leave it) plus the layers' GGX lobes: the specular layer's with the
metal's, and the coat's (optics/principled.py, optics/layers.py). A
lamp of size 0 takes one sample; a lamp with a size takes `samples`,
stratified over a pixel: eye sample s of a pixel uses points s K .. s K +
K - 1 of the R2 sequence, rotated by a hash of the pixel. A lamp that
looks smaller than a degree (a sun, a small lamp far off) casts a few of
them first, at least two a pixel, and the rest only where a pixel's
points disagree (`direct_radiance`). A sample behind the surface gets no shadow ray.
Dielectrics and reflectors block the lamps' shadow rays: the light they
redirect arrives through the illumination maps.

Each rough lobe takes a lamp's light by two strategies (Veach 1997,
multiple importance sampling, as Cycles does): the lamp's samples, and as
many rays drawn from the lobe by its visible normals (`lobe_drawn_lamps`),
which meet the lamp itself (seen_lamps.py). Each weighs what it finds by
the power heuristic, p_own^2 / (p_lamp^2 + p_lobe^2) (sampling/mis.py,
as Cycles does): a narrow lobe under a large lamp gets its highlight from
its own rays, a wide one from the lamp's samples. The diffuse base takes the lamp's samples alone.
Rough casters show the lamps' highlights (`rough_specular_radiance`), as
Cycles' glossy and glass closures do, weighed against the rays the eye
pass's bounce draws there, which meet the lamps themselves, by the same
heuristic.

The world lights a surface with E = int L(w) V(w) cos(theta) dw over the
hemisphere, and its lobes with int L(w) V(w) f_s(v, w) cos(theta) dw, what
Cycles computes with bounces at 0. All are estimated from the same
directions, drawn by cos(theta) / pi (Malley), for an image by the world's
radiance (environment.py), and by each lobe's visible normals (Heitz 2018),
weighted by the balance heuristic (Veach 1997). A direction
that meets a caster brings its light to the surface through the maps
(emission/sky_lamps.py), as a lamp's; what the lobes reflect of it goes on
through the caster to the sky (world_paths.py), kept apart for the caustic
pass."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..emission import radiometry
from ..emission.environment import Environment
from ..emission.lamp_samples import apparent_size, sample_lamp
from ..optics.microfacet import branch_pdf1, bsdf_cosine1
from ..optics.principled import Lobe, lobe_pdf1, lobe_weight1
from ..optics.specular import radiance_scale1
from ..sampling.hash import hash_uniform, hash_uniform1, stream_key
from ..sampling.mis import power_heuristic1
from ..sampling.sequences import r2_point1
from ..sampling.warps import cosine_hemisphere, frames
from ..scene import Light, MeshLight
from ..tracing.accelerator import REFLECTED, Accelerator
from ..util.jit import kernel
from ..util.rows import contiguous
from ..util.vectors import DIVISION_FLOOR, dot, dot1, max_channel1, row, set_row
from .seen_lamps import lamps_met
from .world_paths import WorldThroughCasters

# Hash streams of the strata's rotations: two per lamp, two for each of the
# world's strategies, two per lamp seen in rough casters, two for the rays
# drawn from lobes toward the lamps.
_WORLD_STREAM = 1 << 16
_ROUGH_STREAM = 1 << 18
_LOBE_STREAM = 1 << 20
# A lamp that looks smaller than this (radians; the sun is 0.0093) casts
# SHADOW_PROBES shadow rays a pixel first, the rest only where they disagree.
SMALL_LAMP = math.radians(1.0)
SHADOW_PROBES = 2
# Draws of a pixel's world rays, per strategy: its strata of every eye sample;
# strategies: the cosine's, the image's and up to two lobes'.
_WORLD_DRAWS = 1 << 20
_WORLD_STRATEGIES = 4
# Directions toward the world that met something, followed on through the
# casters together.
_WORLD_BATCH = 1 << 18


@dataclass
class WorldLight:
    """The world's light at n points: irradiance (n,3) W/m^2 from it, and
    glossy (n,3) W/(m^2 sr) the radiance their specular layers reflect of
    it toward the eye."""

    irradiance: np.ndarray
    glossy: np.ndarray


def strata(ids: np.ndarray, index: np.ndarray, stream: int, seed: int) -> np.ndarray:
    """(n,2) points of the R2 sequence at `index (n,)`, rotated by a hash of
    `ids (n,)` (streams `stream` and `stream + 1`): a pixel's samples spread
    evenly over the unit square."""
    out = np.empty((len(ids), 2))
    _strata(out, np.ascontiguousarray(ids, dtype=np.int64), np.ascontiguousarray(index, dtype=np.int64),
            np.uint64(stream_key(stream, seed)), np.uint64(stream_key(stream + 1, seed)))
    return out


@kernel("void(f8[:, ::1], i8[::1], i8[::1], u8, u8)")
def _strata(out, ids, index, key_x, key_y):
    for i in range(len(ids)):
        out[i, 0], out[i, 1] = r2_point1(index[i], hash_uniform1(ids[i], key_x), hash_uniform1(ids[i], key_y))


def shadow_rays(accel: Accelerator, points: np.ndarray, facing: np.ndarray, dirs: np.ndarray, dist: np.ndarray,
                on_surface: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origins, dirs, lengths) of the shadow rays from `points (n,3)`,
    lifted off their surface (facing (n,3)), toward lamp samples `dist (n,)`
    along `dirs (n,3)`, stopping 2 epsilon short. A sample on a surface (a
    mesh light's face) is aimed at from the lifted origin itself: the ray
    along `dirs`, moved by the lift, would meet a face it grazes short of
    the sample (2% of a glowing ball's light was lost so)."""
    origins = accel.offset(points, facing, dirs)
    if on_surface:
        dirs = points + dirs * dist[:, None] - origins
        dist = np.linalg.norm(dirs, axis=1)
        dirs = dirs / np.maximum(dist, DIVISION_FLOOR)[:, None]
    return origins, dirs, dist - 2.0 * accel.epsilon


def direct_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                    shading: np.ndarray, facing: np.ndarray, view: np.ndarray, diffuse: np.ndarray,
                    lobes: list[Lobe], far: float, pixel: np.ndarray, first_stratum: np.ndarray, samples: int,
                    seed: int, adaptive: bool = True, per_pixel: int = 1) -> np.ndarray:
    """Radiance (n,3) toward the eye from all lamps' direct light.

    With `adaptive`, for a lamp that looks smaller than SMALL_LAMP, every
    point casts the first of its `samples` shadow rays, as many as make
    SHADOW_PROBES in a pixel of `per_pixel` points (one each from 2 points
    up); where all the probes of a pixel's points agree (all blocked, or
    all clear) the other samples take their verdict without a ray, and
    elsewhere they are cast (adaptive shadow sampling). The probes are
    the first strata of each point's, spread over the lamp by the R2
    sequence across the pixel's points. Such a lamp's penumbra is narrow
    (its angle times the occluder's distance): a pixel inside it sees its
    probes disagree but for a few points near its ends, where the penumbra
    comes out a little sharper; the eye pass's edge samples, which take the
    pixels across a shadow's edge, cast every ray (not `adaptive`).

    shading, facing   (n,3) shading and geometric normals, both on the eye's side
    view              (n,3) unit vectors from the points toward the eye
    diffuse           (n,3) the diffuse reflectance (under a layer, its share)
    lobes             the points' GGX lobes (material_table.layers_at); a lamp
                      hidden from glossy rays lights none (as Cycles)
    pixel, first_stratum  (n,) the pixel each point is seen in, and the
                      index of its first stratum there
    """
    n = len(points)
    out = np.zeros((n, 3))
    shading, facing = np.ascontiguousarray(shading, dtype=np.float64), np.ascontiguousarray(facing, dtype=np.float64)
    diffuse, view = np.ascontiguousarray(diffuse, dtype=np.float64), contiguous(view, np.float64)

    def lamp_sample(light: Light, number: int, k: int, count: int, rows: np.ndarray):
        """Sample k of `count` for the points `rows (m,)`: the rows lit from
        the front (l,), their directions (l,3) and distances (l,) to clear,
        and the radiance (l,3) each brings where nothing blocks it."""
        uv = strata(np.take(pixel, rows), np.take(first_stratum, rows) * count + k, 2 * number, seed)
        lamp = sample_lamp(light, energy, np.take(points, rows, axis=0), uv, far)
        idx, radiance = _lambert_lit(rows, shading, facing, diffuse, lamp.dirs, lamp.irradiance, count)
        at, dirs = rows[idx], np.take(lamp.dirs, idx, axis=0)
        if light.visibility.glossy and lobes:
            per_sample, pdf = np.take(lamp.irradiance, idx, axis=0) / count, np.take(lamp.pdf, idx)
            for lobe in lobes:
                _add_glossy(radiance, at, dirs, per_sample, pdf, shading, view, lobe.lamp_lit, *lobe.fields)
        return at, dirs, np.take(lamp.dist, idx), radiance

    def clear(at: np.ndarray, dirs: np.ndarray, dist: np.ndarray, light: Light) -> np.ndarray:
        return ~accel.occluded(*shadow_rays(accel, np.take(points, at, axis=0), np.take(facing, at, axis=0), dirs,
                                            dist, isinstance(light, MeshLight)))

    everyone = np.arange(n, dtype=np.int64)
    for number, light in enumerate(lights):
        count = 1 if radiometry.is_delta(light) else samples
        probes = min(count, -(-SHADOW_PROBES // per_pixel))
        cast, seen = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
        for k in range(probes):
            at, dirs, dist, radiance = lamp_sample(light, number, k, count, everyone)
            visible = clear(at, dirs, dist, light)
            _add_visible(out, at, visible, radiance)
            cast[at] += 1
            seen[at[visible]] += 1
        if count == probes:
            continue
        probed = cast == probes
        clear_all, blocked_all = _pixels_agree(pixel, probed & (seen == probes), probed & (seen == 0))
        agreed = (clear_all | blocked_all) & (apparent_size(light, points) < SMALL_LAMP) & adaptive
        open_sky = agreed & clear_all
        rows = np.flatnonzero(open_sky | ~agreed)
        for k in range(probes, count):
            at, dirs, dist, radiance = lamp_sample(light, number, k, count, rows)
            visible = np.take(open_sky, at)
            test = np.flatnonzero(~visible)
            visible[test] = clear(at[test], np.take(dirs, test, axis=0), dist[test], light)
            _add_visible(out, at, visible, radiance)
    for number, lobe in enumerate(lobes):
        out += lobe_drawn_lamps(accel, lights, energy, points, shading, facing, view, lobe, pixel, first_stratum,
                                samples, seed, number)
    return out


def lobe_drawn_lamps(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                     shading: np.ndarray, facing: np.ndarray, view: np.ndarray, lobe: Lobe, pixel: np.ndarray,
                     first_stratum: np.ndarray, samples: int, seed: int, number: int) -> np.ndarray:
    """Radiance (n,3) toward the eye of the lamps that rays drawn from the
    points' lamp-lit `lobe` meet, `samples` rays a point stratified over its
    pixel as the lamps' are: L f cos / (p samples) of each lamp met in front
    of what the ray meets first, times its power heuristic weight
    (seen_lamps.lamps_met); the other strategy of `direct_radiance`'s
    glossy term. Rays see the objects and lamps that glossy rays see; the
    lobe `number` of a point draws them from a stream of its own."""
    out = np.zeros((len(points), 3))
    met = [light for light in lights if light.visibility.glossy and not radiometry.is_delta(light)
           and not isinstance(light, MeshLight)]
    rows = np.flatnonzero(lobe.lamp_lit)
    if not met or not len(rows):
        return out
    normal, eye, above = (np.take(a, rows, axis=0) for a in (shading, view, facing))
    layers, tangent, bitangent = lobe.take(rows), *frames(normal)
    ids, first = np.take(pixel, rows), np.take(first_stratum, rows)
    for k in range(samples):
        dirs = layers.sample(normal, tangent, bitangent, eye,
                             strata(ids, first * samples + k, _LOBE_STREAM + 2 * number, seed))
        pdf = layers.pdf(normal, eye, dirs)
        up = np.flatnonzero((dot(dirs, normal) > 0.0) & (dot(dirs, above) > 0.0) & (pdf > 0.0))
        at, toward, density = np.take(rows, up), np.take(dirs, up, axis=0), np.take(pdf, up)
        origins = accel.offset(np.take(points, at, axis=0), np.take(facing, at, axis=0), toward)
        kind = np.full(len(up), REFLECTED)
        reach = accel.intersect(origins, toward, kind=kind).t
        radiance = lamps_met(met, energy, origins, toward, reach, kind, density)
        weight = layers.take(up).weight(np.take(normal, up, axis=0), np.take(eye, up, axis=0), toward)
        np.add.at(out, at, radiance * weight / (density * samples)[:, None])
    return out


@kernel("Tuple((i8[::1], f8[:, ::1]))(i8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], i8)")
def _lambert_lit(rows, shading, facing, diffuse, dirs, irradiance, count):
    """The lamp samples `dirs, irradiance (m,3)` of the points `rows (m,)`
    that light them from the front (idx (l,) into the m), and the Lambert
    radiance of each toward the eye, one of `count` samples:
    L = (E / count) diffuse cos(theta_l) / pi, cos(theta_l) = n_s.l at the
    shading normal; lit where n_s.l > 0, n_g.l > 0 (`facing`) and E > 0."""
    idx = np.empty(len(rows), dtype=np.int64)
    radiance = np.empty((len(rows), 3))
    lit = 0
    for j in range(len(rows)):
        r = rows[j]
        cos = shading[r, 0] * dirs[j, 0] + shading[r, 1] * dirs[j, 1] + shading[r, 2] * dirs[j, 2]
        above = facing[r, 0] * dirs[j, 0] + facing[r, 1] * dirs[j, 1] + facing[r, 2] * dirs[j, 2]
        if not (cos > 0.0 and above > 0.0 and max(irradiance[j, 0], irradiance[j, 1], irradiance[j, 2]) > 0.0):
            continue
        idx[lit] = j
        for c in range(3):
            radiance[lit, c] = irradiance[j, c] / count * (diffuse[r, c] * (cos / math.pi))
        lit += 1
    return idx[:lit].copy(), radiance[:lit].copy()


@kernel("void(f8[:, ::1], i8[::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[:, ::1], b1[::1], f8[:, ::1], "
        "f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1])")
def _add_glossy(radiance, at, dirs, irradiance, pdf, shading, view, lamp_lit, f0, eta, alpha, gain, metal, base, b):
    """radiance[j] += E_j f cos(theta_l) of the lobe at point `at[j]`
    (principled.lobe_weight1) where it is `lamp_lit`, for the lamp samples
    `dirs (l,3)` drawn with density `pdf (l,)`, E_j their irradiance
    `(l,3)` over the number of samples, times the power heuristic's weight
    against p_lobe (principled.lobe_pdf1; 1 for a density of inf, which no
    lobe's ray meets); the lobe's fields (principled.Lobe.fields) per point."""
    for j in range(len(at)):
        r = at[j]
        if not lamp_lit[r]:
            continue
        w = lobe_weight1(row(shading, r), row(view, r), row(dirs, j), row(f0, r), eta[r], alpha[r], row(gain, r),
                         row(metal, r), row(base, r), row(b, r))
        share = 1.0
        if pdf[j] < math.inf:
            share = power_heuristic1(1.0, pdf[j], 1.0, lobe_pdf1(row(shading, r), row(view, r), row(dirs, j), alpha[r]))
        for c in range(3):
            radiance[j, c] += irradiance[j, c] * (w[c] * share)


@kernel("void(f8[:, ::1], i8[::1], b1[::1], f8[:, ::1])")
def _add_visible(out, at, visible, radiance):
    """out[at[j]] += radiance[j] where `visible (l,)`."""
    for j in range(len(at)):
        if visible[j]:
            for c in range(3):
                out[at[j], c] += radiance[j, c]


def _pixels_agree(pixel: np.ndarray, clear: np.ndarray, blocked: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n,) bool each: is every point seen in the same pixel as point i
    (`pixel (n,)`) `clear (n,)`, and is every one `blocked (n,)`?"""
    _, group = np.unique(pixel, return_inverse=True)
    points = np.bincount(group)
    return (np.bincount(group, weights=clear) == points)[group], (np.bincount(group, weights=blocked) == points)[group]


def world_light(accel: Accelerator, environment: Environment, points: np.ndarray, shading: np.ndarray,
                facing: np.ndarray, view: np.ndarray, lobes: list[Lobe], far: float, pixel: np.ndarray,
                first_stratum: np.ndarray, samples: int, seed: int, sky_paths: WorldThroughCasters | None = None,
                medium: np.ndarray | None = None, surface: np.ndarray | None = None,
                chance: np.ndarray | None = None) -> tuple[WorldLight, np.ndarray]:
    """(open, through (n,3) W/(m^2 sr)): the world's light at the points,
    shadows included, in two parts: what reaches them along directions
    that meet nothing, and, given `sky_paths`, the radiance their lobes
    reflect of the sky through the casters (world_paths.py; a ray leaves
    triangle `surface (n,)` inside object `medium (n,)`), else 0; the
    irradiance through the casters is the maps' (emission/sky_lamps.py). A shadow ray finds
    the directions that meet something first; those of point i are
    followed with probability `chance[i]`, 0 for none (Russian roulette:
    what they bring is divided by it),
    _WORLD_BATCH or so at a time (one bounce.trace for them all: its calls
    cost more than its rays). `samples` directions of each strategy per
    point, the cosine's, the image's and each of the `lobes`' (material_table.layers_at):
    `_world_directions` weighs them, `_add_world` adds what each brings to the
    irradiance, and `_add_lobe_light` to the glossy part through each lobe."""
    n = len(points)
    seen_light, through = WorldLight(np.zeros((n, 3)), np.zeros((n, 3))), np.zeros((n, 3))
    image = environment.world.environment is not None
    shading, facing = contiguous(shading, np.float64), contiguous(facing, np.float64)
    view = contiguous(view, np.float64)
    tangent, bitangent = frames(shading) if lobes else (None, None)

    def add_glossy(out: np.ndarray, idx, seen, toward, light, density) -> None:
        if not lobes:
            return
        rows = np.flatnonzero(seen)
        at, toward = np.take(idx, rows), contiguous(np.take(toward, rows, axis=0), np.float64)
        radiance = contiguous(light, np.float64) / (np.take(density, rows) * samples)[:, None]
        for lobe in lobes:
            _add_lobe_light(out, at, toward, radiance, shading, view, *lobe.fields)

    def add(idx, seen, toward, light, density, cos) -> None:
        _add_world(seen_light.irradiance, idx, seen, contiguous(light, np.float64), density, cos, samples)
        add_glossy(seen_light.glossy, idx, seen, toward, light, density)

    blocked = []

    def follow() -> None:
        """The blocked directions gathered so far, each followed on through
        the casters with its point's chance (one trace for them all), added
        to the open light or, through the casters, to the lobes' light."""
        if not blocked:
            return
        at, origins, toward, density, cos, draws = (np.concatenate(c) for c in zip(*blocked))
        blocked.clear()
        kept = np.flatnonzero(hash_uniform(draws, _WORLD_STREAM + 6, seed) < np.take(chance, at))
        at, origins, toward, density, cos, draws = (np.take(a, kept, axis=0)
                                                    for a in (at, origins, toward, density, cos, draws))
        # a followed direction stands for 1 / chance of its kind
        density = density * np.take(chance, at)
        clear, met, behind = sky_paths.light(origins, toward, np.take(medium, at), np.take(surface, at), draws)
        add(at, clear, toward, environment.light(np.take(toward, np.flatnonzero(clear), axis=0)), density, cos)
        add_glossy(through, at, met, toward, np.take(behind, np.flatnonzero(met), axis=0), density)

    nowhere = np.zeros(0, dtype=bool)
    for k in range(samples):
        index = first_stratum * samples + k
        drawn = [(cosine_hemisphere(shading, strata(pixel, index, _WORLD_STREAM, seed)), nowhere)]
        if image:
            drawn.append((environment.sample(strata(pixel, index, _WORLD_STREAM + 2, seed))[0], nowhere))
        for number, lobe in enumerate(lobes):
            uv = strata(pixel, index, _world_lobe_stream(number), seed)
            drawn.append((lobe.sample(shading, tangent, bitangent, view, uv), lobe.active))
        for strategy, (dirs, own) in enumerate(drawn):
            dirs = contiguous(dirs, np.float64)
            others = contiguous(environment.density(dirs), np.float64) if image else np.zeros(n)
            for lobe in lobes:
                others = others + lobe.pdf(shading, view, dirs)
            idx, density, cos = _world_directions(shading, facing, dirs, others, own)
            if len(idx) == 0:
                continue
            toward = np.take(dirs, idx, axis=0)
            origins = accel.offset(np.take(points, idx, axis=0), np.take(facing, idx, axis=0), toward)
            seen = ~accel.occluded(origins, toward, np.full(len(idx), far))
            add(idx, seen, toward, environment.light(np.take(toward, np.flatnonzero(seen), axis=0)), density, cos)
            if sky_paths is not None and not seen.all():
                rows = np.flatnonzero(~seen & (np.take(chance, idx) > 0))
                at = np.take(idx, rows)
                draws = (np.take(pixel, at) * _WORLD_DRAWS + np.take(index, at)) * _WORLD_STRATEGIES + strategy
                blocked.append((at, *(np.take(a, rows, axis=0) for a in (origins, toward, density, cos)), draws))
                if sum(len(b[0]) for b in blocked) >= _WORLD_BATCH:
                    follow()
    follow()
    return seen_light, through


def _world_lobe_stream(number: int) -> int:
    """The hash streams of the world's directions drawn from lobe `number`."""
    return _WORLD_STREAM + 4 if number == 0 else _WORLD_STREAM + 6 + 2 * number


@kernel("Tuple((i8[::1], f8[::1], f8[::1]))(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], b1[::1])")
def _world_directions(shading, facing, dirs, others, own):
    """The world's sample directions `dirs (n,3)` at the points that take
    them, idx (l,), with the density (l,) all strategies draw each by and
    its cosine (l,) at the shading normal: the balance heuristic's sum
    (Veach 1997) of cos(theta) / pi and the other strategies' densities
    `others (n,)` (the image's, and each lobe's, principled.Lobe.pdf). A
    direction counts above both normals with a density, and where drawn
    from a lobe (`own (n,)`, (0,) otherwise) at the lobe's own points only."""
    n = len(dirs)
    idx, density, cos = np.empty(n, dtype=np.int64), np.empty(n), np.empty(n)
    lit = 0
    for i in range(n):
        d, normal = row(dirs, i), row(shading, i)
        c = dot1(normal, d)
        p = max(c, 0.0) / math.pi + others[i]
        if not (c > 0.0 and dot1(row(facing, i), d) > 0.0 and p > 0.0) or (len(own) and not own[i]):
            continue
        idx[lit], density[lit], cos[lit] = i, p, c
        lit += 1
    return idx[:lit].copy(), density[:lit].copy(), cos[:lit].copy()


@kernel("void(f8[:, ::1], i8[::1], b1[::1], f8[:, ::1], f8[::1], f8[::1], i8)")
def _add_world(irradiance, idx, seen, light, density, cos, samples):
    """For each of the directions at points `idx (l,)` that the shadow
    rays found `seen`, the world's radiance `light (s,3)` (the seen ones in
    order) over its `density (l,)` and the `samples`:
    irradiance[i] += L cos / (p samples)."""
    m = 0
    for j in range(len(idx)):
        if not seen[j]:
            continue
        i = idx[j]
        for c in range(3):
            irradiance[i, c] += light[m, c] / (density[j] * samples) * cos[j]
        m += 1


@kernel("void(f8[:, ::1], i8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], "
        "f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1])")
def _add_lobe_light(glossy, at, toward, radiance, shading, view, f0, eta, alpha, gain, metal, base, b):
    """glossy[at[j]] += L_j f cos(theta_l) of the lobe at point `at[j]`
    (principled.lobe_weight1) for light `radiance (l,3)` (over its density
    and the samples) from the unit directions `toward (l,3)`; the lobe's
    fields (principled.Lobe.fields) per point."""
    for j in range(len(at)):
        i = at[j]
        w = lobe_weight1(row(shading, i), row(view, i), row(toward, j), row(f0, i), eta[i], alpha[i], row(gain, i),
                         row(metal, i), row(base, i), row(b, i))
        for c in range(3):
            glossy[i, c] += radiance[j, c] * w[c]


def rough_specular_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                            shading: np.ndarray, facing: np.ndarray, view: np.ndarray, alpha: np.ndarray,
                            eta: np.ndarray, mirror: np.ndarray, tints: tuple[np.ndarray, np.ndarray], far: float,
                            pixel: np.ndarray, first_stratum: np.ndarray, samples: int, seed: int,
                            branches_traced: bool = True) -> np.ndarray:
    """Radiance (n,3) toward the eye from all lamps' direct light at points
    of rough casters: each lamp sample's irradiance times the GGX
    interface's f |cos| (optics.microfacet.bsdf_cosine1) and the tint of
    what it does there, what Cycles adds at a glossy or glass closure by
    next-event estimation; where the eye pass traces the rays its bounce
    draws there (`branches_traced`), which meet the lamps too, weighed
    against them by multiple importance sampling (`_rough_lit`). A lamp on the far side of glass (`eta (n,)`
    eta_view / eta_lamp, not a `mirror (n,)`) shines through it, its
    radiance scaled as the eye's refracted rays' (specular.radiance_scale1);
    shadow rays as in direct_radiance.

    shading, facing   (n,3) shading and geometric normals, both on the eye's side
    view              (n,3) unit vectors from the points toward the eye
    alpha             (n,) GGX width, > 0
    tints             (reflection, transmission), each (n,3), the colours
                      of a reflected and a transmitted lamp sample
    """
    out = np.zeros((len(points), 3))
    shading, facing, view = (contiguous(a, np.float64) for a in (shading, facing, view))
    alpha, eta, mirror = contiguous(alpha, np.float64), contiguous(eta, np.float64), contiguous(mirror, bool)
    for number, light in enumerate(lights):
        count = 1 if radiometry.is_delta(light) else samples
        for k in range(count):
            uv = strata(pixel, first_stratum * count + k, _ROUGH_STREAM + 2 * number, seed)
            lamp = sample_lamp(light, energy, points, uv, far)
            pdf = lamp.pdf if branches_traced else np.full(len(points), np.inf)
            idx, dirs, radiance = _rough_lit(facing, shading, view, contiguous(lamp.dirs, np.float64),
                                             contiguous(lamp.irradiance, np.float64), pdf, alpha, eta, mirror,
                                             *tints, count, light.visibility.glossy, light.visibility.transmission)
            if len(idx) == 0:
                continue
            blocked = accel.occluded(*shadow_rays(accel, np.take(points, idx, axis=0), np.take(facing, idx, axis=0),
                                                  dirs, np.take(lamp.dist, idx), isinstance(light, MeshLight)))
            _add_visible(out, idx, contiguous(~blocked, bool), radiance)
    return out


@kernel("Tuple((i8[::1], f8[:, ::1], f8[:, ::1]))(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], "
        "f8[::1], f8[::1], f8[::1], b1[::1], f8[:, ::1], f8[:, ::1], i8, b1, b1)")
def _rough_lit(facing, shading, view, dirs, irradiance, pdf, alpha, eta, mirror, reflection_tint, transmission_tint,
               count, glossy, transmission):
    """The lamp samples `dirs, irradiance (n,3)` that light the rough points
    through their GGX interface (idx (l,)), their directions (l,3) and the
    radiance (l,3) each brings toward the eye, one of `count` samples:
    E f |cos| / count (optics.microfacet.bsdf_cosine1) times the tint,
    where f |cos| > 0; a transmitted sample times radiance_scale1 too, and
    each of density `pdf (n,)` times the power heuristic's weight, `count`
    of them against p_branch of the one ray the eye pass's bounce
    draws there (optics.microfacet.branch_pdf1; 1 for a density of inf,
    which no such ray meets).
    A sample counts on the eye's side of both normals if the lamp is seen
    by `glossy` rays, or, but at a `mirror`, behind both if by
    `transmission` rays (its Ray Visibility, as Cycles' next-event
    estimation honours it), and where E > 0."""
    n = len(dirs)
    idx, toward, radiance = np.empty(n, dtype=np.int64), np.empty((n, 3)), np.empty((n, 3))
    lit = 0
    for i in range(n):
        d = row(dirs, i)
        above, along = dot1(row(facing, i), d), dot1(row(shading, i), d)
        sides = ((above > 0.0 and along > 0.0 and glossy)
                 or (above < 0.0 and along < 0.0 and not mirror[i] and transmission))
        if not (sides and max_channel1(row(irradiance, i)) > 0.0):
            continue
        f = bsdf_cosine1(row(view, i), d, row(shading, i), alpha[i], eta[i], mirror[i])
        if not f > 0.0:
            continue
        idx[lit] = i
        set_row(toward, lit, d)
        through = along < 0.0
        tint = row(transmission_tint, i) if through else row(reflection_tint, i)
        share = 1.0
        if pdf[i] < math.inf:
            branch = branch_pdf1(row(view, i), d, row(shading, i), alpha[i], eta[i])
            share = power_heuristic1(count, pdf[i], 1.0, branch)
        scale = f / count * share * (radiance_scale1(eta[i]) if through else 1.0)
        for c in range(3):
            radiance[lit, c] = irradiance[i, c] * (tint[c] * scale)
        lit += 1
    return idx[:lit].copy(), toward[:lit].copy(), radiance[:lit].copy()
