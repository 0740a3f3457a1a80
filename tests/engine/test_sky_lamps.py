"""The sky as suns (emission/sky_lamps.py), against closed forms: regions
of equal light that tile the sky, suns that bring each region's irradiance
to a flat receiver, cells of the regions' solid angles; and what the maps
do with them: only the light that arrives on a floor's lit side, beams
spread in proportion to their image's area."""

import math
from dataclasses import replace

import numpy as np
import pytest

from caustic_addon import Dielectric, Diffuse, Mesh, Object, PointLight, RenderSettings, Scene, World, render, shapes
from caustic_addon.emission.aims import casters_and_bounds, flux_toward, sun_widening
from caustic_addon.emission.environment import environment_of
from caustic_addon.emission.sky_lamps import (MIN_REGIONS, REGION_RAYS, SKY_REGIONS, median_cut, region_count,
                                             sky_lamps)
from caustic_addon.emission.world_sun import extract_sun
from caustic_addon.maps.charts import PlaneChart
from caustic_addon.maps.receivers import facing_casters
from caustic_addon.passes.beam import SKY_SPREAD_PARTS, _spread_beams
from scenes import top_camera


def window_sky(h: int = 64, w: int = 128) -> np.ndarray:
    """A sky of radiance 0.5 with a window of 20 at rows 10..13, columns 30..37."""
    image = np.full((h, w, 3), 0.5)
    image[10:14, 30:38] = 20.0
    return image


def test_the_median_cut_tiles_the_sky_in_regions_of_equal_light():
    image = window_sky()
    h, w = image.shape[:2]
    theta = (np.arange(h) + 0.5) / h * math.pi
    weight = image[..., 0] * np.sin(theta)[:, None]
    boxes = median_cut(weight, 64, theta)
    covered = np.zeros((h, w), dtype=int)
    for r0, r1, c0, c1 in boxes:
        covered[r0:r1, c0:c1] += 1
    assert len(boxes) == 64 and (covered == 1).all()
    light = np.array([weight[r0:r1, c0:c1].sum() for r0, r1, c0, c1 in boxes])
    # equal to a pixel's light: a cut falls between pixels
    assert light.max() - light.min() < 4 * weight.max()
    # the window, an eighth of the sky's light on a 256th of its pixels, is cut finest
    size = np.zeros((h, w))
    for r0, r1, c0, c1 in boxes:
        size[r0:r1, c0:c1] = (r1 - r0) * (c1 - c0)
    assert size[10:14, 30:38].mean() < 0.5 * np.median(size)


@pytest.mark.parametrize("world", ["uniform", "window"])
@pytest.mark.parametrize("count", [MIN_REGIONS, SKY_REGIONS])
def test_the_skys_suns_bring_a_floor_the_skys_irradiance(world, count):
    """A horizontal floor under the sky gets E = int L cos(theta) dw over
    the upper hemisphere: pi for a uniform sky of radiance 1. The suns
    bring n . sum_i L_i Omega_i d_i, the same where each region's colour is
    even (the window's regions, cut coarser, straddle the horizon more),
    and their strengths sum to the scalar irradiance int L dw but for each
    region's spread (d_i . c <= 1), which falls as a region's solid angle:
    2% of it in 64 regions, under 0.5% in 256."""
    sky = World(1.0) if world == "uniform" else World(1.0, window_sky())
    suns = sky_lamps(sky, count)
    assert len(suns) == count
    image = np.ones((64, 128, 3)) if sky.environment is None else sky.environment
    h, w = image.shape[:2]
    theta = (np.arange(h) + 0.5) / h * math.pi
    pixel_sr = (2 * math.pi / w) * (math.pi / h) * np.sin(theta)
    upper = theta < math.pi / 2
    floor = (image[upper, :, 0] * (pixel_sr * np.cos(theta))[upper, None]).sum()
    brought = sum(sun.strength * sun.color[0] * max(0.0, -sun.direction[2]) for sun in suns)
    assert brought == pytest.approx(floor, rel=0.005 if count == SKY_REGIONS else 0.015)
    scalar = (image[..., 0] * pixel_sr[:, None]).sum()
    assert (1.0 - 1.5 / count) * scalar < sum(sun.strength for sun in suns) <= scalar
    assert all(sun.of_world for sun in suns)


def test_a_regions_cell_spans_its_solid_angle():
    for sun in sky_lamps(World(1.0), SKY_REGIONS):
        a, b, c, d = sun.cell
        flat = 0.5 * (np.linalg.norm(np.cross(b - a, c - a)) + np.linalg.norm(np.cross(c - a, d - a)))
        solid_angle = 2 * math.pi * (1 - math.cos(0.5 * sun.angle))
        assert flat == pytest.approx(solid_angle, rel=1e-9)


def test_a_black_sky_has_no_suns():
    assert sky_lamps(World(), SKY_REGIONS) == []
    assert sky_lamps(World(1.0, np.zeros((8, 16, 3))), SKY_REGIONS) == []



def test_a_world_that_comes_back_is_cut_once_and_a_changed_one_afresh():
    """Live and an animation read the world again for every update: the
    same environment array in a new World is cut into sun and sky regions
    once (emission/kept_worlds.py); a new array, or another colour, is
    another world."""
    image = np.full((64, 128, 3), 0.5)
    image[20, 30] = 5000.0
    sun, sky = extract_sun(World(1.0, image))
    again, sky_again = extract_sun(World(1.0, image))
    assert again is sun and sky_lamps(sky_again, SKY_REGIONS) is sky_lamps(sky, SKY_REGIONS)
    assert environment_of(World(1.0, image)) is environment_of(World(1.0, image))
    # the window a quarter turn further round the sky: its sun turns with it
    turned, _ = extract_sun(World(1.0, np.roll(image, 32, axis=1)))
    assert math.degrees(math.acos(np.clip(turned.direction @ sun.direction, -1, 1))) > 45.0
    brighter, brighter_sky = extract_sun(World(2.0, image))
    assert brighter.strength == pytest.approx(2.0 * sun.strength)
    assert sum(s.strength for s in sky_lamps(brighter_sky, SKY_REGIONS)) == pytest.approx(
        2.0 * sum(s.strength for s in sky_lamps(sky, SKY_REGIONS)))

def test_a_flat_receiver_holds_the_light_on_its_casters_side():
    floor = shapes.plane(4.0)
    chart = PlaneChart(np.zeros(3), np.array([0.0, 0.0, 1.0]), floor.vertices)
    above = Object("Above", shapes.uv_sphere(0.3, (0, 0, 1.0), 16, 8), Dielectric(1.5))
    below = Object("Below", shapes.uv_sphere(0.3, (0, 0, -1.0), 16, 8), Dielectric(1.5))
    np.testing.assert_array_equal(facing_casters(chart, [above]), [0.0, 0.0, 1.0])
    np.testing.assert_array_equal(facing_casters(chart, [below]), [0.0, 0.0, -1.0])
    assert facing_casters(chart, [above, below]) is None and facing_casters(chart, []) is None


def test_light_under_a_floor_does_not_show_on_it():
    """Water from 0.1 m below a floor to 0.4 m above it, lit only from
    below by a sky that is black above the horizon: the light that
    enters the water's bottom reaches the floor's underside, and its top,
    which the camera sees, stays dark."""
    image = np.zeros((32, 64, 3))
    image[16:] = 1.0
    water = Object("Water", shapes.wavy_slab(20.0, 0.5, waves=(), cells=1, center=(0, 0, -0.1)), Dielectric(1.33))
    scene = Scene([Object("Floor", shapes.plane(40.0), Diffuse(albedo=1.0)), water], [],
                  top_camera(0.5, 4, 1.0), world=World(1.0, image))
    result = render(scene, RenderSettings(spp=1, world_samples=4))
    assert result.stats["lamp_rays"] > 0
    assert result.passes["caustic"].max() == 0.0


def test_a_spread_beams_parts_share_its_light_by_their_area():
    """A beam spread over a triangle (a quadrilateral with two corners in
    one, as a sky region's cell at the pole is): its copies' light sums to
    the beam's, and its centroid is the triangle's, 2/3 of the way from the
    doubled corner, where equal shares per part would put it halfway."""
    beam = np.array([[[-0.01, -0.01], [0.01, -0.01], [0.0, 0.01]]])
    spread = np.array([[[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [-1.0, 1.0]]])
    triangles, light, hulls, hull_light = _spread_beams(beam, np.ones((1, 3)), spread,
                                                        np.array([SKY_SPREAD_PARTS]), 1e-3)
    beam_area = 2e-4
    flux, moment = 0.0, 0.0
    for polygons, values in ((triangles, light), (hulls, hull_light)):
        for polygon, value in zip(polygons, values):
            area, centroid_y = _area_and_centroid_y(polygon)
            flux += value[0] * area
            moment += value[0] * area * centroid_y
    assert flux == pytest.approx(beam_area, rel=1e-6)
    assert moment / flux == pytest.approx(2.0 / 3.0, abs=0.05)


def _area_and_centroid_y(polygon: np.ndarray) -> tuple[float, float]:
    """(area, y of the centroid) of the polygon `polygon (k,2)`, its corners
    in order (a repeated corner adds nothing)."""
    x, y = polygon[:, 0], polygon[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * cross.sum()
    return abs(area), float(((y + np.roll(y, -1)) * cross).sum() / (6.0 * area))


def test_light_energy_leaves_the_skys_caustic_alone():
    """Light Energy multiplies the lights, not the world, nor the suns
    taken from it: the sky's caustic is the same at any Energy."""
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 32, 16), Dielectric(1.5))
    scene = Scene([Object("Floor", shapes.plane(4.0), Diffuse(albedo=1.0)), ball], [], top_camera(0.5, 4),
                  world=World(1.0))
    caustic = [render(scene, RenderSettings(spp=1, world_samples=1, energy=energy)).passes["caustic"]
               for energy in (1.0, 3.0)]
    assert caustic[0].max() > 0.05
    np.testing.assert_array_equal(caustic[0], caustic[1])


def test_however_few_the_regions_none_spans_more_than_a_quarter_turn():
    """Two regions of the window sky: the window's half and the rest, each
    wider than a quarter turn, are cut on until none is."""
    image = window_sky()
    h, w = image.shape[:2]
    theta = (np.arange(h) + 0.5) / h * math.pi
    boxes = median_cut(image[..., 0] * np.sin(theta)[:, None], 2, theta)
    covered = np.zeros((h, w), dtype=int)
    for r0, r1, c0, c1 in boxes:
        covered[r0:r1, c0:c1] += 1
    assert (covered == 1).all() and len(boxes) >= 4
    assert max(c1 - c0 for _, _, c0, c1 in boxes) <= w // 4


def ball_under_a_lamp(world: World) -> Scene:
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 32, 16), Dielectric(1.5))
    return Scene([Object("Floor", shapes.plane(4.0), Diffuse(albedo=1.0)), ball],
                 [PointLight(np.array([0.0, 0.0, 3.0]), 400.0)], top_camera(0.5, 4), world=world)


def test_a_dim_sky_beside_a_lamp_is_cut_into_fewer_regions_that_each_get_a_grid():
    """The regions follow the sky's share of the lamp rays: a sky alone is
    SKY_REGIONS at 40,000 of them; a dim world beside a lamp gets the power
    of two that gives each region about REGION_RAYS of its share, more at
    more rays, never under MIN_REGIONS."""
    scene = ball_under_a_lamp(World(0.05))
    targets, sphere = casters_and_bounds(scene)
    assert region_count(scene.world, [], targets, sphere, 40_000) == SKY_REGIONS
    sky_flux = math.pi * 0.3 ** 2 * sum(r.strength * sun_widening(r.angle) ** 2
                                        for r in sky_lamps(scene.world, SKY_REGIONS))
    share = sky_flux / (sky_flux + flux_toward(scene.lights[0], targets, sphere))
    assert 0.05 < share < 0.5
    counts = {rays: region_count(scene.world, scene.lights, targets, sphere, rays) for rays in (5_000, 80_000, 160_000)}
    assert counts[5_000] == MIN_REGIONS
    for rays in (80_000, 160_000):
        assert counts[rays] & (counts[rays] - 1) == 0
        assert REGION_RAYS <= share * rays / counts[rays] < 2 * REGION_RAYS
    assert counts[80_000] < counts[160_000]


def test_a_skys_fewest_regions_bring_its_caustic_the_light_of_the_most():
    """The sky alone at 4,000 lamp rays is cut into MIN_REGIONS regions:
    its light through the ball onto the floor is within 6% of the
    converged caustic's, SKY_REGIONS regions at 80,000 rays. It is low by
    a region's mean cosine (a sun brings a flat receiver facing it the
    region's irradiance, and a ball the region's light times that cosine:
    2% in 64 regions), and by what grids of 60 rays miss at the ball's rim."""
    scene = replace(ball_under_a_lamp(World(0.05)), lights=[])
    targets, sphere = casters_and_bounds(scene)
    assert region_count(scene.world, [], targets, sphere, 4000) == MIN_REGIONS
    assert region_count(scene.world, [], targets, sphere, 80_000) == SKY_REGIONS

    def flux(rays: int) -> float:
        settings = RenderSettings(lamp_rays=rays, spp=1, eye_pass=False, map_resolution_limit=256)
        imap = render(scene, settings).maps["Floor"]
        return float(imap.irradiance()[..., 0].sum() * imap.cell ** 2)

    assert flux(4000) == pytest.approx(flux(80_000), rel=0.06)


def test_a_glass_of_no_area_under_a_sky_is_named_and_renders():
    """A glass whose faces are all one point has a target of no size: the
    sky's share of the rays toward it is none, and the render says why the
    glass casts nothing rather than failing."""
    point = Mesh(np.full((3, 3), [0.0, 0.0, 1.0]), np.array([[0, 1, 2]]))
    scene = Scene([Object("Floor", shapes.plane(4.0), Diffuse()), Object("Dot", point, Dielectric(1.5))], [],
                  top_camera(0.5, 4), world=World(0.05))
    result = render(scene, RenderSettings(lamp_rays=5000, spp=1, world_samples=1))
    assert any("'Dot' has no area" in w for w in result.warnings)
