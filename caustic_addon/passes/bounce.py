"""The one bounce every pass makes, photons, beam vertices and eye rays
alike: cast, attenuate inside a medium, arrive at an opaque surface, or
orient the normals at a specular one (a dielectric or a reflector) and
reflect or refract. The passes differ only in what they do on arrival, with
the paths that leave the scene, and in how they scatter: one branch chosen
by its Fresnel probability (photons), or both branches with their Fresnel
weights (beams, eye rays). A reflector is a surface whose Fresnel
reflectance is 1: it always reflects, and its colour is its reflectance.

A rough surface scatters about a GGX microfacet normal that each pass draws
for each path (`facets`, from the pass's own random numbers) instead of
the shading normal, as Cycles' `bsdf_microfacet_sample` does: Fresnel at the
microfacet normal, the path's weight times G2/G1 and Multiscatter GGX's
factor (`multiscatter`), and a path that leaves on the wrong side of the
macro surface ends.

Between Embree's casts a bounce runs a few kernels (util.jit) over its
rows: Embree's output decoded into Hits (tracing.accelerator), each path's
fate and Beer-Lambert (`_arrivals`), the normals and Fresnel (`_oriented`),
both branches with their origins (`_branches`), and at a rough surface its
microfacet normals (`_facets`) and multiscatter factors
(`_multiscatter_factors`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from ..optics.media import beer_lambert1
from ..optics.microfacet import branch_pdf1, shadowing_weight1, visible_normal_about1
from ..optics.multiscatter import albedo_at1, multiscatter_factor1
from ..optics.specular import (basic_irradiance_scale, fresnel_dielectric1, radiance_scale1, reflect1, refract1,
                               valid_reflection_normal1)
from ..sampling.hash import hash_uniform1
from ..sampling.warps import concentric_disc1, orthonormal_basis1
from ..scene.material_table import MATERIAL_TYPES, Materials
from ..tracing.accelerator import GEOMETRY_TYPES, REFLECTED, REFRACTED, Accelerator, offset1
from ..tracing.hits import HIT_TYPES, MISS, Hits, inside1
from ..tracing.triangles import normals1
from ..util.jit import inline, kernel, named_kernel
from ..util.rows import contiguous, partition, take_rows
from ..util.vectors import dot1, max_channel1, normalize1, row, scale1, set_row
from .differentials import branch_differentials
from .interface import INTERFACE_TYPES, Interface
from .paths import MIN_BRANCH_WEIGHT, PATH_TYPES, Paths

_FAMILY_PRIME = np.uint64(0x100000001B3)
_ID_PRIME = np.uint64(0x9E3779B97F4A7C15)
# The family bit of a beam path scattered at a rough surface: its family is
# its own (its grid key is in it), so it bounds no beam with its neighbours.
SCATTERED = np.uint64(1 << 63)
# What became of a path at its hit (trace): it left the scene, arrived at an
# opaque surface, or met a specular one.
_ESCAPED, _ARRIVED, _SPECULAR = 0, 1, 2


@inline
def oriented1(d, face, shading):
    """(facing, shading): the geometric normal `face` turned against the
    ray `d`, and the shading normal put on its side and raised toward it
    where its mirror reflection of the ray would not leave the surface
    (optics.specular.valid_reflection_normal1), as Cycles sets up a glass's,
    a mirror's or a metal's normal."""
    facing = face if dot1(d, face) < 0.0 else scale1(-1.0, face)
    if dot1(shading, facing) < 0.0:
        shading = scale1(-1.0, shading)
    return facing, valid_reflection_normal1(facing, scale1(-1.0, d), shading)


@inline
def reflectance1(reflector, reflects, cos_i, eta):
    """The share of light an interface reflects: all at a reflector,
    none where its Fresnel is none (a Refraction BSDF), else exact Fresnel."""
    if reflector:
        return 1.0
    return fresnel_dielectric1(cos_i, eta) if reflects else 0.0


@inline
def index_of1(ior, medium, band):
    """The index of refraction of `medium` (an object, MISS: air, 1) in
    wavelength band `band`, from `ior (m,K)`."""
    n = ior[max(medium, 0), band]
    return 1.0 if medium == MISS else n


@inline
def crossing1(medium, outer, obj, toward, closed, body):
    """(entered, beyond, beneath, real) of a ray inside `medium` over
    `outer` (Paths) that meets a surface of object `obj`, `toward` its
    front (against its outward normal).

    Closed objects nest (Schmidt and Budge 2002, "Simple nested dielectrics
    in ray traced images", without priorities): a ray enters `obj` unless it
    is inside its body already, and is then in `obj` over `medium`; leaving
    `medium` it is back in `outer`. Leaving `outer` while inside `medium`
    (a tumbler's wall met inside the whisky that overlaps it) changes no
    medium's light, so the crossing is not `real`: it neither bends nor
    reflects. An open mesh's side is its normal's."""
    in_medium, in_outer, solid = inside1(medium, obj, body), inside1(outer, obj, body), closed[obj]
    if not solid:
        if toward:
            return True, obj, medium, True
        return False, (outer if in_medium else MISS), MISS, True
    if in_medium:
        return False, outer, MISS, True
    if in_outer:
        return False, medium, MISS, False
    return True, obj, medium, True


@named_kernel("void", PATH_TYPES, HIT_TYPES, INTERFACE_TYPES, MATERIAL_TYPES, GEOMETRY_TYPES,
              {"ior": "f8[:, ::1]", "reflects": "b1[::1]", "roughness": "f8[::1]"})
def _oriented(prim, u, v, obj, dirs, medium, outer, band, triangles, closed, body, ior, reflector,
              reflects, roughness, facing, shading, entering, eta, fresnel, alpha, beyond, beneath):
    """orient's rows: `ior (m,K)` per object and band, `band (n,)` each
    row's; `reflects (m,)` False where an object's Fresnel is none;
    `roughness (m,)` each object's GGX alpha. eta is the index of the
    medium the ray is in over that of the one beyond (index_of1); a
    crossing that is not real has eta 1, no Fresnel and no roughness."""
    for i in range(len(prim)):
        d, o = row(dirs, i), obj[i]
        face, normal = normals1(triangles, o, prim[i], u[i], v[i])
        entered, over, under, real = crossing1(medium[i], outer[i], o, dot1(d, face) < 0.0, closed, body)
        f, s = oriented1(d, face, normal)
        e = index_of1(ior, medium[i] if entered else o, band[i]) / index_of1(ior, over, band[i])
        set_row(facing, i, f)
        set_row(shading, i, s)
        entering[i], beyond[i], beneath[i] = entered, over, under
        eta[i] = e if real else 1.0
        alpha[i] = roughness[o] if real else 0.0
        fresnel[i] = reflectance1(reflector[o], reflects[o], -dot1(d, s), eta[i]) if real else 0.0


def orient(accel: Accelerator, hits: Hits, dirs: np.ndarray, materials: Materials, medium: np.ndarray,
           outer: np.ndarray, band=None) -> Interface:
    """Orient the hits' normals against `dirs (n,3)` and evaluate Fresnel
    (reflectance1: 1 at reflectors, which reflect everything). Dielectrics refract with
    their IOR in wavelength band `band` ((n,) per ray), or at 587.6 nm (n_d)
    when it is None, over that of the medium on the ray's side.

    Entering or leaving: for a closed mesh, the ray's own state `medium,
    outer (n,)` (the objects it is inside, or MISS; any object of the same
    body counts) decides, since a hit at an edge or a grazing hit can land
    on a face whose normal says otherwise (crossing1); for an open mesh, the
    outward geometric normal does (dot(d, n) < 0 means entering). The
    normals: oriented1.

    A ray that leaves closed glass for the air and enters other closed
    glass or water at once (their surfaces coincide, or lie a hair apart:
    tracing/joins.py) crosses one interface, of the ratio of their indices,
    as light does where a liquid wets its glass."""
    n = len(hits.prim)
    facing, shading = np.empty((n, 3)), np.empty((n, 3))
    entering, eta, fresnel, alpha = np.empty(n, dtype=bool), np.empty(n), np.empty(n), np.empty(n)
    beyond, beneath = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    ior = materials.ior[:, None] if band is None else materials.ior_bands
    band = np.zeros(n, dtype=np.int64) if band is None else contiguous(band, np.int64)
    _oriented(prim=contiguous(hits.prim, np.int64), u=contiguous(hits.u, np.float64), v=contiguous(hits.v, np.float64),
              obj=contiguous(hits.obj, np.int64), dirs=contiguous(dirs, np.float64),
              medium=contiguous(medium, np.int64), outer=contiguous(outer, np.int64), band=band,
              triangles=accel.triangles, closed=accel.closed, body=accel.body,
              ior=contiguous(ior, np.float64), reflector=materials.reflector, reflects=materials.fresnel,
              roughness=contiguous(materials.alpha, np.float64), facing=facing, shading=shading, entering=entering,
              eta=eta, fresnel=fresnel, alpha=alpha, beyond=beyond, beneath=beneath)
    joined = np.full(n, MISS, dtype=np.int64)
    if accel.joins.partners:
        _join(accel, hits, contiguous(dirs, np.float64), materials, ior, band, entering, beyond, eta, fresnel,
              shading, joined)
    return Interface(hits.points, facing, shading, entering, eta, fresnel, alpha, shading, beyond, beneath, joined)


def _join(accel: Accelerator, hits: Hits, dirs: np.ndarray, materials: Materials, ior: np.ndarray, band: np.ndarray,
          entering: np.ndarray, beyond: np.ndarray, eta: np.ndarray, fresnel: np.ndarray, shading: np.ndarray,
          joined: np.ndarray) -> None:
    """orient's rows that leave closed glass for the air where other glass
    or water lies against it (Accelerator.joins): they go into that one,
    their eta and Fresnel those of the two indices. Changes the arrays in place."""
    rows = np.flatnonzero(~entering & (beyond == MISS) & accel.joins.has_partners[hits.obj])
    if len(rows) == 0:
        return
    found = accel.joins.entered(np.take(hits.obj, rows), np.take(hits.prim, rows), np.take(hits.points, rows, axis=0),
                               np.take(dirs, rows, axis=0))
    rows, found = rows[found != MISS], found[found != MISS]
    _joined(rows, found, contiguous(hits.obj, np.int64), dirs, contiguous(ior, np.float64), band, shading,
            materials.reflector, materials.fresnel, beyond, eta, fresnel, joined)


@kernel("void(i8[::1], i8[::1], i8[::1], f8[:, ::1], f8[:, ::1], i8[::1], f8[:, ::1], b1[::1], b1[::1], i8[::1], "
        "f8[::1], f8[::1], i8[::1])")
def _joined(rows, found, obj, dirs, ior, band, shading, reflector, reflects, beyond, eta, fresnel, joined):
    """_join's rows `rows (k,)`, each going into object `found (k,)`."""
    for j in range(len(rows)):
        i, o, w = rows[j], obj[rows[j]], found[j]
        beyond[i], joined[i] = w, w
        eta[i] = ior[o, band[i]] / ior[w, band[i]]
        fresnel[i] = reflectance1(reflector[o], reflects[o], -dot1(row(dirs, i), row(shading, i)), eta[i])


def facets(surface: Interface, dirs: np.ndarray, materials: Materials, obj: np.ndarray,
           uv: np.ndarray) -> Interface:
    """`surface` with each rough row's scattering normal drawn from the GGX
    normals visible from the ray `dirs (n,3)` at objects `obj (n,)`, by
    `uv (n,2)` in [0,1)^2 through the concentric disc, in the frame
    (sampling.warps.orthonormal_basis1) of the shading normal
    (optics.microfacet.visible_normal_about1), and its Fresnel there
    (reflectance1). Smooth rows are left as they are."""
    rough = np.flatnonzero(surface.rough)
    if len(rough) == 0:
        return surface
    scattering, fresnel = contiguous(surface.scattering, np.float64).copy(), surface.fresnel.copy()
    _facets(rough, contiguous(dirs, np.float64), contiguous(surface.shading, np.float64), contiguous(uv, np.float64),
            contiguous(surface.alpha, np.float64), contiguous(surface.eta, np.float64), materials.reflector,
            materials.fresnel, contiguous(obj, np.int64), scattering, fresnel)
    return replace(surface, fresnel=fresnel, scattering=scattering)


@kernel("void(i8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], b1[::1], b1[::1], i8[::1], f8[:, ::1], "
        "f8[::1])")
def _facets(rough, dirs, shading, uv, alpha, eta, reflector, reflects, obj, scattering, fresnel):
    """facets' rough rows `rough (m,)`."""
    for j in range(len(rough)):
        i = rough[j]
        d, normal = row(dirs, i), row(shading, i)
        tangent, bitangent = orthonormal_basis1(normal)
        x, y = concentric_disc1(uv[i, 0], uv[i, 1])
        h = visible_normal_about1(scale1(-1.0, d), normal, tangent, bitangent, alpha[i], x, y)
        set_row(scattering, i, h)
        fresnel[i] = reflectance1(reflector[obj[i]], reflects[obj[i]], -dot1(d, h), eta[i])


def multiscatter(surface: Interface, materials: Materials, obj: np.ndarray, dirs: np.ndarray, out: np.ndarray,
                 crossed: np.ndarray, carries_light: bool) -> np.ndarray:
    """(n,3) Multiscatter GGX's factor (optics.multiscatter) for rays
    `dirs (n,3)` that left rough rows of `surface` along `out (n,3)`,
    `crossed (n,)` where they went through; 1 where smooth or plain GGX.

    Cycles takes the factor on the eye's side of the bounce: at the cosine
    of the direction toward the camera, from the table of the side that
    direction is on (`microfacet_ggx_preserve_energy`, with the IOR of the
    camera ray's side). For eye rays that is where they come from; for
    light (photons, beam vertices, `carries_light`) it is where it goes, so
    the caustic is the one Cycles' camera paths gather. The factor is not
    reciprocal: taken on the light's side instead, a white surface would
    give back exactly the flux each photon brings; the two sides' tables
    differ, at Roughness 0.4 and 60 degrees E is 0.91 leaving glass and
    0.98 entering it."""
    factor = np.ones((len(dirs), 3))
    rough = np.flatnonzero(surface.rough)
    if len(rough) == 0:
        return factor
    _multiscatter_factors(rough, contiguous(obj, np.int64), contiguous(surface.entering, bool),
                          contiguous(crossed, bool), contiguous(out if carries_light else dirs, np.float64),
                          contiguous(surface.shading, np.float64), carries_light, materials.facet_albedo,
                          materials.facet_albedo_avg, materials.energy_tint, factor)
    return factor


@kernel("void(i8[::1], i8[::1], b1[::1], b1[::1], f8[:, ::1], f8[:, ::1], b1, f8[:, :, ::1], f8[:, ::1], "
        "f8[:, ::1], f8[:, ::1])")
def _multiscatter_factors(rough, obj, entering, crossed, toward, shading, carries_light, albedo, albedo_avg, color,
                          factor):
    """multiscatter's rough rows: `toward (n,3)` the rays' directions
    toward the eye, or away from it (only |cos| counts); the tables
    `albedo (objects,2,k)` and `albedo_avg (objects,2)` by side (0 outside)."""
    for i in rough:
        o = obj[i]
        side = 0 if entering[i] else 1
        if carries_light and crossed[i]:
            side = 1 - side
        mu = abs(dot1(row(toward, i), row(shading, i)))
        set_row(factor, i, multiscatter_factor1(albedo_at1(albedo[o, side], mu), albedo_avg[o, side], row(color, o)))


@inline
def turned1(d, n, eta, mirror):
    """(out, mirror): `d` reflected about `n` if `mirror`, else refracted
    through it, or reflected under total internal reflection (mirror then
    True); refraction is worked out only where it is asked for."""
    if mirror:
        return reflect1(d, n), True
    through, tir = refract1(d, n, eta)
    return (reflect1(d, n), True) if tir else (through, False)


@inline
def scatter1(d, scattering, facing, shading, eta, alpha, mirror):
    """(out, crossed, kept) of a ray `d` at an interface of `eta`: mirror
    reflection if `mirror`, else Snell refraction (total internal
    reflection reflects), about the `scattering` normal; `out` unit.

    A smooth surface (alpha 0) keeps all the weight, a rough one G2/G1
    (optics.microfacet.shadowing_weight1; the multiscatter factor is the
    caller's). A ray that leaves on the wrong side of the geometric normal
    `facing` or of the shading normal keeps nothing: a shading normal can
    send a refracted ray back out, or a reflection into the surface, and
    Cycles ends those paths (bsdf_microfacet_sample). Smooth shading across
    a glass's hard edges then darkens it as it does in Cycles."""
    out, mirror = turned1(d, scattering, eta, mirror)
    side, macro = dot1(out, facing), dot1(out, shading)
    wrong = (side <= 0.0 or macro <= 0.0) if mirror else (side >= 0.0 or macro >= 0.0)
    kept = 0.0 if wrong else 1.0
    if alpha > 0.0 and not wrong:
        kept = shadowing_weight1(-dot1(d, shading), abs(macro), alpha)
    return normalize1(out), not mirror, kept


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], b1[::1], "
        "f8[:, ::1], b1[::1], f8[::1])")
def _scattered(dirs, scattering, facing, shading, eta, alpha, mirror, out, crossed, kept):
    for i in range(len(dirs)):
        o, c, k = scatter1(row(dirs, i), row(scattering, i), row(facing, i), row(shading, i), eta[i], alpha[i],
                           mirror[i])
        set_row(out, i, o)
        crossed[i], kept[i] = c, k


def scatter(surface: Interface, dirs: np.ndarray,
            reflect_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scatter1 of each row of `dirs (n,3)` at `surface`, reflecting where
    `reflect_mask (n,)`: new unit directions (n,3), which of them crossed
    the surface (n,) bool, and the share of weight each keeps (n,)."""
    n = len(dirs)
    out, crossed, kept = np.empty((n, 3)), np.empty(n, dtype=bool), np.empty(n)
    _scattered(contiguous(dirs, np.float64), contiguous(surface.scattering, np.float64),
               contiguous(surface.facing, np.float64), contiguous(surface.shading, np.float64),
               contiguous(surface.eta, np.float64), contiguous(surface.alpha, np.float64),
               contiguous(reflect_mask, bool), out, crossed, kept)
    return out, crossed, kept


@inline
def crossed_media1(crossed, beyond, beneath, medium, outer):
    """(medium, outer) of a path after a bounce: those beyond the surface
    (Interface.beyond, beneath) if it crossed, its own if it did not."""
    if crossed:
        return beyond, beneath
    return medium, outer


@inline
def transmission1(transmission_tint, obj, joined):
    """The transmission tint (3-tuple) of a crossing at object `obj`, times
    that of the object `joined` against it (MISS: none)."""
    c, t = row(transmission_tint, obj), row(transmission_tint, max(joined, 0))
    if joined == MISS:
        return c
    return c[0] * t[0], c[1] * t[1], c[2] * t[2]


@inline
def next_family1(family, surface, event, ident, own):
    """The uint64 signature of a path that adds (surface, event) to
    `family`, FNV-style: (family * P) ^ (4 surface + event + 1); the parts
    of one body with one material are one surface. Where `own`, the path's
    own id `ident` goes in first (family ^ ident * Q), so no other path
    shares it, and the SCATTERED bit is set; it stays set."""
    scattered = own or (family & SCATTERED) != np.uint64(0)
    if own:
        family = family ^ (np.uint64(ident) * _ID_PRIME)
    signature = (family * _FAMILY_PRIME) ^ (np.uint64(surface) * np.uint64(4) + np.uint64(event + 1))
    return signature | SCATTERED if scattered else signature


def _own_families(surface: Interface) -> np.ndarray:
    """(n,) bool: the rows whose branches take a family of their own, the rough ones."""
    return surface.rough


@named_kernel("i8", PATH_TYPES, HIT_TYPES, INTERFACE_TYPES, MATERIAL_TYPES, GEOMETRY_TYPES,
              {"own": "b1[::1]", "factor": "f8[:, ::1]", "radiance": "b1", "roulette": "f8", "draws": "i8[::1]",
               "strata": "i8", "key": "u8", "source": "i8[::1]", "with_pdf": "b1"})
def _branches(dirs, weight, medium, outer, floor, family, ids, obj, prim,
              points, facing, shading, scattering, eta, fresnel, alpha, beyond, beneath, joined, own,
              reflection_tint, transmission_tint, dielectric, surface_of, factor, radiance, epsilon, roulette, draws,
              strata, key, with_pdf, out_origins, out_dirs, out_weight, out_medium, out_outer, out_family, out_kind,
              out_surface, out_pdf, source):
    """split's branches, all reflected ones, then all refracted ones, into
    the out_ arrays (2n rows); returns how many there are. `source` is the
    path each comes from; `factor (2n,3)` the multiscatter factors of the
    reflected then the refracted branches, or (0,3): none; `radiance` where
    the paths carry radiance (eye rays), whose refracted branches take
    radiance_scale1; `family` (0,) where the paths have none; `draws (n,)`
    the ids the roulette of each path's branches hashes, or (0,): no
    roulette, `strata` how many draws share one stratified set (Roulette);
    `out_pdf`, where `with_pdf`, the density each branch's direction was
    drawn with (microfacet.branch_pdf1 where rough, inf where smooth)."""
    n, count = len(dirs), 0
    for event in range(2):
        mirror = event == 0
        for i in range(n):
            o = obj[i]
            if not (mirror or dielectric[o]):
                continue
            d = row(dirs, i)
            c = row(reflection_tint, o) if mirror else transmission1(transmission_tint, o, joined[i])
            out, crossed, kept = scatter1(d, row(scattering, i), row(facing, i), row(shading, i), eta[i], alpha[i],
                                          mirror)
            share = fresnel[i] if mirror else (1.0 - fresnel[i] if crossed else 0.0)
            s = share * kept * (radiance_scale1(eta[i]) if radiance and crossed else 1.0)
            w = (weight[i, 0] * c[0] * s, weight[i, 1] * c[1] * s, weight[i, 2] * c[2] * s)
            if len(factor):
                j = event * n + i
                w = (w[0] * factor[j, 0], w[1] * factor[j, 1], w[2] * factor[j, 2])
            if not max_channel1(w) >= floor[i]:
                continue
            level = roulette * floor[i] / MIN_BRANCH_WEIGHT
            if len(draws) and max_channel1(w) < level:
                chance = max_channel1(w) / level
                group, member = draws[i] // strata, draws[i] % strata
                u = hash_uniform1(2 * group + (1 if crossed else 0), key) + member / strata
                if not u - math.floor(u) < chance:
                    continue
                w = (w[0] / chance, w[1] / chance, w[2] / chance)
            set_row(out_origins, count, offset1(row(points, i), row(facing, i), out, epsilon))
            set_row(out_dirs, count, out)
            set_row(out_weight, count, w)
            out_medium[count], out_outer[count] = crossed_media1(crossed, beyond[i], beneath[i], medium[i], outer[i])
            if len(family):
                out_family[count] = next_family1(family[i], surface_of[o], event, ids[i], own[i])
            out_kind[count] = REFRACTED if crossed else REFLECTED
            out_surface[count], source[count] = prim[i], i
            if with_pdf:
                pdf = math.inf
                if alpha[i] > 0.0:
                    pdf = branch_pdf1(scale1(-1.0, d), out, row(shading, i), alpha[i], eta[i])
                out_pdf[count] = pdf
            count += 1
    return count


@dataclass
class Roulette:
    """Russian roulette on faint branches (pbrt's, Cycles'): a branch whose
    throughput w (max channel) falls below `weight` of its path's starting
    weight (its floor over MIN_BRANCH_WEIGHT) goes on with probability p =
    w / that level, its weight divided by p, so the mean is kept.

    The draws of a group of `strata` paths (an eye pixel's samples: `draws
    (n,)` int64, group draw // strata, member draw % strata) are
    stratified: u = frac(r + member / strata), r one uniform per group and
    kind of branch, which hashes 2 group + (the branch was refracted) with
    `key` (sampling.hash.stream_key of the bounce's stream). Each u is
    uniform, so each branch's mean is kept, and of a pixel's faint
    branches about p of them go on, not a binomial count: 4 samples whose
    reflections each go on with p = 0.8 keep 3 or 4, never 1, so a pixel
    seen through glass is not a speckle that the edge pass mistakes for
    an edge."""

    weight: float
    draws: np.ndarray
    key: int
    strata: int = 1


def split(accel: Accelerator, materials: Materials, paths: Paths, hits: Hits, surface: Interface,
          carries_light: bool, roulette: Roulette | None = None) -> Paths:
    """Both branches of every path at its specular hit: the reflected one
    with weight F and the refracted one with weight 1 - F (dielectrics
    only), each times the surface's tint for its kind (Materials'
    reflection_tint, transmission_tint), an eye ray's refracted one (not
    `carries_light`) times radiance_scale1 as well, and where rough about the same
    microfacet normal (`facets` drew it), times what scatter1 keeps and the
    multiscatter factor (on the eye's side: `carries_light` for beam
    vertices, not for eye rays). A branch whose weight falls below its
    path's floor stops. With families, each branch records its event
    (next_family1); a branch scattered at a rough surface takes a family of
    its own (SCATTERED). The branches leave epsilon off the surface
    (offset1). With a `roulette`, the faint branches play it. All in one
    kernel, `_branches`, but the multiscatter factors, which numpy gives
    first where a row is rough. Paths with ray differentials hand them on
    to their branches (differentials.py)."""
    n = len(paths)
    factor = np.zeros((0, 3))
    if surface.rough.any():
        factor = np.concatenate([multiscatter(surface, materials, hits.obj, paths.dirs, *scatter(
            surface, paths.dirs, np.full(n, mirror))[:2], carries_light) for mirror in (True, False)])
    family = np.zeros(0, dtype=np.uint64) if paths.family is None else contiguous(paths.family, np.uint64)
    out = dict(out_origins=np.empty((2 * n, 3)), out_dirs=np.empty((2 * n, 3)), out_weight=np.empty((2 * n, 3)),
               out_medium=np.empty(2 * n, dtype=np.int64), out_outer=np.empty(2 * n, dtype=np.int64),
               out_family=np.empty(2 * n if len(family) else 0, dtype=np.uint64),
               out_kind=np.empty(2 * n, dtype=np.int8), out_surface=np.empty(2 * n, dtype=np.int64),
               out_pdf=np.empty(2 * n), source=np.empty(2 * n, dtype=np.int64))
    f8, i8 = np.float64, np.int64
    count = _branches(
        dirs=contiguous(paths.dirs, f8), weight=contiguous(paths.weight, f8), medium=contiguous(paths.medium, i8),
        outer=contiguous(paths.outer, i8), floor=contiguous(paths.floor, f8), family=family,
        ids=contiguous(paths.ids, i8), obj=contiguous(hits.obj, i8), prim=contiguous(hits.prim, i8),
        points=contiguous(surface.points, f8), facing=contiguous(surface.facing, f8),
        shading=contiguous(surface.shading, f8), scattering=contiguous(surface.scattering, f8),
        eta=contiguous(surface.eta, f8), fresnel=contiguous(surface.fresnel, f8), alpha=contiguous(surface.alpha, f8),
        beyond=contiguous(surface.beyond, i8), beneath=contiguous(surface.beneath, i8),
        joined=contiguous(surface.joined, i8),
        own=contiguous(_own_families(surface), bool), reflection_tint=materials.reflection_tint,
        transmission_tint=materials.transmission_tint, dielectric=materials.dielectric, surface_of=accel.surface,
        factor=factor, radiance=not carries_light, epsilon=accel.epsilon,
        roulette=0.0 if roulette is None else roulette.weight,
        draws=np.zeros(0, dtype=i8) if roulette is None else contiguous(roulette.draws, i8),
        strata=1 if roulette is None else roulette.strata, key=np.uint64(0 if roulette is None else roulette.key),
        with_pdf=paths.pdf is not None,
        **out)
    origins, dirs, weight, medium, outer, family, kind, prim, pdf, source = (out[name][:count] for name in out)
    d_origins = d_dirs = None
    if paths.d_origins is not None:
        d_origins, d_dirs = branch_differentials(accel, paths, hits, surface, source, kind, dirs)
    return Paths(origins, dirs, weight, medium, outer, np.take(paths.ids, source), np.take(paths.floor, source),
                 np.ones(count, dtype=bool), None if paths.band is None else np.take(paths.band, source),
                 None if paths.family is None else family, None if paths.kind is None else kind, prim,
                 d_origins, d_dirs, None if paths.pdf is None else pdf)


@kernel("void(f8[:, ::1], i8[::1], f8[::1], i8[::1], f8[:, ::1], b1[::1], f8[:, ::1], i1[::1])")
def _arrivals(weight, medium, t, obj, absorption, specular_surface, out_weight, fate):
    """Each path's fate at its hit (_ESCAPED, _ARRIVED, _SPECULAR), and its
    weight there: times beer_lambert1 over the leg `t` where it travelled
    inside a medium and hit something."""
    for i in range(len(t)):
        o = obj[i]
        fate[i] = _ESCAPED if o == MISS else (_SPECULAR if specular_surface[o] else _ARRIVED)
        for c in range(3):
            out_weight[i, c] = weight[i, c]
            if o != MISS and medium[i] != MISS:
                out_weight[i, c] *= beer_lambert1(absorption[medium[i], c], t[i])


class Tracer(Protocol):
    """What a pass does where the bounce leaves the choice to it."""

    def escaped(self, paths: Paths) -> None:
        """`paths` left the scene."""

    def arrived(self, paths: Paths, hits: Hits) -> None:
        """`paths` met an opaque surface at `hits`."""

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        """The paths that go on from the specular hits `hits`, at bounce `depth`."""


def trace(accel: Accelerator, materials: Materials, paths: Paths, max_depth: int, tracer: Tracer) -> None:
    """Follow `paths` through up to `max_depth` specular bounces, handing
    `tracer` what each bounce leaves to it. Each bounce groups its paths by
    fate once (util.rows.partition: those that escaped, arrived, met a
    specular surface, each in their order) and hands on views of the groups."""
    for depth in range(max_depth + 1):
        n = len(paths)
        if n == 0:
            return
        hits = accel.intersect(paths.origins, paths.dirs, paths.medium, paths.outer, paths.kind, paths.surface)
        weight, fate = np.empty((n, 3)), np.empty(n, dtype=np.int8)
        _arrivals(contiguous(paths.weight, np.float64), contiguous(paths.medium, np.int64), hits.t, hits.obj,
                  materials.absorption, materials.specular_surface, weight, fate)
        order, ends = np.empty(n, dtype=np.int64), np.empty(3, dtype=np.int64)
        partition(fate, order, ends)
        escaped, arrived = int(ends[_ESCAPED]), int(ends[_ARRIVED])
        paths = replace(paths, weight=weight)
        if max(escaped, arrived - escaped, n - arrived) < n:
            paths, hits = paths.take(order), hits.take(order[escaped:])
        else:
            hits = hits.span(escaped, n)
        tracer.escaped(paths.span(0, escaped))
        tracer.arrived(paths.span(escaped, arrived), hits.span(0, arrived - escaped))
        paths, hits = paths.span(arrived, n), hits.span(arrived - escaped, n - escaped)
        if len(paths) == 0:
            return
        surface = orient(accel, hits, paths.dirs, materials, paths.medium, paths.outer, paths.band)
        paths = tracer.scattered(paths, hits, surface, depth)


def on_maps(accel: Accelerator, materials: Materials, maps: dict, paths: Paths, hits: Hits):
    """Where the paths that have met a specular surface land on a
    receiver's map (`maps`: object index -> IlluminationMap), one receiver
    at a time: (object index, rows (k,) of `paths`, xy (k,2) chart metres,
    scale (k,) chart area per world area, island (k,) of the chart,
    basic (k,) the share of their flux a map holds: the basic irradiance
    of the medium they arrive through, specular.basic_irradiance_scale).
    A map takes the paths that arrive on its chart's front (charts.Chart)."""
    land = np.flatnonzero(paths.specular & np.isin(hits.obj, list(maps)))
    for index in np.unique(hits.obj[land]):
        rows = land[hits.obj[land] == index]
        chart = maps[index].chart
        if chart.front is not None:
            rows = rows[np.take(paths.dirs, rows, axis=0) @ chart.front < 0.0]
            if len(rows) == 0:
                continue
        local = np.take(hits.prim, rows) - accel.prim_offset[index]
        xy = chart.coords(local, np.take(hits.u, rows), np.take(hits.v, rows), np.take(hits.points, rows, axis=0))
        basic = basic_irradiance_scale(materials.medium_ior(np.take(paths.medium, rows)))
        yield int(index), rows, xy, chart.area_scale(local), chart.islands_of(local), basic
