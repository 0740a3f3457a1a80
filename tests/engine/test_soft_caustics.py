"""Beams from lamps with a size: each point of the lamp spreads its beams
over the image of its cell of the lamp, so that the points' sharp caustics
sum to a smooth soft one, and each beam grid's triangles carry their own
measure of the aim."""

import math
from dataclasses import replace

import numpy as np

from benchmarks.scenes import slab
from caustic_addon import Dielectric, RenderSettings, SunLight, render
from scenes import ball_lens


def map_cells(imap, half: float) -> tuple[np.ndarray, np.ndarray]:
    """(irradiance (n,n) W/m^2, distance from the axis (n,n) m) of the map's
    cells within `half` m of the chart's centre: each cell's exact mean."""
    first = np.floor((-half - imap.chart.origin) / imap.cell).astype(int)
    count = int(np.ceil(2 * half / imap.cell))
    cols, rows = np.meshgrid(first[0] + np.arange(count), first[1] + np.arange(count))
    lo = imap.chart.origin + imap.cell * np.stack([cols.ravel(), rows.ravel()], axis=1)
    centre = imap.chart.world(lo + 0.5 * imap.cell)
    return (imap.mean_over(lo, lo + imap.cell)[:, 0].reshape(count, count),
            np.hypot(centre[:, 0], centre[:, 1]).reshape(count, count))


def gaussian(values: np.ndarray, sigma: float) -> np.ndarray:
    """`values (h,w)` blurred by a Gaussian of `sigma` cells (its tails cut at 3 sigma)."""
    reach = int(np.ceil(3 * sigma))
    kernel = np.exp(-0.5 * (np.arange(-reach, reach + 1) / sigma) ** 2)
    kernel /= kernel.sum()
    padded = np.pad(values, reach, mode="edge")
    rows = np.apply_along_axis(lambda v: np.convolve(v, kernel, "valid"), 1, padded)
    return np.apply_along_axis(lambda v: np.convolve(v, kernel, "valid"), 0, rows)


def test_a_disc_lamps_caustic_through_a_ball_lens_is_smooth_in_every_map_cell():
    """The ball lens under a disc lamp (Soft Falloff) of radius 0.5 m, at the
    default settings: 14 x 14 points of the lamp. Each point's caustic has a
    sharp spike on its axis, and the lamp's image is 0.33 m across, so
    between them they made a lattice of dots 21 mm apart (the image of a
    lamp cell) over the caustic's core, which the lamp's light does not
    have: a cell (7.8 mm) was up to 32% of the core's mean irradiance off
    its neighbourhood's mean (a Gaussian of 1.5 cells), 5.3% RMS. With
    each point's beams spread over its cell's image, 8.0% and 1.6%; a
    converged render (64 x 64 points, 8M lamp rays) has 3.7% and 0.9%
    there, the caustic's own curvature at its peak, and 20M photons 6.1%
    and 1.4%, their noise. Each cell of the core within 10% of the core's
    mean of its neighbourhood's mean, and 2.5% RMS."""
    scene = ball_lens(pixels=8)
    scene.lights = [replace(scene.lights[0], radius=0.5, soft_falloff=True)]
    irradiance, distance = map_cells(render(scene, RenderSettings(spp=1)).maps["Floor"], 0.25)
    core = distance < 0.18
    mean = irradiance[core].mean()
    off = np.abs(irradiance - gaussian(irradiance, 1.5))[core] / mean
    assert off.max() < 0.10
    assert np.sqrt((off ** 2).mean()) < 0.025


def test_the_floor_under_a_glass_slab_in_a_sun_with_an_angle_is_even():
    """A clear slab under a sun of 8 degrees: the floor under its middle gets
    E = S (1 - F)^2 / (1 - F^2) (every internal reflection; the tilt of the
    sun's rays changes F by under 1e-4). Every point of the sun laid its
    grid's centre cell over the slab's middle, where its four corners lie on
    a circle of the concentric map: the flat square they span covers 2/pi
    of that cell's disc, and its beams were pi/2 too bright, a patch +57%
    about 0.2 m across. Each cell within 0.1% of E."""
    scene = slab.scene()
    scene.objects[1] = replace(scene.objects[1], material=Dielectric(slab.IOR))
    scene.lights = [SunLight((0, 0, -1), slab.SUN, angle=math.radians(8.0))]
    irradiance, distance = map_cells(render(scene, RenderSettings(spp=1)).maps["Floor"], 1.0)
    exact = slab.SUN * (1 - slab.FRESNEL) ** 2 / (1 - slab.FRESNEL ** 2)
    np.testing.assert_allclose(irradiance[distance < 1.0], exact, rtol=1e-3)
