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

from dataclasses import dataclass, field

import numpy as np

from ..emission.photons import Photons
from ..maps.illumination_map import IlluminationMap
from ..optics.media import beer_lambert
from ..optics.spectrum import photon_band
from ..sampling.hash import hash_uniform
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS
from ..util.rows import take_rows
from ..util.vectors import DIVISION_FLOOR, max_channel
from .bounce import orient, scatter

# Below this fraction of its starting flux (max channel), a photon plays
# Russian roulette and survives with probability flux / threshold.
ROULETTE_FRACTION = 0.05


@dataclass
class TransportStats:
    """rays cast; paths emitted, of which `refined` were added by beam
    refinement; photons or beams landed; flux landed (3,) W."""

    rays: int = 0
    emitted: int = 0
    refined: int = 0
    landed: int = 0
    flux_landed: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def add(self, other: "TransportStats") -> None:
        self.rays += other.rays
        self.emitted += other.emitted
        self.refined += other.refined
        self.landed += other.landed
        self.flux_landed = self.flux_landed + other.flux_landed


def trace_photons(accel: Accelerator, materials: Materials, maps: dict[int, IlluminationMap],
                  photons: Photons, max_depth: int, seed: int, start_medium: int = MISS) -> TransportStats:
    """Trace one batch of photons, which start inside object `start_medium`
    (MISS: in air), and splat the ones that land into `maps` (keyed by
    receiver object index). Returns what it did."""
    stats = TransportStats(emitted=len(photons.flux))
    origins, dirs, ids = photons.origins, photons.dirs, photons.ids
    band = photon_band(ids, materials.band_count, seed)
    flux = photons.flux * (materials.band_count * materials.band_weights[band])
    start_flux = max_channel(flux)
    medium = np.full(len(flux), start_medium, dtype=np.int64)
    specular = np.zeros(len(flux), dtype=bool)

    for depth in range(max_depth + 1):
        if len(flux) == 0:
            break
        hits = accel.intersect(origins, dirs, medium)
        stats.rays += len(flux)
        keep = hits.hit
        origins, dirs, flux, start_flux, medium, specular, ids, band = take_rows(
            keep, origins, dirs, flux, start_flux, medium, specular, ids, band)
        hits = hits.select(keep)
        points = hits.points

        inside = medium != MISS
        if inside.any():
            flux[inside] *= beer_lambert(np.take(materials.absorption, medium[inside], axis=0), hits.t[inside])

        land = specular & materials.receiver[hits.obj]
        for index in np.unique(hits.obj[land]):
            sel = land & (hits.obj == index)
            local = hits.prim[sel] - accel.prim_offset[index]
            maps[index].deposit(local, hits.u[sel], hits.v[sel], points[sel], flux[sel])
            stats.landed += int(sel.sum())
            stats.flux_landed = stats.flux_landed + flux[sel].sum(axis=0)

        bounce = materials.specular_surface[hits.obj]
        origins, dirs, flux, start_flux, medium, ids, band = take_rows(
            bounce, origins, dirs, flux, start_flux, medium, ids, band)
        hits = hits.select(bounce)
        points = hits.points
        if len(flux) == 0:
            break

        surface = orient(accel, hits, dirs, points, materials, medium, band)
        dirs, crossed = scatter(surface, dirs, hash_uniform(ids, 2 * depth, seed) < surface.fresnel)
        flux *= np.take(materials.color, hits.obj, axis=0)
        medium = np.where(crossed, np.where(surface.entering, hits.obj, MISS), medium)
        specular = np.ones(len(flux), dtype=bool)
        origins = accel.offset(points, surface.facing, dirs)

        flux, alive = _roulette(flux, start_flux, hash_uniform(ids, 2 * depth + 1, seed))
        origins, dirs, flux, start_flux, medium, specular, ids, band = take_rows(
            alive, origins, dirs, flux, start_flux, medium, specular, ids, band)
    return stats


def _roulette(flux: np.ndarray, start_flux: np.ndarray, xi: np.ndarray):
    """Russian roulette on photons below ROULETTE_FRACTION of their starting
    flux: survive with probability q = flux / threshold, flux /= q. `xi (n,)`
    are uniform random numbers. Returns (flux (n,3), alive (n,) bool)."""
    threshold = ROULETTE_FRACTION * start_flux
    peak = max_channel(flux)
    low = peak < threshold
    if not low.any():
        return flux, np.ones(len(flux), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(low, peak / threshold, 1.0)
    alive = ~low | (xi < q)
    flux = flux / np.where(alive, np.maximum(q, DIVISION_FLOOR), 1.0)[:, None]
    return flux, alive & (peak > 0.0)

