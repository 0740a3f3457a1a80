"""Lamps with a size and the world's light, against closed forms: the eye
pass's direct light (radiance = albedo E / pi on a white floor seen from
above), the photon and beam passes' light from sized lamps, and the limits
that must hold as a size goes to 0."""

import math

import numpy as np
import pytest

from caustic_addon import (AreaLight, Dielectric, Diffuse, Object, PointLight, RenderSettings, Scene, Specular,
                           SpotLight, SunLight, Visibility, World, render, shapes)
from caustic_addon.emission.environment import Environment, uv_to_directions
from caustic_addon.emission.lamp_samples import sample_lamp
from caustic_addon.emission.world_sun import extract_sun
from caustic_addon.optics.specular import fresnel_dielectric
from caustic_addon.passes import world_paths
from caustic_addon.sampling.sequences import r2_sequence
from scenes import floor_points, top_camera

HEIGHT = 2.0
POWER = 400.0


def floor_scene(lamp, half_width=1.0, pixels=32, objects=(), world=None, camera_height=20.0, floor=40.0) -> Scene:
    return Scene([Object("Floor", shapes.plane(floor), Diffuse(albedo=1.0)), *objects], [lamp] if lamp else [],
                 top_camera(half_width, pixels, camera_height), world=world or World())


def floor_irradiance(scene: Scene, **settings) -> np.ndarray:
    """(pixy, pixx) W/m^2 on the white floor: the render's direct light times pi."""
    result = render(scene, RenderSettings(**{"spp": 1, "lamp_rays": 1000, **settings}))
    return (result.passes["direct"] + result.passes["ambient"])[..., 0] * math.pi


def test_a_soft_falloff_lamp_lights_its_axis_as_cycles_does():
    """Cycles' soft falloff: a disc of radius r facing the point, radiance
    P / (4 pi^2 r^2), gives P / (4 pi (d^2 + r^2)) on its axis."""
    for radius in (0.2, 0.8):
        lamp = PointLight((0, 0, HEIGHT), POWER, radius=radius)
        centre = floor_irradiance(floor_scene(lamp, 0.02, 2), lamp_samples=512)
        assert centre.mean() == pytest.approx(POWER / (4 * math.pi * (HEIGHT ** 2 + radius ** 2)), rel=0.005)


def test_a_sphere_lamp_lights_the_floor_as_a_point_lamp_does():
    """Soft Falloff off: a uniform sphere's irradiance is the point law
    wherever all of it is above the horizon (Nusselt)."""
    lamp = PointLight((0, 0, HEIGHT), POWER, radius=0.5, soft_falloff=False)
    scene = floor_scene(lamp, 1.0, 8)
    xy = floor_points(scene)
    d2 = (xy ** 2).sum(axis=-1) + HEIGHT ** 2
    exact = POWER / (4 * math.pi) * HEIGHT / d2 ** 1.5
    np.testing.assert_allclose(floor_irradiance(scene, lamp_samples=256), exact, rtol=0.01)


def test_a_disc_area_lamp_lights_its_axis_by_the_closed_form():
    """A one-sided Lambertian disc of radius a and radiance L = P / (pi pi a^2):
    E = pi L a^2 / (h^2 + a^2) on its axis."""
    a = 0.6
    lamp = AreaLight((0, 0, HEIGHT), (a, 0, 0), (0, a, 0), (0, 0, -1), POWER, "ELLIPSE")
    centre = floor_irradiance(floor_scene(lamp, 0.02, 2), lamp_samples=512)
    assert centre.mean() == pytest.approx(POWER / (math.pi * (HEIGHT ** 2 + a ** 2)), rel=0.005)


def test_a_square_area_lamp_lights_its_centre_by_the_view_factor():
    """Under the centre of a square of side s at height h, E = pi L F with the
    view factor F = (2 / pi) (A / sqrt(1 + A^2)) atan(1 / sqrt(1 + A^2)) x 2,
    A = s / (2 h) (Howell's catalogue, a parallel rectangle, by quarters)."""
    side = 1.2
    lamp = AreaLight((0, 0, HEIGHT), (side / 2, 0, 0), (0, side / 2, 0), (0, 0, -1), POWER)
    x = side / (2 * HEIGHT)
    quarter = (1 / (2 * math.pi)) * (x / math.sqrt(1 + x * x) * math.atan(x / math.sqrt(1 + x * x)) * 2)
    radiance = POWER / (math.pi * side ** 2)
    centre = floor_irradiance(floor_scene(lamp, 0.02, 2), lamp_samples=512)
    assert centre.mean() == pytest.approx(math.pi * radiance * 4 * quarter, rel=0.005)


def test_an_area_lamp_is_one_sided():
    lamp = AreaLight((0, 0, HEIGHT), (0.5, 0, 0), (0, 0.5, 0), (0, 0, 1), POWER)
    assert floor_irradiance(floor_scene(lamp, 0.5, 4), lamp_samples=16).max() == 0.0


def test_a_disc_lamps_penumbra_over_a_straight_edge_is_the_visible_part_of_the_disc():
    """A small disc lamp (radius a, height h) over an opaque half-plane at
    height z: at offset x from the edge's shadow line, the lamp shows the
    part of its disc beyond the line seen through the edge, a circular
    segment at distance s = x (h - z) / z from the disc's centre: its area
    fraction (theta - sin theta) / (2 pi), theta = 2 acos(s / a)."""
    a, z = 0.1, 1.0
    lamp = AreaLight((0, 0, HEIGHT), (a, 0, 0), (0, a, 0), (0, 0, -1), POWER, "ELLIPSE")
    wall = Object("Edge", shapes.plane(10.0, (-5.0, 0.0, z)), Diffuse(albedo=0.0, receiver=False))
    scene = floor_scene(lamp, 0.3, 30, [wall], camera_height=0.5)
    measured = floor_irradiance(scene, lamp_samples=1024)
    x = floor_points(scene)[..., 0]
    open_floor = floor_irradiance(floor_scene(lamp, 0.3, 30), lamp_samples=256)
    s = np.clip(x * (HEIGHT - z) / z / a, -1.0, 1.0)
    theta = 2.0 * np.arccos(s)
    visible = 1.0 - (theta - np.sin(theta)) / (2.0 * math.pi)
    np.testing.assert_allclose(measured, open_floor * visible, atol=0.01 * open_floor.max())
    penumbra = np.abs(s) < 0.9
    assert penumbra.sum() > 100


def test_a_sun_with_an_angle_gives_its_strength_to_a_surface_facing_it():
    sun = SunLight((0, 0, -1), 3.0, angle=math.radians(20))
    np.testing.assert_allclose(floor_irradiance(floor_scene(sun, 0.5, 4), lamp_samples=64), 3.0, rtol=1e-3)
    tilted = SunLight((math.sin(0.6), 0, -math.cos(0.6)), 3.0, angle=math.radians(10))
    np.testing.assert_allclose(floor_irradiance(floor_scene(tilted, 0.5, 4), lamp_samples=512),
                               3.0 * math.cos(0.6), rtol=2e-3)


def test_a_spot_masks_each_point_of_its_disc():
    """Cycles evaluates the spot's cone from each sampled point of the lamp:
    on the floor under the cone's edge the irradiance is the disc's
    integral of the mask, not the centre's mask times the disc's light."""
    lamp = SpotLight((0, 0, HEIGHT), (0, 0, -1), POWER, math.radians(40), 0.3, radius=0.3)
    points = np.array([[x, 0.0, 0.0] for x in np.linspace(0.4, 1.0, 7)])
    rng = np.random.default_rng(1)
    estimates = [sample_lamp(lamp, 1.0, points, rng.random((len(points), 2)), 100.0) for _ in range(4000)]
    mean = np.mean([e.irradiance[:, 0] * np.maximum(e.dirs[:, 2], 0.0) for e in estimates], axis=0)
    # quadrature over the disc facing each point, with the mask per disc point
    u, v = np.meshgrid((np.arange(200) + 0.5) / 200, (np.arange(200) + 0.5) / 200)
    r, phi = 0.3 * np.sqrt(u.ravel()), 2 * math.pi * v.ravel()
    exact = []
    for p in points:
        axis = (p - lamp.position) / np.linalg.norm(p - lamp.position)
        t = np.cross(axis, [0.0, 1.0, 0.0])
        t /= np.linalg.norm(t)
        b = np.cross(axis, t)
        q = lamp.position + (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b
        d = p - q
        dist = np.linalg.norm(d, axis=1)
        cos_mask = (d / dist[:, None]) @ lamp.direction
        half = math.cos(math.radians(20))
        mask = np.clip((cos_mask - half) / ((1 - half) * lamp.blend), 0, 1)
        mask = mask * mask * (3 - 2 * mask)
        radiance = POWER / (4 * math.pi ** 2 * 0.09)
        exact.append(np.mean(radiance * mask * (d @ axis / dist) * (-d[:, 2] / dist) * math.pi * 0.09 / dist ** 2))
    np.testing.assert_allclose(mean, exact, rtol=0.03, atol=0.002 * max(exact))


def test_an_open_floor_under_a_uniform_world_has_radiance_albedo_times_the_world():
    scene = Scene([Object("Floor", shapes.plane(40.0), Diffuse(albedo=0.6))], [], top_camera(0.5, 4),
                  world=World((0.5, 1.0, 2.0)))
    result = render(scene, RenderSettings(spp=1, world_samples=64))
    np.testing.assert_allclose(result.passes["ambient"].reshape(-1, 3), np.tile([0.3, 0.6, 1.2], (16, 1)), rtol=1e-6)


def test_the_world_is_seen_where_eye_rays_leave_and_occluded_under_a_roof():
    """A roof of half-width w at height z over the floor's centre hides the
    sky within angle atan(w / z) of the zenith in x: a 2D slot, whose
    visible share of the cosine-weighted hemisphere at the centre is
    1 - sin(atan(w / z)) along x for an infinitely long roof in y."""
    w, z = 0.5, 1.0
    roof = Object("Roof", shapes.plane(1.0, (0.0, 0.0, z)), Diffuse(albedo=0.0, receiver=False))
    roof.mesh = roof.mesh.transformed(np.diag([1.0, 200.0, 1.0, 1.0]))
    scene = Scene([Object("Floor", shapes.plane(400.0), Diffuse(albedo=1.0)), roof], [],
                  top_camera(0.01, 2, height=0.5), world=World(1.0))
    result = render(scene, RenderSettings(spp=4, world_samples=256))
    assert result.passes["ambient"][..., 0].mean() == pytest.approx(1.0 - math.sin(math.atan(w / z)), abs=0.01)
    sky = render(Scene([], [], top_camera(0.5, 4), world=World(0.25)), RenderSettings(spp=1))
    np.testing.assert_allclose(sky.image[..., :3].ravel(), 0.25)


def sun_in_the_sky(rows=slice(20, 23), cols=slice(127, 130), radiance=1000.0):
    """(image (128, 256, 3), to_sky (3,), irradiance W/m^2, solid angle sr)
    of a sky that is black but for a patch of pixels."""
    h, w = 128, 256
    image = np.zeros((h, w, 3))
    image[rows, cols] = radiance
    theta = (np.arange(h) + 0.5) / h * math.pi
    solid_angle = (2 * math.pi / w) * (math.pi / h) * np.sin(theta[rows]).sum() * (cols.stop - cols.start)
    centre = np.array([[0.5 * (cols.start + cols.stop) / w, 0.5 * (rows.start + rows.stop) / h]])
    return image, uv_to_directions(centre)[0], radiance * solid_angle, solid_angle


def test_an_environment_samples_its_light_in_proportion_to_it():
    """The estimate sum L(w) / p(w) / n of the world's light is its
    integral, and each sample of a uniform pixel carries the same weight
    but for sin(theta) within the pixel: the light is the pixel's own
    value, as the density is. (With the bilinear lookup the camera sees,
    the density missed the half-pixel rim, 16% of a 3 x 3 pixel sun, and
    each sample of the sun weighed differently: a grainy floor.)"""
    image, _, irradiance, _ = sun_in_the_sky()
    environment = Environment(World(1.0, image))
    dirs, density = environment.sample(r2_sequence(np.arange(200_000), np.zeros(2)))
    weight = environment.light(dirs)[:, 0] / density
    assert weight.mean() == pytest.approx(irradiance, rel=1e-3)
    on_sun = weight > 0
    assert on_sun.mean() == 1.0
    # sin(theta) spans cot(theta) d(theta) = 4% across a pixel row 30 degrees from the zenith
    assert weight.std() / weight.mean() < 0.02
    np.testing.assert_allclose(environment.density(dirs), density, rtol=1e-9)


def test_an_hdris_sun_is_taken_out_as_a_sun_lamp_and_an_overcast_sky_is_not():
    image, to_sky, irradiance, solid_angle = sun_in_the_sky()
    image += 0.5
    sun, rest = extract_sun(World(2.0, image))
    assert sun.strength == pytest.approx(2.0 * (irradiance + 0.5 * solid_angle))
    assert sun.angle == pytest.approx(2 * math.acos(1 - solid_angle / (2 * math.pi)))
    assert math.degrees(math.acos(-sun.direction @ to_sky)) < 0.05
    assert rest.environment.max() == 0.5 and (rest.environment == 0).sum() == 27
    overcast = np.full((64, 128, 3), 1.0)
    overcast[20, 60] = 20.0
    assert extract_sun(World(1.0, overcast))[0] is None
    assert extract_sun(World(1.0))[0] is None


def test_the_white_furnace_under_index_matched_glass_is_balanced_by_the_skys_suns():
    """Under a uniform world of radiance 1, a white floor has radiance 1
    everywhere, glass of index 1 or not: the world's shadow rays bring what
    the glass leaves open, and the sky's suns (emission/sky_lamps.py) what
    it hides, through it into the map. Nothing is counted twice and nothing
    dropped: the mean is 1, and so is every block of 4 x 4 pixels but for
    the cells' first-order spread and the world's samples."""
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 64, 32), Dielectric(1.0))
    scene = floor_scene(None, 1.0, 32, [ball], world=World(1.0), floor=4.0)
    result = render(scene, RenderSettings(spp=1, world_samples=64))
    assert result.stats["lamp_rays"] > 0
    assert result.passes["caustic"][..., 0].max() > 0.1
    total = (result.passes["ambient"] + result.passes["caustic"])[..., 0]
    assert total.mean() == pytest.approx(1.0, rel=0.005)
    np.testing.assert_allclose(total.reshape(8, 4, 8, 4).mean(axis=(1, 3)), 1.0, rtol=0.03)


@pytest.mark.parametrize("metallic", [1.0, 0.5])
def test_a_metal_floor_under_index_matched_glass_in_the_white_furnace_gives_back_all_light(metallic, monkeypatch):
    """The same furnace with a Principled floor of Base Color 1, IOR 1 and
    Roughness 0.3: its metal gives back all the light its lobe gathers,
    through the glass too (passes/world_paths.py), and its diffuse base
    what the map holds. Where that lobe's paths through the glass are
    followed with a chance of 1/4, the mean stays."""
    monkeypatch.setattr(world_paths.WorldThroughCasters, "chances",
                        lambda self, glossy, lit: np.where(glossy > 0, 0.25, 0.0))
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 64, 32), Dielectric(1.0))
    floor = Object("Floor", shapes.plane(4.0), Diffuse(1.0, specular=Specular(roughness=0.3, ior=1.0,
                                                                                   metallic=metallic)))
    scene = Scene([floor, ball], [], top_camera(0.5, 16), world=World(1.0))
    result = render(scene, RenderSettings(spp=4, world_samples=64))
    assert result.passes["caustic"][..., 0].mean() > 0.1
    total = (result.passes["ambient"] + result.passes["caustic"])[..., 0]
    assert total.mean() == pytest.approx(1.0, rel=0.01)


def _under_a_pane(n: float, half: float, height: float, points: np.ndarray) -> np.ndarray:
    """(k,) a white floor's radiance at `points (k,2)` under a square glass
    pane of index `n`, half-width `half` and height `height` centred over
    the origin, in a uniform world of radiance 1: (1 / pi) int int X
    cos(theta) sin(theta) dtheta dphi over the hemisphere, X = T(theta) =
    (1 - R) / (1 + R) (the pane's transmittance with every internal
    reflection, R the unpolarised Fresnel reflectance at theta) where the
    pane covers the sky, below atan(d(phi) / height), d the distance to its
    edge along phi, and 1 beyond it."""
    theta = (np.arange(2000) + 0.5) / 2000 * (math.pi / 2)
    phi = (np.arange(360) + 0.5) / 360 * (2 * math.pi)
    reflectance = fresnel_dielectric(np.cos(theta), 1.0 / n)
    along = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    out = []
    for point in points:
        with np.errstate(divide="ignore"):
            reach = np.where(along > 0, (half - point) / along, (-half - point) / along)
        edge = np.arctan(np.min(np.where(np.isfinite(reach), reach, np.inf), axis=1) / height)
        seen = np.where(theta[None, :] < edge[:, None], ((1 - reflectance) / (1 + reflectance))[None, :], 1.0)
        out.append((seen * (np.cos(theta) * np.sin(theta))[None, :]).sum() * (math.pi / 4000) * (2 * math.pi / 360)
                   / math.pi)
    return np.array(out)


def test_the_skys_light_through_a_glass_pane_is_the_panes_transmittance():
    """Under a 4 m glass pane, n = 1.5, 1 m above a white floor in a
    uniform world of radiance 1, the floor's 1 m square beneath its centre
    has the mean radiance of `_under_a_pane`: the sky's suns bring what
    the pane lets through, with every internal reflection, and the world's
    shadow rays the sky beyond its edge."""
    pane = Object("Pane", shapes.wavy_slab(4.0, 0.05, waves=(), cells=1, center=(0, 0, 1.0)), Dielectric(1.5))
    scene = floor_scene(None, 0.5, 16, [pane], world=World(1.0), camera_height=0.5, floor=40.0)
    result = render(scene, RenderSettings(spp=1, world_samples=64, max_depth=32))
    total = (result.passes["ambient"] + result.passes["caustic"])[..., 0]
    assert result.passes["caustic"][..., 0].mean() > 0.5
    expected = _under_a_pane(1.5, 2.0, 1.0, floor_points(scene)[::3, ::3].reshape(-1, 2)).mean()
    assert total.mean() == pytest.approx(expected, rel=0.01)


@pytest.mark.parametrize("density", ["beam", "adaptive"])
def test_a_sun_in_an_hdri_throws_the_caustic_of_a_sun_lamp(density):
    """A 3 x 3 pixel patch of a black sky, 30 degrees from the zenith, and
    a sun lamp from its centre of the same irradiance and solid angle throw
    the same caustic through a glass ball: the same flux, and the same
    picture but for the patch's shape and, with photons, their noise."""
    image, to_sky, irradiance, solid_angle = sun_in_the_sky()
    centre = np.array([0.0, 0.0, 0.8]) + 0.8 / to_sky[2] * to_sky
    ball = Object("Ball", shapes.uv_sphere(0.3, (centre[0], centre[1], 0.8), 64, 32), Dielectric(1.5))
    sun = SunLight(-to_sky, irradiance, angle=2 * math.acos(1 - solid_angle / (2 * math.pi)))
    # beams need no more rays to be exact, photons as many as their noise asks
    settings = RenderSettings(spp=1, lamp_rays=100_000 if density == "beam" else 400_000, density=density)
    from_sky = render(floor_scene(None, 0.5, 48, [ball], world=World(1.0, image), floor=4.0),
                      settings).passes["caustic"][..., 0]
    from_sun = render(floor_scene(sun, 0.5, 48, [ball], floor=4.0),
                      settings).passes["caustic"][..., 0]
    assert from_sky.sum() == pytest.approx(from_sun.sum(), rel=0.02)
    # beams take the sky's sun as a sun lamp: the same caustic, without the photons' noise
    assert np.abs(from_sky - from_sun).sum() < (0.01 if density == "beam" else 0.1) * from_sun.sum()


SIZED = [AreaLight((0, 0, HEIGHT), (0.3, 0, 0), (0, 0.3, 0), (0, 0, -1), POWER),
         PointLight((0, 0, HEIGHT), POWER, radius=0.3, soft_falloff=False),
         SunLight((0, 0, -1), 5.0, angle=0.3)]


@pytest.mark.parametrize("lamp", SIZED, ids=["area", "sphere", "sun"])
def test_beams_from_a_sized_lamp_through_index_matched_glass_are_its_direct_light(lamp):
    """Glass of index 1 bends nothing and reflects nothing: the caustic it
    throws on the floor is the direct light its shadow ray misses, pixel by
    pixel, for beams from every point of a lamp with a size. (Before the
    beam grid's cells were cut along the concentric map's diagonals, a
    dotted seam ran across this caustic, 20% off either way.)"""
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 64, 32), Dielectric(1.0))
    # a 2 m floor: map cells of 2 mm against the pixels' 25 mm
    scene = floor_scene(lamp, 0.1, 8, [ball], floor=2.0)
    caustic = render(scene, RenderSettings(spp=1, lamp_rays=200_000)).passes["caustic"][..., 0] * math.pi
    open_floor = floor_irradiance(floor_scene(lamp, 0.1, 8, floor=2.0), lamp_samples=512)
    np.testing.assert_allclose(caustic, open_floor, rtol=0.02)


def test_beams_from_a_point_lamp_have_no_seam():
    """The same for a point lamp, at 16 x 16 pixels. The residue, under 3%,
    is a ring of pixels around the aim's axis, where the concentric map's
    innermost cells bend most (a sector drawn as a triangle)."""
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 64, 32), Dielectric(1.0))
    lamp = PointLight((0, 0, HEIGHT), POWER)
    caustic = render(floor_scene(lamp, 0.1, 16, [ball], floor=2.0),
                     RenderSettings(spp=1, lamp_rays=200_000)).passes["caustic"][..., 0] * math.pi
    open_floor = floor_irradiance(floor_scene(lamp, 0.1, 16, floor=2.0))
    np.testing.assert_allclose(caustic, open_floor, rtol=0.03)


@pytest.mark.parametrize("lamp", SIZED, ids=["area", "sphere", "sun"])
def test_photons_from_a_sized_lamp_through_index_matched_glass_carry_its_direct_light(lamp):
    """The same with photons, whose adaptive estimate of k = 64 has about
    1 / sqrt(64) = 12.5% noise per pixel: the mean over the 64 pixels agrees
    within 3%, and each pixel within four times the noise."""
    ball = Object("Ball", shapes.uv_sphere(0.3, (0, 0, 0.8), 64, 32), Dielectric(1.0))
    scene = floor_scene(lamp, 0.1, 8, [ball], floor=2.0)
    result = render(scene, RenderSettings(spp=1, lamp_rays=2_000_000, density="adaptive"))
    ratio = result.passes["caustic"][..., 0] * math.pi / floor_irradiance(floor_scene(lamp, 0.1, 8, floor=2.0),
                                                                         lamp_samples=512)
    assert ratio.mean() == pytest.approx(1.0, abs=0.03)
    assert np.abs(ratio - 1.0).max() < 4 * 0.125


RIMMED = [AreaLight((0, 0, 4.0), (0.2, 0, 0), (0, 0.2, 0), (0, 0, -1), 300.0),
          PointLight((0, 0, 4.0), 300.0, radius=0.2, soft_falloff=False),
          SunLight((0, 0, -1), 5.0, angle=0.05)]


@pytest.mark.parametrize("lamp", RIMMED, ids=["area", "sphere", "sun"])
def test_beams_from_a_sized_lamp_keep_the_light_of_the_glass_rim(lamp):
    """A glass ball lit by a lamp with a size, at the default lamp rays: each
    point of the lamp has a grid of some 200 rays, and the light the ball's
    rim reflects onto the floor around it comes from the outer few percent
    of its radius, thinner than a grid cell. Every point laid the same grid
    over the ball, so all of them missed the rim together: the area lamp's
    floor got 6.4% less light than photons give, and none of the ring
    around the ball. Each point's grid now sits at its own fraction of a
    cell, and between them they sample the rim. Against 2M photons: the
    light landed on the floor within 1.2%, and the floor around the ball
    (0.7 m to 3 m from its axis, in view) within 15%."""
    ball = Object("Ball", shapes.uv_sphere(0.6, (0, 0, 0.6), 96, 48), Dielectric(1.5),
                  Visibility(camera=False))
    scene = floor_scene(lamp, 3.0, 48, [ball], floor=8.0)
    xy = floor_points(scene)
    around = (np.hypot(xy[..., 0], xy[..., 1]) >= 0.7)[..., None]
    beams = render(scene, RenderSettings(spp=1, lamp_rays=40_000))
    photons = render(scene, RenderSettings(spp=1, lamp_rays=2_000_000, density="adaptive"))
    assert beams.stats["flux_landed_w"][0] == pytest.approx(photons.stats["flux_landed_w"][0], rel=0.012)
    assert (beams.passes["caustic"] * around).sum() == pytest.approx((photons.passes["caustic"] * around).sum(),
                                                                     rel=0.15)


def test_a_sized_lamps_caustic_tends_to_the_point_lamps_as_its_size_goes_to_0():
    ball = Object("Ball", shapes.uv_sphere(0.5, (0, 0, 1.0), 64, 32), Dielectric(1.5))

    def caustic(radius):
        lamp = PointLight((0, 0, 4.0), POWER, radius=radius)
        # no edge samples: the pixels they refine follow the shadow, which the lamp's size softens
        return render(floor_scene(lamp, 0.6, 24, [ball]),
                      RenderSettings(spp=1, lamp_rays=40_000, edge_samples=0)).passes["caustic"]

    point = caustic(0.0)
    errors = [np.abs(caustic(r) - point).mean() / point.mean() for r in (0.3, 0.1, 0.03, 0.01)]
    # a small lamp's penumbra is under a map cell: one point of it, its centre
    assert errors[0] > errors[1] >= errors[2] >= errors[3] == 0.0


def test_a_lamp_of_size_0_renders_as_before():
    """radius 0 takes the point lamp's exact path: one shadow ray, no
    stratification, whatever lamp_samples says."""
    lamp = PointLight((0.3, 0.2, HEIGHT), POWER)
    first = render(floor_scene(lamp), RenderSettings(spp=1, lamp_samples=1))
    second = render(floor_scene(lamp), RenderSettings(spp=1, lamp_samples=32))
    np.testing.assert_array_equal(first.image, second.image)
