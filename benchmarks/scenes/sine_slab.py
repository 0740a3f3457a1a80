"""Sunlight through water whose top is one cosine wave: a smooth, folded
caustic whose exact image is known, for the meshed surface itself.

The water (shapes.wavy_slab, one wave) is the mesh both renderers see: flat
facets between vertices 12.5 mm apart with the field's unit normals at the
vertices, interpolated. The wave runs along x (angle 0: the quads' edges
lie along its crests) or across the quads' diagonals (angle -pi/4: each
triangle's diagonal lies along a crest). Either way a vertex's height and
normal are functions of u, the position along the wave, and each triangle
spans one step of u between its vertices, so a facet's height and its
barycentric normal are affine in u alone. The surface is the same all along
a crest; a ray of the sun entering at u lands on the floor at U(u):

- at the facet, height z(u) and normal n(u) = |lerp(n_m, n_m+1)|;
- refracted into the water (Snell, n = 1.33) and out of its flat bottom,
  each time weighted by the unpolarised Fresnel transmittance;
- then down to the floor.

The light entering between u and u + du, per metre of crest, is
S (d . (z', 0, -1)) du for the sun's direction d and irradiance S. The
floor's irradiance depends on U alone, and a pixel's mean is its integral
against the distribution of U over the pixel's square: a box one pixel wide
(angle 0), or a tent reaching one pixel's half-diagonal (angle -pi/4). The
sums here run over 2^24 points per metre of water: exact to about 1e-5 of a
pixel's light, folds included. Internal reflections (2% of 2% of the light)
are left out, and so is the light through the walls, whose pixels `region`
leaves out.

The camera is wavy_slab.under_water's: 0.05 m under the water, looking
straight down, 90 degrees across 240x180, so a pixel is 2.5 mm of floor.
"""

from __future__ import annotations

import math

import numpy as np

from benchmarks.references.water_reference import (BOTTOM, DEPTH, EYE_HEIGHT, IOR, PIXEL, PIXX, PIXY,
                                                   fresnel_transmittance, refract, wall_free)
from caustic_addon import Camera, Object, Scene, shapes
from caustic_addon.scene import Dielectric, Diffuse, SunLight

SIZE, CELLS = 1.0, 80
AMPLITUDE, WAVELENGTH = 0.012, 0.2
SUN, ALBEDO = 4.0, 1.0
# name: (the wave's angle, the sun's direction)
VARIANTS = {"sine_slab": (0.0, (0.0, 0.0, -1.0)),
            "sine_slab_diagonal": (-0.25 * math.pi, (0.15, 0.1, -1.0))}


def scene(name: str = "sine_slab") -> Scene:
    angle, sun = VARIANTS[name]
    water = shapes.wavy_slab(SIZE, DEPTH, ((AMPLITUDE, WAVELENGTH, angle),), CELLS, (0.0, 0.0, BOTTOM))
    camera = Camera.look_at((0.0, 0.0, EYE_HEIGHT), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixx=PIXX, pixy=PIXY,
                            fov=math.radians(90.0))
    return Scene(objects=[Object("Pool floor", shapes.plane(4.0), Diffuse(albedo=ALBEDO)),
                          Object("Water", water, Dielectric(IOR))],
                 lights=[SunLight(sun, SUN)], camera=camera)


def landings(u: np.ndarray, angle: float, sun) -> tuple[np.ndarray, np.ndarray]:
    """Where the sun's ray entering the water's top at `u (n,)` (along the
    wave, from the slab's middle) lands on the floor, U (n,), and its share
    of the light per metre of crest, W (n,) (times du)."""
    step = SIZE / CELLS * (1.0 if angle == 0.0 else math.sqrt(0.5))
    ticks = np.arange(-math.ceil(SIZE / step), math.ceil(SIZE / step) + 1) * step
    k = 2.0 * math.pi / WAVELENGTH
    heights = BOTTOM + DEPTH + AMPLITUDE * np.cos(k * ticks)
    normals = np.stack([AMPLITUDE * k * np.sin(k * ticks), np.zeros_like(ticks), np.ones_like(ticks)], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    # the sun in the wave's frame (u, crest, z)
    d = np.asarray(sun, dtype=np.float64) / np.linalg.norm(sun)
    c, s = math.cos(angle), math.sin(angle)
    d = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]])
    m = np.floor((u - ticks[0]) / step).astype(np.int64)
    offset = u - ticks[m]
    slope = (heights[m + 1] - heights[m]) / step
    z = heights[m] + offset * slope
    n = normals[m] + (offset / step)[:, None] * (normals[m + 1] - normals[m])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    eta = 1.0 / IOR
    rays = np.broadcast_to(d, n.shape)
    inside = refract(rays, n, eta)
    u_bottom = u + inside[:, 0] * (z - BOTTOM) / -inside[:, 2]
    out = refract(inside, np.broadcast_to([0.0, 0.0, 1.0], n.shape), IOR)
    landed = u_bottom + out[:, 0] * BOTTOM / -out[:, 2]
    weight = SUN * (d[0] * slope - d[2]) * fresnel_transmittance(-np.einsum("ij,ij->i", rays, n), eta) \
        * fresnel_transmittance(-inside[:, 2], IOR)
    return landed, weight


def region(name: str = "sine_slab") -> np.ndarray:
    """(PIXY, PIXX) the pixels no wall's light reaches (water_reference.wall_free)."""
    return wall_free(SIZE, DEPTH + AMPLITUDE, VARIANTS[name][1])


def exact_radiance(name: str = "sine_slab", samples_per_metre: int = 1 << 24) -> np.ndarray:
    """(PIXY, PIXX) the floor's radiance ALBEDO E / pi, each pixel its
    footprint's mean, row 0 at +y (the image's top)."""
    angle, sun = VARIANTS[name]
    cols, rows = np.arange(PIXX), np.arange(PIXY)
    if angle == 0.0:
        # U is x: a column's box
        first, width, count = -0.5 * PIXX * PIXEL, PIXEL, PIXX
        index = np.broadcast_to(cols, (PIXY, PIXX))
    else:
        # U = (x - y)/sqrt(2): the pixels c + r = j share U_j, spaced half a diagonal
        width = PIXEL * math.sqrt(0.5)
        first, count = -0.5 * (PIXX + PIXY) * width + width, PIXX + PIXY - 1
        index = rows[:, None] + cols[None, :]
    irradiance = np.zeros(count)
    total = int(samples_per_metre * SIZE)
    du = SIZE / total
    chunk = 1 << 22
    for start in range(0, total, chunk):
        u = -0.5 * SIZE + (np.arange(start, min(start + chunk, total)) + 0.5) * du
        landed, weight = landings(u, angle, sun)
        where = (landed - first) / width
        j = np.floor(where).astype(np.int64)
        # the box: all to U_j; the tent: linear weights to the two nearest U_j, its height 1/width
        shares = ((j, 1.0),) if angle == 0.0 else ((j, 1.0 - (where - j)), (j + 1, where - j))
        for jj, share in shares:
            seen = (jj >= 0) & (jj < count)
            irradiance += np.bincount(jj[seen], weights=(weight * share)[seen], minlength=count) * du / width
    return ALBEDO * irradiance[index] / math.pi
