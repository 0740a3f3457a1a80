"""Lamps with a size met by eye rays, against closed forms: seen straight on
they have the radiance Cycles gives them, their glint in glass is that
radiance times Fresnel, and each kind of eye ray sees a lamp only where its
ray visibility allows."""

import math

import numpy as np
import pytest

from caustic_addon import (AreaLight, Camera, Dielectric, Diffuse, Object, PointLight, Reflector, RenderSettings,
                           Scene, SunLight, Visibility, World, render, shapes)
from caustic_addon.maps.cache import lamp_pass_key
from caustic_addon.optics.specular import fresnel_dielectric

POWER = 100.0
SEEN = Visibility(camera=True)


def far_floor() -> Object:
    """A small receiver out of sight, so that the scene has one."""
    return Object("Floor", shapes.plane(0.01, (0.0, 0.0, -50.0)), Diffuse(0.5))


def centre_pixel(objects, lamp, camera: Camera) -> np.ndarray:
    """(3,) the radiance at the middle of the image (its direct pass: the lamps)."""
    result = render(Scene([far_floor(), *objects], [lamp], camera, world=World(0.0)),
                    RenderSettings(spp=1, lamp_rays=1000))
    return result.passes["direct"][camera.pixy // 2, camera.pixx // 2]


def facing_camera(target=(0.0, 0.0, 0.0)) -> Camera:
    return Camera.look_at((0.0, -6.0, 0.0), target, pixx=16, pixy=16, fov=math.radians(5.0))


@pytest.mark.parametrize("lamp, radiance", [
    (AreaLight((0, 0, 0), (0.5, 0, 0), (0, 0, 0.25), (0, -1, 0), POWER, visibility=SEEN), POWER / (math.pi * 0.5)),
    (AreaLight((0, 0, 0), (0.5, 0, 0), (0, 0, 0.5), (0, -1, 0), POWER, "ELLIPSE", visibility=SEEN),
     POWER / (math.pi * math.pi * 0.25)),
    (PointLight((0, 0, 0), POWER, radius=0.3, visibility=SEEN), POWER / (4 * math.pi ** 2 * 0.09)),
    (PointLight((0, 0, 0), POWER, radius=0.3, soft_falloff=False, visibility=SEEN), POWER / (4 * math.pi ** 2 * 0.09)),
], ids=["rectangle", "ellipse", "point, soft falloff", "point, a sphere"])
def test_a_lamp_seen_by_the_camera_has_the_radiance_cycles_gives_it(lamp, radiance):
    """Area P / (pi A), point and spot P / (4 pi^2 r^2), as Cycles renders
    them with Camera visibility on (radiometry.py)."""
    assert centre_pixel([], lamp, facing_camera()) == pytest.approx(np.full(3, radiance), rel=1e-6)


def test_a_lamp_is_hidden_from_the_camera_by_default_and_an_area_lamp_from_behind():
    area = AreaLight((0, 0, 0), (0.5, 0, 0), (0, 0, 0.5), (0, -1, 0), POWER)
    assert not area.visibility.camera
    assert np.all(centre_pixel([], area, facing_camera()) == 0.0)
    behind = AreaLight((0, 0, 0), (0.5, 0, 0), (0, 0, 0.5), (0, 1, 0), POWER, visibility=SEEN)
    assert np.all(centre_pixel([], behind, facing_camera()) == 0.0)


def glass_block() -> Object:
    """Glass 2 m deep whose top is the plane z = 0."""
    return Object("Block", shapes.cylinder(20.0, 2.0, (0.0, 0.0, -2.0), 64), Dielectric(1.5))


def mirrored_area_lamp(visibility: Visibility) -> AreaLight:
    """A 3 m square lamp 5.7 m from the origin, facing it along (0, -1, -1),
    where the origin reflects a camera looking down at 45 degrees."""
    axis_y = np.array([0.0, 1.0, -1.0]) / math.sqrt(2.0)
    return AreaLight((0.0, 4.0, 4.0), (1.5, 0, 0), 1.5 * axis_y, (0, -1, -1), POWER, visibility=visibility)


@pytest.mark.parametrize("glossy", [True, False])
def test_a_lamps_glint_in_glass_is_its_radiance_times_fresnel(glossy):
    """A camera looking down at 45 degrees at a glass block sees the lamp's
    reflection, L F(45 degrees, 1.5); light that went into the glass and
    out again sees it by transmission, which the lamp here hides."""
    lamp = mirrored_area_lamp(Visibility(glossy=glossy, transmission=False))
    camera = Camera.look_at((0.0, -4.0, 4.0), (0.0, 0.0, 0.0), pixx=15, pixy=15, fov=math.radians(2.0))
    seen = centre_pixel([glass_block()], lamp, camera)
    fresnel = fresnel_dielectric(math.cos(math.radians(45.0)), 1.0 / 1.5).item()
    expected = POWER / (math.pi * 9.0) * fresnel if glossy else 0.0
    assert seen == pytest.approx(np.full(3, expected), rel=1e-3, abs=1e-12)


@pytest.mark.parametrize("transmission", [True, False])
def test_a_lamp_seen_through_a_glass_pane_is_its_radiance_times_both_transmittances(transmission):
    """Straight through a pane of IOR 1.5: L (1 - F0)^2, F0 = 0.04 (the
    light reflected back and forth inside is 0.16% more)."""
    lamp = AreaLight((0, 3, 0), (1.5, 0, 0), (0, 0, 1.5), (0, -1, 0), POWER,
                     visibility=Visibility(camera=False, transmission=transmission))
    pane = Object("Pane", shapes.cylinder(2.0, 0.5, (0.0, 0.0, 0.0), 64).transformed(
        np.array([[1.0, 0, 0, 0], [0, 0, -1, 0.5], [0, 1, 0, 0], [0, 0, 0, 1]])), Dielectric(1.5))
    seen = centre_pixel([pane], lamp, facing_camera())
    expected = POWER / (math.pi * 9.0) * 0.96 ** 2 if transmission else 0.0
    assert seen == pytest.approx(np.full(3, expected), rel=2e-3, abs=1e-12)


def test_a_suns_disc_is_seen_in_a_mirror_by_the_rays_that_leave_the_scene():
    """A sun of angle 10 degrees, L = S / (pi sin^2 5 degrees), in a mirror
    of reflectance 0.9 seen at 45 degrees."""
    sun = SunLight((0.0, -1.0, -1.0), 3.0, angle=math.radians(10.0))
    mirror = Object("Mirror", shapes.plane(20.0), Reflector(0.9))
    camera = Camera.look_at((0.0, -4.0, 4.0), (0.0, 0.0, 0.0), pixx=15, pixy=15, fov=math.radians(2.0))
    expected = 0.9 * 3.0 / (math.pi * math.sin(math.radians(5.0)) ** 2)
    assert centre_pixel([mirror], sun, camera) == pytest.approx(np.full(3, expected), rel=1e-6)


def test_a_lamps_visibility_leaves_the_maps_as_they_are():
    """Which eye rays see a lamp changes no map: two reads of one scene,
    each with its own Visibility, keep the maps of the first."""
    def scene(visibility):
        lamp = PointLight((0, 0, 2), POWER, radius=0.1, visibility=visibility)
        return Scene([far_floor()], [lamp], facing_camera(), world=World(0.0))
    settings = RenderSettings()
    assert lamp_pass_key(scene(Visibility(camera=True)), settings) == lamp_pass_key(scene(Visibility()), settings)
