"""Radiance across a refraction: radiance over n^2 is what crosses an
interface (Veach 1997, sec. 5.2), so a floor under water seen from the air
is 1 / n^2 as bright as the irradiance the illumination map holds would
make it under the air, and a camera under water records the basic radiance
L / n^2, as Cycles renders it. Where the eye leaves the glass it entered,
the factors cancel."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, World, render, shapes
from caustic_addon.optics.specular import fresnel_dielectric

WATER, SUN, ALBEDO = 1.33, 1000.0, 0.5
F0 = ((WATER - 1) / (WATER + 1)) ** 2


def water_over_floor(bottom: float, camera_z: float = 20.0, sky: bool = False) -> Scene:
    """A flat disc of water 4 m across and 0.5 m deep, its bottom at z =
    `bottom`, over a floor at z = 0 under a vertical sun, seen straight
    down by an orthographic camera at `camera_z`; a `bottom` below 0 puts
    the floor inside the water, as a pool's water modelled past its floor
    does. With `sky`, no sun but a uniform world of radiance 1, and water
    20 m across, so that the floor sees the sky through its surface, but
    for 0.3% of its light within 3 degrees of the horizon."""
    camera = np.eye(4)
    camera[2, 3] = camera_z
    water = (shapes.wavy_slab(20.0, 0.5, waves=(), cells=1, center=(0, 0, bottom)) if sky
             else shapes.cylinder(2.0, 0.5, (0, 0, bottom)))
    return Scene(objects=[Object("Floor", shapes.plane(400.0 if sky else 8.0), Diffuse(albedo=ALBEDO)),
                          Object("Water", water, Dielectric(WATER))],
                 lights=[] if sky else [SunLight((0, 0, -1), SUN)],
                 camera=Camera(camera, pixx=8, pixy=8, kind="ORTHO", ortho_scale=1.0),
                 world=World(1.0) if sky else World())


def assert_uniform(image: np.ndarray, exact: float) -> None:
    """The image's mean within 0.5% of `exact`, each pixel within 2% (the
    beams' grid shows through the flat surface at its cells' scale)."""
    assert image.mean() == pytest.approx(exact, rel=5e-3)
    np.testing.assert_allclose(image, exact, rtol=0.02)


def test_a_floor_under_water_seen_from_the_air_is_one_over_n_squared_as_bright():
    """The sun crosses the surface once, E = S (1 - F), and so does the
    eye: L = (1 - F) / n^2 rho E / pi. Cycles renders the same (its paths
    take no factor, and the sun's cone narrows by n^2 under water). With
    no factor the floor was n^2 = 1.77 times too bright."""
    image = render(water_over_floor(-0.1), RenderSettings()).image[..., :3]
    assert_uniform(image, ALBEDO * SUN * (1 - F0) ** 2 / (math.pi * WATER ** 2))


def test_a_floor_under_a_slab_with_air_between_sees_the_factors_cancel():
    """The eye's rays leave the water before they meet the floor: n^2 in,
    1 / n^2 out. Every round trip inside the slab counts, for the sun and
    for the eye: L = rho S / pi ((1 - F)^2 / (1 - F^2))^2."""
    image = render(water_over_floor(0.3), RenderSettings()).image[..., :3]
    assert_uniform(image, ALBEDO * SUN / math.pi * ((1 - F0) ** 2 / (1 - F0 ** 2)) ** 2)


def test_a_camera_under_water_records_the_floor_s_basic_radiance():
    """Under water the floor's radiance is rho E / pi with E = S (1 - F);
    the camera records L / n^2, as Cycles does."""
    image = render(water_over_floor(-0.1, camera_z=0.2), RenderSettings()).image[..., :3]
    assert_uniform(image, ALBEDO * SUN * (1 - F0) / (math.pi * WATER ** 2))


def test_the_sky_on_a_floor_under_water_is_the_sky_through_one_surface():
    """In a uniform world of radiance 1, the floor under water gets
    E = 2 pi int (1 - R) cos sin dtheta over the sky's directions, the
    light through the surface, compressed into the cone of the critical
    angle: radiance n^2 times as high over 1 / n^2 the solid angle. The
    camera above sees it through the surface, (1 - F0) / n^2 rho E / pi,
    in the caustic pass (the sky reflected, F0, is in the ambient pass)."""
    scene = water_over_floor(-0.1, camera_z=0.5, sky=True)
    result = render(scene, RenderSettings(spp=1, world_samples=1024, max_depth=32))
    theta = (np.arange(20_000) + 0.5) / 20_000 * (math.pi / 2)
    transmitted = 1 - fresnel_dielectric(np.cos(theta), 1.0 / WATER)
    irradiance = 2 * math.pi * np.sum(transmitted * np.cos(theta) * np.sin(theta)) * (math.pi / 40_000)
    exact = (1 - F0) / WATER ** 2 * ALBEDO * irradiance / math.pi
    assert result.passes["caustic"][..., 0].mean() == pytest.approx(exact, rel=5e-3)


@pytest.mark.parametrize("bottom, basic", [(-0.1, 1 / WATER ** 2), (0.3, 1.0)], ids=["under water", "in the air"])
def test_a_map_under_water_holds_the_basic_irradiance_that_cycles_shows(bottom, basic):
    """A baked map is shown by Cycles and EEVEE, whose paths take no factor
    at refractions: a receiver inside a medium holds its basic irradiance
    E / n^2 (the floor under water: E = S (1 - F)), one in the air E, here
    S ((1 - F)^2 / (1 - F^2)) under the slab, in the image a bake writes."""
    floor = render(water_over_floor(bottom), RenderSettings()).maps["Floor"].irradiance()
    irradiance = SUN * ((1 - F0) if bottom < 0 else (1 - F0) ** 2 / (1 - F0 ** 2))
    h, w = floor.shape[:2]
    assert_uniform(floor[h // 3:2 * h // 3, w // 3:2 * w // 3], irradiance * basic)
