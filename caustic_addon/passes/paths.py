"""Paths in flight: one struct of arrays for the photons, beam vertices and
eye rays that a pass traces (after pbrt-v4's RayWorkItem)."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Optional

import numpy as np

from ..tracing.accelerator import CAMERA
from ..tracing.hits import MISS
from ..util.rows import take, true_rows
from ..util.vectors import max_channel

# A branch of a beam vertex or an eye ray whose weight (max channel) falls
# below this share of its starting weight is not traced further.
MIN_BRANCH_WEIGHT = 1e-4


@dataclass
class Paths:
    """n paths.

    origins   (n,3) world
    dirs      (n,3) unit, world
    weight    (n,3) flux, W (photons), or throughput (beam vertices, eye rays)
    medium    (n,) int64 the closed object each path is inside, MISS in air;
              where closed objects nest or overlap (a marble in water,
              whisky in a tumbler), the one entered last
    outer     (n,) int64 the closed object of another body that the path
              is also inside, beneath `medium`: the one it is back in when
              it leaves `medium`; MISS where none (bounce.orient)
    ids       (n,) int64 the photon's id (it seeds the photon's random
              numbers), the beam vertex's grid key, or the eye ray's pixel
    floor     (n,) the weight (max channel) below which a branch stops
              (beams, eye rays) or a photon plays Russian roulette
    specular  (n,) bool: the path has met a specular surface
    band      (n,) int64 wavelength band, or None: refract at 587.6 nm
    family    (n,) uint64 the sequence of (surface, event) so far, or None
              where no one asks (beam mode asks)
    kind      (n,) int8 the kind of ray for the objects' ray visibility
              (tracing.accelerator CAMERA, REFLECTED, REFRACTED), or None:
              the ray sees every object (the pass from the lamps)
    surface   (n,) int64 the triangle the path last scattered at, MISS
              until it first does (where surfaces touch, the next one it
              meets may lie at that very point: tracing/contact.py)
    d_origins (n,2,3) float32 world: how the origin changes per pixel step
    d_dirs    (n,2,3) float32 right and down (passes/differentials.py; a
              beam vertex's per unit along its lamp cell's axes), or
              None where no one asks (eye rays ask once they meet a
              specular surface, beam vertices from lamps with a size)
    pdf       (n,) 1/sr: the density the path's last bounce drew its
              direction with, where rough (microfacet.branch_pdf1), inf
              where smooth or none yet; None where no one asks (the pass
              from the lamps)
    """

    origins: np.ndarray
    dirs: np.ndarray
    weight: np.ndarray
    medium: np.ndarray
    outer: np.ndarray
    ids: np.ndarray
    floor: np.ndarray
    specular: np.ndarray
    band: Optional[np.ndarray] = None
    family: Optional[np.ndarray] = None
    kind: Optional[np.ndarray] = None
    surface: Optional[np.ndarray] = None
    d_origins: Optional[np.ndarray] = None
    d_dirs: Optional[np.ndarray] = None
    pdf: Optional[np.ndarray] = None

    def __len__(self) -> int:
        return len(self.ids)

    @staticmethod
    def start(origins: np.ndarray, dirs: np.ndarray, weight: np.ndarray, ids: np.ndarray, media: tuple[int, int],
              floor: np.ndarray, band: Optional[np.ndarray] = None, family: bool = False,
              camera: bool = False) -> "Paths":
        """Paths leaving a lamp or, as CAMERA rays if `camera`, the camera,
        from inside the objects `media` (medium, outer; MISS: in air), with
        no specular event yet."""
        n = len(ids)
        return Paths(origins, dirs, weight, np.full(n, media[0], dtype=np.int64), np.full(n, media[1], dtype=np.int64),
                     ids, floor,
                     np.zeros(n, dtype=bool), band, np.zeros(n, dtype=np.uint64) if family else None,
                     np.full(n, CAMERA, dtype=np.int8) if camera else None, np.full(n, MISS, dtype=np.int64),
                     pdf=np.full(n, np.inf) if camera else None)

    def _columns(self) -> list[str]:
        return [f.name for f in fields(self) if getattr(self, f.name) is not None]

    def select(self, mask: np.ndarray) -> "Paths":
        """The paths where `mask (n,)` is True: these very paths where it is
        True throughout."""
        index = true_rows(np.ascontiguousarray(mask, dtype=bool))
        return self if len(index) == len(self) else self.take(index)

    def take(self, index: np.ndarray) -> "Paths":
        """The paths `index (k,)` int64, in that order."""
        return Paths(**{name: take(getattr(self, name), index) for name in self._columns()})

    def span(self, start: int, stop: int) -> "Paths":
        """The paths start .. stop - 1, views of these."""
        return Paths(**{name: getattr(self, name)[start:stop] for name in self._columns()})

    @staticmethod
    def concat(parts: list["Paths"]) -> "Paths":
        names = parts[0]._columns()
        return Paths(**{name: np.concatenate([getattr(p, name) for p in parts]) for name in names})


def relative_floor(weight: np.ndarray) -> np.ndarray:
    """(n,) MIN_BRANCH_WEIGHT of each path's starting weight `weight (n,3)`."""
    return MIN_BRANCH_WEIGHT * max_channel(weight)


# The numba type of each field, for the kernels that take path arrays by
# name (util.jit.named_kernel).
PATH_TYPES = {"origins": "f8[:, ::1]", "dirs": "f8[:, ::1]", "weight": "f8[:, ::1]", "medium": "i8[::1]",
              "outer": "i8[::1]",
              "ids": "i8[::1]", "floor": "f8[::1]", "specular": "b1[::1]", "band": "i8[::1]", "family": "u8[::1]",
              "kind": "i1[::1]", "surface": "i8[::1]", "d_origins": "f4[:, :, ::1]", "d_dirs": "f4[:, :, ::1]",
              "pdf": "f8[::1]"}
