"""The one bounce every pass makes, photons, beam vertices and eye rays
alike: cast, attenuate inside a medium, arrive at an opaque surface, or
orient the normals at a specular one (a dielectric or a reflector) and
reflect or refract. The passes differ only in what they do on arrival, with
the paths that leave the scene, and in how they scatter: one branch chosen
by its Fresnel probability (photons), or both branches with their Fresnel
weights (beams, eye rays). A reflector is a surface whose Fresnel
reflectance is 1: it always reflects, and its colour is its reflectance."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..optics.media import beer_lambert
from ..optics.specular import fresnel_dielectric, reflect, refract
from ..scene.material_table import Materials
from ..tracing.accelerator import REFLECTED, REFRACTED, Accelerator
from ..tracing.hits import MISS, Hits
from ..util.rows import take_rows
from ..util.vectors import dot, max_channel, normalize
from .paths import Paths

_FAMILY_PRIME = np.uint64(0x100000001B3)


@dataclass
class Interface:
    """n rays at specular hits, oriented.

    points      (n,3) world hit points
    facing      (n,3) geometric normal on the side the ray comes from
    shading     (n,3) shading normal on that same side
    entering    (n,) bool: the ray goes from outside the object to inside
    eta         (n,) eta_i / eta_t for this crossing
    fresnel     (n,) unpolarised reflectance; 1 under total internal
                reflection and at reflectors
    """

    points: np.ndarray
    facing: np.ndarray
    shading: np.ndarray
    entering: np.ndarray
    eta: np.ndarray
    fresnel: np.ndarray

    def select(self, mask: np.ndarray) -> "Interface":
        return Interface(*take_rows(mask, self.points, self.facing, self.shading, self.entering, self.eta,
                                    self.fresnel))


def orient(accel: Accelerator, hits: Hits, dirs: np.ndarray, materials: Materials, medium: np.ndarray,
           band=None) -> Interface:
    """Orient the hits' normals against `dirs (n,3)` and evaluate Fresnel
    (1 at reflectors, which reflect everything). Dielectrics refract with
    their IOR in wavelength band `band` ((n,) per ray), or at 587.6 nm (n_d)
    when it is None.

    Entering or leaving: for a closed mesh, the ray's own state `medium (n,)`
    (the object it is inside, or MISS; any object of the same body counts)
    decides, since a hit at an edge or a grazing hit can land on a face
    whose normal says otherwise; for an open mesh, the outward geometric
    normal does (dot(d, n) < 0 means entering).
    The geometric normal is turned against the ray, and the shading normal
    put on its side; where interpolation tips it past the ray
    (dot(d, n_s) >= 0), the geometric normal is used instead.
    """
    face = np.take(accel.face_normal, hits.prim, axis=0)
    toward = dot(dirs, face) < 0.0
    entering = np.where(accel.closed[hits.obj], ~accel.inside(medium, hits.obj), toward)
    facing = np.where(toward[:, None], face, -face)
    shading = accel.shading_normal(hits.prim, hits.u, hits.v)
    shading = np.where((dot(shading, facing) < 0.0)[:, None], -shading, shading)
    tipped = dot(dirs, shading) >= 0.0
    shading[tipped] = facing[tipped]
    ior = materials.ior[hits.obj] if band is None else materials.ior_bands[hits.obj, band]
    eta = np.where(entering, 1.0 / ior, ior)
    fresnel = np.where(materials.reflector[hits.obj], 1.0, fresnel_dielectric(-dot(dirs, shading), eta))
    return Interface(hits.points, facing, shading, entering, eta, fresnel)


def scatter(surface: Interface, dirs: np.ndarray, reflect_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """New unit directions (n,3) and which of them crossed the surface (n,) bool:
    mirror reflection where `reflect_mask`, Snell refraction elsewhere (total
    internal reflection reflects).

    A shading normal can send a reflected ray into the surface or a refracted
    one back out; those rays are redone about the geometric normal, which
    cannot.
    """
    reflected = reflect(dirs, surface.shading)
    refracted, tir = refract(dirs, surface.shading, surface.eta)
    mirror = reflect_mask | tir
    out = np.where(mirror[:, None], reflected, refracted)
    side = dot(out, surface.facing)
    wrong = np.where(mirror, side <= 0.0, side >= 0.0)
    if wrong.any():
        d, n = dirs[wrong], surface.facing[wrong]
        redo_refract, redo_tir = refract(d, n, surface.eta[wrong])
        mirror[wrong] |= redo_tir
        out[wrong] = np.where(mirror[wrong][:, None], reflect(d, n), redo_refract)
    return normalize(out), ~mirror


def crossed_medium(surface: Interface, crossed: np.ndarray, obj: np.ndarray, medium: np.ndarray) -> np.ndarray:
    """(n,) the medium after the bounce: the object entered, MISS after
    leaving it, or `medium (n,)` where the path did not cross."""
    return np.where(crossed, np.where(surface.entering, obj, MISS), medium)


def split(accel: Accelerator, materials: Materials, paths: Paths, hits: Hits, surface: Interface) -> Paths:
    """Both branches of every path at its specular hit: the reflected one
    with weight F and the refracted one with weight 1 - F (dielectrics
    only), each times the surface's tint. A branch whose weight falls below
    its path's floor stops. With families, each branch records its event."""
    tint = np.take(materials.color, hits.obj, axis=0)
    branches = []
    for event, mirror in ((0, True), (1, False)):
        dirs, crossed = scatter(surface, paths.dirs, np.full(len(paths), mirror))
        share = surface.fresnel if mirror else np.where(crossed, 1.0 - surface.fresnel, 0.0)
        weight = paths.weight * tint * share[:, None]
        family = None if paths.family is None else _next_family(paths.family, accel.surface[hits.obj], event)
        kind = None if paths.kind is None else np.where(crossed, REFRACTED, REFLECTED).astype(np.int8)
        branch = Paths(accel.offset(surface.points, surface.facing, dirs), dirs, weight,
                       crossed_medium(surface, crossed, hits.obj, paths.medium), paths.ids, paths.floor,
                       np.ones(len(paths), dtype=bool), paths.band, family, kind, hits.prim)
        exists = mirror | materials.dielectric[hits.obj]
        branches.append(branch.select(exists & (max_channel(weight) >= paths.floor)))
    return Paths.concat(branches)


def _next_family(family: np.ndarray, surface: np.ndarray, event: int) -> np.ndarray:
    """(n,) uint64 signatures of paths that add (surface, event) to
    `family`: the parts of one body with one material are one surface."""
    with np.errstate(over="ignore"):
        return (family * _FAMILY_PRIME) ^ (surface.astype(np.uint64) * np.uint64(4) + np.uint64(event + 1))


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
    `tracer` what each bounce leaves to it."""
    for depth in range(max_depth + 1):
        if len(paths) == 0:
            return
        hits = accel.intersect(paths.origins, paths.dirs, paths.medium, paths.kind, paths.surface)
        tracer.escaped(paths.select(~hits.hit))
        paths, hits = paths.select(hits.hit), hits.select(hits.hit)
        inside = paths.medium != MISS
        if inside.any():
            paths.weight[inside] *= beer_lambert(np.take(materials.absorption, paths.medium[inside], axis=0),
                                                 hits.t[inside])
        specular = materials.specular_surface[hits.obj]
        tracer.arrived(paths.select(~specular), hits.select(~specular))
        paths, hits = paths.select(specular), hits.select(specular)
        if len(paths) == 0:
            return
        surface = orient(accel, hits, paths.dirs, materials, paths.medium, paths.band)
        paths = tracer.scattered(paths, hits, surface, depth)


def on_maps(accel: Accelerator, maps: dict, paths: Paths, hits: Hits):
    """Where the paths that have met a specular surface land on a
    receiver's map (`maps`: object index -> IlluminationMap), one receiver
    at a time: (object index, rows (k,) of `paths`, xy (k,2) chart metres,
    scale (k,) chart area per world area, island (k,) of the chart)."""
    land = np.flatnonzero(paths.specular & np.isin(hits.obj, list(maps)))
    for index in np.unique(hits.obj[land]):
        rows = land[hits.obj[land] == index]
        local = np.take(hits.prim, rows) - accel.prim_offset[index]
        chart = maps[index].chart
        xy = chart.coords(local, np.take(hits.u, rows), np.take(hits.v, rows), np.take(hits.points, rows, axis=0))
        yield int(index), rows, xy, chart.area_scale(local), chart.islands_of(local)
