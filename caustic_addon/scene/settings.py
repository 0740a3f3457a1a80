"""What the user tunes: the paper's parameters and the engine's."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional

# Each level of beam refinement can quadruple a diverging cell's paths.
MAX_BEAM_REFINEMENT = 5


@dataclass
class RenderSettings:
    """What the user tunes. Defaults are the ones the accuracy benchmark chose.

    lamp_rays     rays traced from the lamps in all, shared among them by the
                  flux each sends toward the casters (the paper's "jumlah
                  sinar lampu"; it used 40,000): photons, or beam grid points
                  before refinement adds its own
    emission      'targeted': only toward the casters (transparent and
                  reflecting objects); 'sphere': the
                  paper's eq. (1) over the whole sphere of directions
    energy        multiplier on every lamp's power (the paper's lamp energy)
    map_scale     edge of one illumination-map cell in millimetres of world
                  space (the paper's map scale, 5 or 40), or None for the
                  adaptive estimate that needs no tuning
    density       'splat' (the paper's bilinear map), 'adaptive' (k nearest
                  photons, on the map's grid) or 'beam' (photons on a grid
                  whose neighbours bound beams: no noise; beams.py)
    beam_refinement  times a beam grid cell is split in four where its
                  paths diverge (0 for a plain grid)
    max_depth     specular bounces per photon and per eye ray
    spp           eye samples per pixel
    edge_samples  eye samples that replace a pixel's `spp` where they
                  disagree (a silhouette, a shadow's edge); no second pass
                  unless it is above spp
    lamp_samples  shadow rays per eye sample toward each lamp with a size
                  (a lamp of size 0 takes one), stratified over the pixel;
                  a lamp smaller than a degree casts two first, the rest
                  where a pixel's disagree
    world_samples directions per eye sample toward the world, stratified
                  over the pixel (twice for an image: by cos and by radiance)
    bands         wavelength bands traced when a material disperses
                  (spectrum.py); one band, and no cost, when none does
    eye_pass      False for a bake: the maps alone, read at their own cells;
                  no eye pass, so no layer finer than a cell (beam_map.py)
    """

    lamp_rays: int = 40_000
    emission: Literal["targeted", "sphere"] = "targeted"
    energy: float = 1.0
    map_scale: Optional[float] = None
    density: Literal["splat", "adaptive", "beam"] = "beam"
    k_nearest: int = 64
    beam_refinement: int = 1
    max_depth: int = 12
    spp: int = 4
    edge_samples: int = 8
    lamp_samples: int = 8
    world_samples: int = 8
    seed: int = 0
    chunk_size: int = 1 << 17
    threads: int = 2
    map_resolution_limit: int = 1024
    bands: int = 6
    eye_pass: bool = True

    def validate(self) -> None:
        """Raise ValueError naming the field that is out of range."""
        checks = [
            ("lamp_rays", self.lamp_rays >= 0, "must be >= 0"),
            ("seed", self.seed >= 0, "must be >= 0"),
            ("emission", self.emission in ("targeted", "sphere"), "must be 'targeted' or 'sphere'"),
            ("energy", math.isfinite(self.energy) and self.energy >= 0, "must be a finite number >= 0"),
            ("map_scale", self.map_scale is None or (math.isfinite(self.map_scale) and self.map_scale > 0),
             "must be a positive number of millimetres"),
            ("density", self.density in ("splat", "adaptive", "beam"), "must be 'splat', 'adaptive' or 'beam'"),
            ("k_nearest", self.k_nearest >= 1, "must be >= 1"),
            ("beam_refinement", 0 <= self.beam_refinement <= MAX_BEAM_REFINEMENT,
             f"must be in 0..{MAX_BEAM_REFINEMENT}"),
            ("max_depth", self.max_depth >= 1, "must be >= 1"),
            ("spp", self.spp >= 1, "must be >= 1"),
            ("edge_samples", self.edge_samples >= 0, "must be >= 0"),
            ("lamp_samples", self.lamp_samples >= 1, "must be >= 1"),
            ("world_samples", self.world_samples >= 1, "must be >= 1"),
            ("chunk_size", self.chunk_size >= 1, "must be >= 1"),
            ("threads", self.threads >= 1, "must be >= 1"),
            ("bands", 1 <= self.bands <= 64, "must be in 1..64"),
        ]
        for name, ok, why in checks:
            if not ok:
                raise ValueError(f"{name} {why} (got {getattr(self, name)!r})")
