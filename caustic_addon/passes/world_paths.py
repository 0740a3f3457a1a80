"""The world's light through the casters, as a Principled receiver's
lobes reflect it: a direction toward the world that meets glass or a
mirror goes on through it, as a photon would the other way
(photon.one_branch: one branch by its Fresnel probability, Russian
roulette when faint, Beer-Lambert inside), until it leaves the scene,
where it sees the sky: a glossy floor's reflection of the sky through a
glass ball. The sky here is the world without its sun, whose glossy
light through glass is dropped as a lamp's is. What the casters let
through onto the receivers, their irradiance, is in the maps, from the
sky's suns (emission/sky_lamps.py)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..emission.environment import Environment
from ..scene.material_table import Materials
from ..tracing.accelerator import SHADOW, Accelerator
from ..tracing.hits import MISS, Hits
from ..util.vectors import DIVISION_FLOOR, max_channel
from .bounce import trace
from .interface import Interface
from .paths import Paths
from .photon import ROULETTE_FRACTION, one_branch

# The first of the random streams of a world ray's choices, past the eye's.
_STREAM = 1 << 21
# Blocked directions are all followed at a point where the sky through the
# casters could bring this share of the light it has from elsewhere, and
# fewer below (Russian roulette, as the eye's faint branches play it)...
ROULETTE_SHARE = 0.05
# ... but at least this share of them.
MIN_CHANCE = 1.0 / 16.0


class _WorldRays:
    """bounce.Tracer for rays toward the world, each a row of the batch
    (its path id): which left the scene at once, and where those that met a
    caster left it, with what they kept."""

    def __init__(self, accel: Accelerator, materials: Materials, draws: np.ndarray, seed: int):
        self.accel, self.materials, self.draws, self.seed = accel, materials, draws, seed
        n = len(draws)
        self.open = np.zeros(n, dtype=bool)
        self.through = np.zeros(n, dtype=bool)
        self.exits, self.kept = np.zeros((n, 3)), np.zeros((n, 3))

    def escaped(self, paths: Paths) -> None:
        self.open[paths.ids[~paths.specular]] = True
        rows = paths.ids[paths.specular]
        self.through[rows] = True
        self.exits[rows], self.kept[rows] = paths.dirs[paths.specular], paths.weight[paths.specular]

    def arrived(self, paths: Paths, hits: Hits) -> None:
        pass

    def scattered(self, paths: Paths, hits: Hits, surface: Interface, depth: int) -> Paths:
        return one_branch(self.accel, self.materials, paths, hits, surface, np.take(self.draws, paths.ids), depth,
                          self.seed, _STREAM, carries_light=False)


@dataclass
class WorldThroughCasters:
    """What the eye pass needs to follow rays toward the world through the
    casters: the scene's `sky` (the world without its sun), and the bounce
    limit and seed of the render."""

    accel: Accelerator
    materials: Materials
    sky: Environment
    max_depth: int
    seed: int

    def chances(self, glossy: np.ndarray, lit: np.ndarray) -> np.ndarray:
        """(n,) the chance with which points whose lobes reflect at most
        `glossy (n,)` of the light, and whose radiance from the lamps and
        the maps is `lit (n,3)`, follow their blocked directions toward the
        world: 1 where the sky's mean radiance times `glossy` could be
        ROULETTE_SHARE of `lit` (max channels), less in proportion below,
        at least MIN_CHANCE, and 0 where they reflect nothing."""
        could = glossy * self.sky.mean_level
        have = ROULETTE_SHARE * max_channel(lit)
        return np.where(glossy > 0, np.clip(could / np.maximum(have, DIVISION_FLOOR), MIN_CHANCE, 1.0), 0.0)

    def light(self, origins: np.ndarray, dirs: np.ndarray, medium: np.ndarray, surface: np.ndarray,
              draws: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(open (n,) bool, through (n,) bool, radiance (n,3)) of rays
        `origins, dirs (n,3)` toward the world, leaving triangles `surface
        (n,)` inside objects `medium (n,)` (MISS: air): which leave the
        scene meeting nothing, which leave it after casters, and the sky's
        radiance those bring times what the casters let through (0
        elsewhere). A ray's choices hash its id in `draws (n,)`. Rays see
        the objects that shadow rays see."""
        n = len(dirs)
        rays = _WorldRays(self.accel, self.materials, draws, self.seed)
        start = np.ones((n, 3))
        paths = Paths(origins, dirs, start, np.ascontiguousarray(medium, dtype=np.int64),
                      np.full(n, MISS, dtype=np.int64), np.arange(n),
                      np.full(n, ROULETTE_FRACTION), np.zeros(n, dtype=bool), kind=np.full(n, SHADOW, dtype=np.int8),
                      surface=np.ascontiguousarray(surface, dtype=np.int64))
        trace(self.accel, self.materials, paths, self.max_depth, rays)
        radiance = np.zeros((n, 3))
        rows = np.flatnonzero(rays.through)
        if len(rows):
            radiance[rows] = self.sky.light(np.take(rays.exits, rows, axis=0)) * np.take(rays.kept, rows, axis=0)
        return rays.open, rays.through, radiance
