"""A coloured glass slab under a vertical sun, the Beer-Lambert case with a
closed form: shared by benchmarks/dispersion.py and the engine tests.

A slab of thickness L and index n whose absorption is set as the colour c
white light takes after the distance L (so exp(-sigma L) = c), 1 m above a
white floor, under a sun of irradiance S. The photon pass plays Fresnel
roulette at both faces, so the floor receives the sum over internal round
trips:

    E = S (1 - F)^2 c / (1 - F^2 c^2),  F = ((n - 1)/(n + 1))^2
"""

from __future__ import annotations

import math

import numpy as np

from caustic_addon import Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, render, shapes
from caustic_addon.optics.media import absorption_from_color

THICKNESS, IOR, SUN = 0.2, 1.5, 1000.0
COLOR = np.array([0.8, 0.5, 0.2])
RADIUS = 2.0
FRESNEL = ((IOR - 1) / (IOR + 1)) ** 2


def scene() -> Scene:
    glass = Dielectric(IOR, absorption=absorption_from_color(COLOR, THICKNESS))
    camera = np.eye(4)
    camera[2, 3] = 20.0
    return Scene(objects=[Object("Floor", shapes.plane(6.0), Diffuse(albedo=1.0)),
                          Object("Slab", shapes.cylinder(RADIUS, THICKNESS, (0, 0, 1.0)), glass)],
                 lights=[SunLight((0, 0, -1), SUN)],
                 camera=Camera(camera, pixx=8, pixy=8, kind="ORTHO", ortho_scale=2.0))


def exact_irradiance() -> np.ndarray:
    """(3,) W/m^2 on the floor under the slab."""
    return SUN * (1 - FRESNEL) ** 2 * COLOR / (1 - FRESNEL ** 2 * COLOR ** 2)


def measured_irradiance(photons: int) -> np.ndarray:
    """(3,) W/m^2: the splat map's mean over the 2 x 2 m square under the
    slab's middle, from `photons` photons."""
    result = render(scene(), RenderSettings(lamp_rays=photons, density="splat", map_scale=50.0, spp=1))
    floor = result.maps["Floor"]
    h, w = floor.shape
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    xy = floor.chart.origin + floor.cell * (np.stack([cols.ravel(), rows.ravel()], axis=1) + 0.5)
    inner = (np.abs(floor.chart.world(xy)[:, :2]) < 1.0).all(axis=1)
    return floor.irradiance().reshape(h * w, 3)[inner].mean(axis=0)


def relative_noise(photons: int) -> float:
    """The splat mean's relative standard deviation: photons are aimed at
    the slab's bounding disc (the sun's target) and reach a cell with
    probability about p = (1 - F)^2, so over the 4 m^2 square it is
    sqrt((1 - p) / (p N)) for the N photons aimed at the square."""
    disc = math.pi * (RADIUS ** 2 + (0.5 * THICKNESS) ** 2)
    aimed = photons * 4.0 / disc
    p = (1 - FRESNEL) ** 2
    return math.sqrt((1 - p) / (p * aimed))
