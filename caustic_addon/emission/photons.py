"""Where photons leave the lamps, which way, and with how much flux.

Each lamp gets an `Emitter` that makes photon i from its index alone, so a
render split into chunks gives the same photons whatever the chunk size.

Two modes:
- 'sphere': the paper's eq. (1), P(u,v) = (cos v cos u, cos v sin u, sin v)
  on a grid of u in [0, 2 pi), v in [-pi/2, pi/2]; a photon carries the
  intensity times the solid angle of its (u,v) cell, so a uniform lamp stays
  uniform.
- 'targeted': only toward the casters (transparent and reflecting objects),
  over the lamps' aims (aims.py), on a low-discrepancy sequence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling.hash import hash_uniform
from ..sampling.sequences import r2_sequence
from ..sampling.warps import sample_disc
from ..scene import Light, MeshLight, SunLight
from . import mesh_lights, radiometry
from .aims import Aim, Sphere, aims, balance_density, meets_any, overlapping, share


# Hash streams of a photon's point on a lamp with a size (the transport uses
# 0 .. 2 max_depth + 1, the wavelength band 1 << 20).
_LAMP_STREAM = 1 << 21


def sphere_grid(count: int) -> tuple[int, int]:
    """(nu, nv): the paper's (u, v) grid with about `count` cells, twice as
    many steps in u (0..2 pi) as in v (-pi/2..pi/2), so cells are square at the equator."""
    nv = max(1, int(round(math.sqrt(count / 2.0))))
    return 2 * nv, nv


@dataclass
class Photons:
    """A batch of n photons leaving a lamp: origins (n,3), dirs (n,3) unit,
    flux (n,3) W, ids (n,) int64 unique per render (they seed each photon's
    random choices). Photons with zero flux are already removed."""

    origins: np.ndarray
    dirs: np.ndarray
    flux: np.ndarray
    ids: np.ndarray


class Emitter:
    """Makes photons [start, stop) of one lamp. `count` is how many it makes
    in all; its photons' ids start at `id_base`; `source` the scene's lamp
    it is (a mesh light's pieces are lamps of their own); a photon that
    meets one of the spheres `beamed` (aims.meets_any) carries nothing:
    beams carry that light (passes.beam.photon_lamps)."""

    count: int
    id_base: int = 0
    source: Light = None
    beamed: tuple = ()

    def emit(self, start: int, stop: int) -> Photons:
        raise NotImplementedError


def _kept(origins, dirs, flux, ids) -> Photons:
    keep = flux.max(axis=1) > 0.0
    return Photons(origins[keep], dirs[keep], flux[keep], ids[keep])


class PointSphereEmitter(Emitter):
    """The paper's eq. (1): every direction, on the (u, v) grid's cell centres."""

    def __init__(self, light: Light, energy: float, count: int):
        self.light, self.energy = light, energy
        self.nu, self.nv = sphere_grid(count)
        self.count = self.nu * self.nv

    def emit(self, start: int, stop: int) -> Photons:
        i = np.arange(start, stop)
        du, dv = 2.0 * math.pi / self.nu, math.pi / self.nv
        u = (i % self.nu + 0.5) * du
        v0 = -0.5 * math.pi + (i // self.nu) * dv
        v = v0 + 0.5 * dv
        dirs = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
        cell_solid_angle = du * (np.sin(v0 + dv) - np.sin(v0))
        flux = radiometry.intensity(self.light, self.energy, dirs) * cell_solid_angle[:, None]
        origins = np.broadcast_to(self.light.position, dirs.shape)
        return _kept(origins, dirs, flux, i + self.id_base)


class AimedEmitter(Emitter):
    """Photons over a lamp's aims: `counts (k,)` of them over each, on the
    R2 sequence mapped onto the unit disc in polar form (r = sqrt(u), phi =
    2 pi v: uniform in area), then onto the aim; a lamp with a size sends
    each from a point of it hashed from the photon's id and `seed`. A
    photon's flux is what the lamp sends its way over the balance density of
    the aims."""

    def __init__(self, light: Light, energy: float, aims: list[Aim], counts: np.ndarray, shift: np.ndarray,
                 seed: int):
        self.light, self.energy, self.aims, self.shift, self.seed = light, energy, aims, shift, seed
        self.starts = np.concatenate([[0], np.cumsum(counts)])
        self.count = int(self.starts[-1])
        self.density = counts / np.array([aim.measure for aim in aims])
        self.near = overlapping(aims)

    def emit(self, start: int, stop: int) -> Photons:
        i = np.arange(start, stop)
        which = np.searchsorted(self.starts, i, side="right") - 1
        disc = sample_disc(1.0, r2_sequence(i - self.starts[which], self.shift))
        ids = i + self.id_base
        lamp = np.stack([hash_uniform(ids, _LAMP_STREAM, self.seed), hash_uniform(ids, _LAMP_STREAM + 1, self.seed)],
                        axis=1)
        origins, dirs, density = np.empty((len(i), 3)), np.empty((len(i), 3)), np.empty(len(i))
        for k in np.unique(which):
            sel, near = which == k, self.near[k]
            origins[sel], dirs[sel] = self.aims[k].rays(disc[sel], lamp[sel])
            density[sel] = balance_density([self.aims[j] for j in near], self.density[near], origins[sel], dirs[sel])
        flux = self.aims[0].emitted(self.energy, dirs) / density[:, None]
        if self.beamed:
            flux[meets_any(list(self.beamed), origins, dirs)] = 0.0
        return _kept(origins, dirs, flux, ids)


def _emitting(light: Light) -> list[Light]:
    """The lamps that send `light`'s photons: a mesh light's pieces
    (mesh_lights.area_lamps), any other lamp itself."""
    if isinstance(light, MeshLight):
        return mesh_lights.area_lamps(light, mesh_lights.PHOTON_PIECES, mesh_lights.lift_off(light))
    return [light]


def make_emitters(lights: list[Light], targets: list[Sphere], scene_sphere: Sphere, mode: str, energy: float,
                  lamp_rays: int, seed: int) -> list[Emitter]:
    """One emitter per lamp that sends light to a target, with the
    `lamp_rays` shared among the aims in proportion to the flux each
    receives. In 'sphere' mode a point or spot lamp sends its share
    everywhere (the paper's eq. 1), and a sun over the whole scene's disc;
    a mesh light's pieces each have an emitter (`_emitting`)."""
    rng = np.random.default_rng(seed)
    if not targets:
        return []
    per_light = []
    for light, source in ((part, source) for source in lights for part in _emitting(source)):
        if mode == "sphere":
            aimed = aims(light, [scene_sphere], scene_sphere)
            if not isinstance(light, SunLight):
                aimed = aimed[:1]
        else:
            aimed = aims(light, targets, scene_sphere)
        if aimed and sum(aim.flux(energy) for aim in aimed) > 0:
            per_light.append((light, source, aimed))
    if not per_light:
        return []
    fluxes = [np.array([aim.flux(energy) for aim in aimed]) for _, _, aimed in per_light]
    counts = np.split(share(lamp_rays, np.concatenate(fluxes)), np.cumsum([len(f) for f in fluxes])[:-1])
    emitters = []
    for (light, source, aimed), n in zip(per_light, counts):
        if mode == "sphere" and not isinstance(light, SunLight):
            emitters.append(PointSphereEmitter(light, energy, int(n.sum())))
        else:
            emitters.append(AimedEmitter(light, energy, aimed, n, rng.random(2), seed))
        emitters[-1].source = source
    for k in range(1, len(emitters)):
        emitters[k].id_base = emitters[k - 1].id_base + emitters[k - 1].count
    return emitters
