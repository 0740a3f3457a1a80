"""An environment's sun as a sun lamp, so that the pass from the lamps
throws its caustic, sharp (beams without noise): the pixels around the
brightest one that are at least SUN_THRESHOLD of its luminance, within
SUN_RADIUS of it, become a sun of their irradiance and solid angle
(Blender's Angle is the disc of that solid angle), and the rest of the
world is the sky, whose light through the casters the eye pass gathers
(passes/world_paths.py). Only a compact source that brings at least
SUN_SHARE of the world's light counts as a sun: a sky with no sun, or an
overcast one, is all sky."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional

import numpy as np

from ..scene import SunLight, World
from .environment import luminance, row_solid_angles, uv_to_directions
from .kept_worlds import per_world

# A sun pixel is at least this share of the brightest pixel's luminance...
SUN_THRESHOLD = 0.01
# ... within this angle of it, radians (the sun is 0.53 degrees across, a
# blurred or low-resolution one a few pixels more).
SUN_RADIUS = math.radians(5.0)
# The sun's share of the world's light, at least.
SUN_SHARE = 0.2


@per_world
def extract_sun(world: World) -> tuple[Optional[SunLight], World]:
    """(the sun lamp of the world's sun or None, the world without it),
    kept while the same world comes back (kept_worlds.py)."""
    image = world.environment
    if image is None:
        return None, world
    h, w = image.shape[:2]
    rgb = image * world.color
    solid_angle = row_solid_angles(h, w)
    lum = np.maximum(luminance(rgb), 0.0)
    peak = np.unravel_index(np.argmax(lum), lum.shape)
    if not lum[peak] > 0:
        return None, world
    rows, cols = np.nonzero(lum >= SUN_THRESHOLD * lum[peak])
    dirs = uv_to_directions(np.stack([(cols + 0.5) / w, (rows + 0.5) / h], axis=1))
    centre = uv_to_directions(np.array([[(peak[1] + 0.5) / w, (peak[0] + 0.5) / h]]))[0]
    near = dirs @ centre >= math.cos(SUN_RADIUS)
    rows, cols, dirs = rows[near], cols[near], dirs[near]
    flux = lum[rows, cols] * solid_angle[rows]
    if flux.sum() < SUN_SHARE * (lum * solid_angle[:, None]).sum():
        return None, world
    irradiance = (rgb[rows, cols] * solid_angle[rows, None]).sum(axis=0)
    toward = (dirs * flux[:, None]).sum(axis=0)
    spanned = float(solid_angle[rows].sum())
    strength = float(irradiance.max())
    sun = SunLight(-toward, strength, irradiance / strength, name="the world's sun",
                   angle=2.0 * math.acos(1.0 - spanned / (2.0 * math.pi)), of_world=True)
    rest = image.copy()
    rest[rows, cols] = 0.0
    return sun, replace(world, environment=rest)
