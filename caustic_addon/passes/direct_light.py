"""Direct light at opaque surface points and at rough casters, with shadow rays: from each lamp
(emission/lamp_samples.py) and from the world.

Radiance leaving a point toward the eye v, per sample of a lamp bringing
irradiance E at normal incidence along the unit vector l:

    L = E cos(theta_l) diffuse / pi + E f_s(v, l) cos(theta_l)

the Lambert term of the diffuse base (what a Cycles Diffuse BSDF returns;
under a Principled BSDF's specular layer, its base colour times the share
the layer leaves it) plus the layer's GGX lobe (optics/principled.py). A
lamp of size 0 takes one sample; a lamp with a size takes `samples`,
stratified over a pixel: eye sample s of a pixel uses points s K .. s K +
K - 1 of the R2 sequence, rotated by a hash of the pixel. A lamp that
looks smaller than a degree (a sun, a small lamp far off) casts a few of
them first, at least two a pixel, and the rest only where a pixel's
points disagree (`direct_radiance`). A sample behind the surface gets no shadow ray.
Dielectrics and reflectors block shadow rays: the light they redirect
arrives through the illumination maps.
Rough casters show the lamps' highlights (`rough_specular_radiance`), as
Cycles' glossy and glass closures do.

The world lights a surface with E = int L(w) V(w) cos(theta) dw over the
hemisphere, and its lobe with int L(w) V(w) f_s(v, w) cos(theta) dw, what
Cycles computes with bounces at 0. Both are estimated from the same
directions, drawn by cos(theta) / pi (Malley), for an image by the world's
radiance (environment.py), and where there is a lobe by its visible normals
(Heitz 2018), weighted by the balance heuristic (Veach 1997)."""

from __future__ import annotations

import math

import numpy as np

from ..emission import radiometry
from ..emission.environment import Environment
from ..emission.lamp_samples import apparent_size, sample_lamp
from ..optics.microfacet import bsdf_cosine
from ..optics.principled import Lobe
from ..sampling.hash import hash_uniform1, stream_key
from ..sampling.sequences import r2_point1
from ..sampling.warps import cosine_hemisphere, frames
from ..scene import Light
from ..tracing.accelerator import Accelerator
from ..util.jit import kernel
from ..util.vectors import dot, max_channel

# Hash streams of the strata's rotations: two per lamp, two for each of the
# world's strategies, two per lamp seen in rough casters.
_WORLD_STREAM = 1 << 16
_ROUGH_STREAM = 1 << 18
# A lamp that looks smaller than this (radians; the sun is 0.0093) casts
# SHADOW_PROBES shadow rays a pixel first, the rest only where they disagree.
SMALL_LAMP = math.radians(1.0)
SHADOW_PROBES = 2


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


def direct_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                    shading: np.ndarray, facing: np.ndarray, view: np.ndarray, diffuse: np.ndarray,
                    lobe: Lobe | None, far: float, pixel: np.ndarray, first_stratum: np.ndarray, samples: int,
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
    lobe              the points' specular layers, or None
    pixel, first_stratum  (n,) the pixel each point is seen in, and the
                      index of its first stratum there
    """
    n = len(points)
    out = np.zeros((n, 3))
    shading, facing = np.ascontiguousarray(shading, dtype=np.float64), np.ascontiguousarray(facing, dtype=np.float64)
    diffuse = np.ascontiguousarray(diffuse, dtype=np.float64)

    def lamp_sample(light: Light, number: int, k: int, count: int, rows: np.ndarray):
        """Sample k of `count` for the points `rows (m,)`: the rows lit from
        the front (l,), their directions (l,3) and distances (l,) to clear,
        and the radiance (l,3) each brings where nothing blocks it."""
        uv = strata(np.take(pixel, rows), np.take(first_stratum, rows) * count + k, 2 * number, seed)
        lamp = sample_lamp(light, energy, np.take(points, rows, axis=0), uv, far)
        # a lamp's samples may be read-only broadcasts of one direction or irradiance
        lamp_dirs = np.require(lamp.dirs, np.float64, ["C", "W"])
        irradiance = np.require(lamp.irradiance, np.float64, ["C", "W"])
        idx, radiance = _lambert_lit(rows, shading, facing, diffuse, lamp_dirs, irradiance, count)
        at, dirs = rows[idx], np.take(lamp_dirs, idx, axis=0)
        if lobe is not None:
            glossy = np.flatnonzero(lobe.lamp_lit[at])
            radiance[glossy] += np.take(irradiance, idx[glossy], axis=0) / count * lobe.take(at[glossy]).weight(
                np.take(shading, at[glossy], axis=0), np.take(view, at[glossy], axis=0), np.take(dirs, glossy, axis=0))
        return at, dirs, np.take(lamp.dist, idx), radiance

    def clear(at: np.ndarray, dirs: np.ndarray, dist: np.ndarray) -> np.ndarray:
        origins = accel.offset(np.take(points, at, axis=0), np.take(facing, at, axis=0), dirs)
        return ~accel.occluded(origins, dirs, dist - 2.0 * accel.epsilon)

    everyone = np.arange(n, dtype=np.int64)
    for number, light in enumerate(lights):
        count = 1 if radiometry.is_delta(light) else samples
        probes = min(count, -(-SHADOW_PROBES // per_pixel))
        cast, seen = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
        for k in range(probes):
            at, dirs, dist, radiance = lamp_sample(light, number, k, count, everyone)
            visible = clear(at, dirs, dist)
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
            visible[test] = clear(at[test], np.take(dirs, test, axis=0), dist[test])
            _add_visible(out, at, visible, radiance)
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
                facing: np.ndarray, view: np.ndarray, lobe: Lobe | None, far: float, pixel: np.ndarray,
                first_stratum: np.ndarray, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(irradiance (n,3) W/m^2, glossy (n,3) W/(m^2 sr)) the world brings
    the points, shadows included, and the radiance their specular layers
    (`lobe`, or None) reflect of it toward `view (n,3)`, from `samples`
    directions of each strategy per point."""
    n = len(points)
    irradiance, glossy = np.zeros((n, 3)), np.zeros((n, 3))
    image = environment.world.environment is not None
    tangent, bitangent = frames(shading) if lobe is not None else (None, None)
    for k in range(samples):
        index = first_stratum * samples + k
        drawn = [(cosine_hemisphere(shading, strata(pixel, index, _WORLD_STREAM, seed)), None)]
        if image:
            drawn.append((environment.sample(strata(pixel, index, _WORLD_STREAM + 2, seed))[0], None))
        if lobe is not None:
            drawn.append((lobe.sample(shading, tangent, bitangent, view, strata(pixel, index, _WORLD_STREAM + 4, seed)),
                          lobe.active))
        for dirs, among in drawn:
            cos = dot(shading, dirs)
            density = np.maximum(cos, 0.0) / math.pi + (environment.density(dirs) if image else 0.0)
            if lobe is not None:
                density = density + lobe.pdf(shading, view, dirs)
            valid = (cos > 0.0) & (dot(facing, dirs) > 0.0) & (density > 0.0)
            idx = np.flatnonzero(valid if among is None else valid & among)
            if len(idx) == 0:
                continue
            toward = np.take(dirs, idx, axis=0)
            seen = ~accel.occluded(accel.offset(np.take(points, idx, axis=0), np.take(facing, idx, axis=0), toward),
                                   toward, np.full(len(idx), far))
            idx, toward = idx[seen], toward[seen]
            radiance = environment.light(toward) / (density[idx] * samples)[:, None]
            irradiance[idx] += radiance * cos[idx][:, None]
            if lobe is not None:
                glossy[idx] += radiance * lobe.take(idx).weight(np.take(shading, idx, axis=0),
                                                                 np.take(view, idx, axis=0), toward)
    return irradiance, glossy


def rough_specular_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                            shading: np.ndarray, facing: np.ndarray, view: np.ndarray, alpha: np.ndarray,
                            eta: np.ndarray, mirror: np.ndarray, far: float, pixel: np.ndarray,
                            first_stratum: np.ndarray, samples: int, seed: int) -> np.ndarray:
    """Radiance (n,3) toward the eye from all lamps' direct light at points
    of rough casters, before their tint: each lamp sample's irradiance
    times the GGX interface's f |cos| (optics.microfacet.bsdf_cosine), what
    Cycles adds at a glossy or glass closure by next-event estimation. A
    lamp on the far side of glass (`eta (n,)` eta_view / eta_lamp, not a
    `mirror (n,)`) shines through it; shadow rays as in direct_radiance.

    shading, facing   (n,3) shading and geometric normals, both on the eye's side
    view              (n,3) unit vectors from the points toward the eye
    alpha             (n,) GGX width, > 0
    """
    out = np.zeros((len(points), 3))
    for number, light in enumerate(lights):
        count = 1 if radiometry.is_delta(light) else samples
        for k in range(count):
            uv = strata(pixel, first_stratum * count + k, _ROUGH_STREAM + 2 * number, seed)
            lamp = sample_lamp(light, energy, points, uv, far)
            above, along = dot(facing, lamp.dirs), dot(shading, lamp.dirs)
            sides = ((above > 0.0) & (along > 0.0)) | ((above < 0.0) & (along < 0.0) & ~mirror)
            idx = np.flatnonzero(sides & (max_channel(lamp.irradiance) > 0.0))
            dirs = np.take(lamp.dirs, idx, axis=0)
            f = bsdf_cosine(np.take(view, idx, axis=0), dirs, np.take(shading, idx, axis=0), alpha[idx], eta[idx],
                            mirror[idx])
            idx, dirs, f = idx[f > 0.0], dirs[f > 0.0], f[f > 0.0]
            if len(idx) == 0:
                continue
            origins = accel.offset(np.take(points, idx, axis=0), np.take(facing, idx, axis=0), dirs)
            blocked = accel.occluded(origins, dirs, np.take(lamp.dist, idx) - 2.0 * accel.epsilon)
            idx, f = idx[~blocked], f[~blocked]
            out[idx] += np.take(lamp.irradiance, idx, axis=0) * (f / count)[:, None]
    return out
