"""Lamps and cameras inside closed glass: their rays start in the glass, so
they are absorbed on their way out and refract as they leave."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, Scene, render, shapes
from caustic_addon.tracing.accelerator import Accelerator
from caustic_addon.tracing.hits import MISS
from caustic_addon.tracing.topology import triangle_normals

from scenes import quick

SIGMA = 2.0  # per metre
RADIUS = 1.0
CENTER = np.array([0.0, 0.0, 1.5])
SEGMENTS = 64


def nested_spheres() -> list[Object]:
    return [Object("Floor", shapes.plane(10.0), Diffuse()),
            Object("Ball", shapes.uv_sphere(RADIUS, CENTER, SEGMENTS, SEGMENTS // 2), Dielectric(1.5)),
            Object("Core", shapes.uv_sphere(0.3, CENTER, 16, 8), Dielectric(1.2))]


def test_medium_at_finds_the_innermost_closed_glass_around_each_point():
    accel = Accelerator(nested_spheres(), 12.0)
    points = CENTER + np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.5], [0.6, 0.0, 0.0], [0.0, 0.0, 1.5],
                                [0.0, 0.0, -1.2], [3.0, 3.0, 3.0]])
    np.testing.assert_array_equal(accel.medium_at(points), [2, 1, 1, MISS, MISS, MISS])
    accel.close()


def absorbing_sphere_scene(sigma: float, camera: Camera, lamp=CENTER) -> Scene:
    """An index-matched (IOR 1) sphere that absorbs `sigma` per metre above
    a floor, with a point lamp at its centre or at `lamp`."""
    glass = shapes.uv_sphere(RADIUS, CENTER, SEGMENTS, SEGMENTS // 2)
    return Scene([Object("Floor", shapes.plane(10.0), Diffuse()),
                  Object("Glass", glass, Dielectric(1.0, absorption=sigma))],
                 [PointLight(lamp, 1000.0)], camera)


def chord_bounds() -> tuple[float, float]:
    """exp(-sigma r) for the farthest and nearest points of the faceted
    sphere from its centre: its vertices lie at R, and no face is nearer
    than its plane's distance from the centre."""
    mesh = shapes.uv_sphere(RADIUS, CENTER, SEGMENTS, SEGMENTS // 2)
    normals, area = triangle_normals(mesh.corners)
    planes = np.abs(np.einsum("ij,ij->i", normals, mesh.corners[:, 0] - CENTER))[area > 0]
    return math.exp(-SIGMA * RADIUS), math.exp(-SIGMA * planes.min())


@pytest.mark.parametrize("density", ["splat", "beam"])
def test_a_lamp_inside_absorbing_glass_is_dimmed_by_the_radius_it_crosses(density):
    """Index-matched, the photons fly straight from the centre: the flux
    that reaches the floor is exp(-sigma r) of what clear glass lets
    through, r the distance to the faceted surface (one fixed set of paths,
    so no noise)."""
    camera = Camera.look_at((0.0, -6.0, 4.0), (0.0, 0.0, 0.0), pixx=8, pixy=8)
    clear = render(absorbing_sphere_scene(0.0, camera), quick(lamp_rays=50_000, density=density))
    dimmed = render(absorbing_sphere_scene(SIGMA, camera), quick(lamp_rays=50_000, density=density))
    ratio = np.array(dimmed.stats["flux_landed_w"]) / np.array(clear.stats["flux_landed_w"])
    low, high = chord_bounds()
    assert np.all((ratio > low) & (ratio < high)), ratio
    assert ("light 'Point' is inside 'Glass': what is outside gets its light only through the glass, as caustics"
            in dimmed.warnings)


def facet_radii(radius: float, segments: int) -> tuple[float, float]:
    """(nearest, farthest): the least distance of a face's plane from the
    centre of a faceted sphere of `radius` and `segments`, and its vertices'."""
    mesh = shapes.uv_sphere(radius, CENTER, segments, segments // 2)
    normals, area = triangle_normals(mesh.corners)
    return float(np.abs(np.einsum("ij,ij->i", normals, mesh.corners[:, 0] - CENTER))[area > 0].min()), radius


def test_a_lamp_in_a_ball_inside_absorbing_glass_is_dimmed_by_the_glass_outside_the_ball():
    """A clear, index-matched ball of radius 0.3 around the lamp, inside the
    absorbing sphere: the photons leave the ball back into the sphere (the
    media nest, Accelerator.media_at), which dims them by exp(-sigma (R -
    r)). Before, they left the ball into the air and passed the sphere's
    face as one already crossed: nothing dimmed them."""
    camera = Camera.look_at((0.0, -6.0, 4.0), (0.0, 0.0, 0.0), pixx=8, pixy=8)
    ball = Object("Ball", shapes.uv_sphere(0.3, CENTER, 32, 16), Dielectric(1.0))
    clear = render(absorbing_sphere_scene(0.0, camera), quick(lamp_rays=50_000, density="splat"))
    scene = absorbing_sphere_scene(SIGMA, camera)
    dimmed = render(Scene(scene.objects + [ball], scene.lights, camera), quick(lamp_rays=50_000, density="splat"))
    ratio = np.array(dimmed.stats["flux_landed_w"]) / np.array(clear.stats["flux_landed_w"])
    (outer_near, outer_far), (inner_near, inner_far) = facet_radii(RADIUS, SEGMENTS), facet_radii(0.3, 32)
    low, high = math.exp(-SIGMA * (outer_far - inner_near)), math.exp(-SIGMA * (outer_near - inner_far))
    assert np.all((ratio > low) & (ratio < high)), (ratio, low, high)


def test_a_camera_inside_absorbing_glass_sees_through_the_radius_it_crosses():
    """A camera at the centre of the same sphere, looking down at floor that
    a low lamp outside lights directly: each eye ray crosses r of glass
    before it leaves, so every pixel of the direct light is exp(-sigma r)
    of the clear-glass render. (Eye rays start at the clip plane, here
    1e-7 m from the eye.)"""
    camera = Camera.look_at(CENTER, (0.0, 0.1, 0.0), pixx=16, pixy=12, fov=math.radians(60.0), clip_start=1e-7)
    lamp = (6.0, 0.0, 0.8)
    clear = render(absorbing_sphere_scene(0.0, camera, lamp), quick(lamp_rays=20_000)).passes["direct"]
    dimmed = render(absorbing_sphere_scene(SIGMA, camera, lamp), quick(lamp_rays=20_000)).passes["direct"]
    assert clear.min() > 0.0
    low, high = chord_bounds()
    ratio = dimmed / clear
    assert ratio.min() > low * (1 - 1e-5) and ratio.max() < high * (1 + 1e-5), (ratio.min(), ratio.max())
