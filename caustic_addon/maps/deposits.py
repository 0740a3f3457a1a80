"""What a pass delivers to the illumination maps: every pass's jobs hand
back their light, and the renderer adds it to the maps in the jobs' order,
so a render sums the same numbers in the same order whatever the threads do."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .illumination_map import IlluminationMap


@dataclass
class Deposits:
    """Light for the maps, by receiver object index.

    photons[obj]  list of (xy (n,2) chart metres, flux (n,3) W, scale (n,)
                  chart area per world area)
    beams[obj]    list of (corners (m,3,2) chart metres, irradiance (m,3) W/m^2)
    """

    photons: dict[int, list] = field(default_factory=dict)
    beams: dict[int, list] = field(default_factory=dict)

    def add_photons(self, obj: int, xy: np.ndarray, flux: np.ndarray, scale: np.ndarray) -> None:
        self.photons.setdefault(obj, []).append((xy, flux, scale))

    def add_beams(self, obj: int, corners: np.ndarray, irradiance: np.ndarray) -> None:
        self.beams.setdefault(obj, []).append((corners, irradiance))

    @property
    def flux(self) -> np.ndarray:
        """(3,) W of the photons (the beams' flux is their irradiance times
        their landed area, which the pass that made them knows)."""
        return sum((flux.sum(axis=0) for parts in self.photons.values() for _, flux, _ in parts), np.zeros(3))

    def into(self, maps: dict[int, IlluminationMap]) -> None:
        for obj, parts in self.photons.items():
            for part in parts:
                maps[obj].add_photons(*part)
        for obj, parts in self.beams.items():
            for part in parts:
                maps[obj].add_beams(*part)
