"""The camera follows Blender's view plane; lamps follow Cycles' units; maps
keep the flux they are given."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, SpotLight
from caustic_addon.camera import eye_rays
from caustic_addon.illumination_map import IlluminationMap, MapEstimate, PlaneChart
from caustic_addon.units import spot_attenuation


def test_perspective_rays_span_the_field_of_view_along_the_fitted_side():
    cam = Camera(np.eye(4), pixx=200, pixy=100, fov=math.radians(60))
    centre, _ = eye_rays(cam, np.array([50 * 200 + 100]), np.array([[0.0, 0.0]]))
    _, dirs = eye_rays(cam, np.array([50 * 200 + 100, 50 * 200]), np.array([[0.0, 0.0], [0.0, 0.0]]))
    np.testing.assert_allclose(dirs[0], [0, 0, -1], atol=1e-12)  # Blender cameras look down -Z
    left_edge_angle = math.atan2(-dirs[1, 0], -dirs[1, 2])
    assert left_edge_angle == pytest.approx(math.radians(30), rel=1e-9)
    portrait = Camera(np.eye(4), pixx=100, pixy=200, fov=math.radians(60))
    _, top = eye_rays(portrait, np.array([50]), np.array([[0.0, 0.0]]))
    assert math.atan2(top[0, 1], -top[0, 2]) == pytest.approx(math.radians(30), rel=1e-9)


def test_lens_shift_moves_the_view_by_the_fitted_side():
    shifted = Camera(np.eye(4), pixx=200, pixy=100, fov=math.radians(60), shift_x=0.5)
    _, dirs = eye_rays(shifted, np.array([50 * 200]), np.array([[0.0, 0.0]]))
    np.testing.assert_allclose(dirs[0], [0, 0, -1], atol=1e-12)  # the left edge is now the centre


def test_orthographic_rays_are_parallel_and_span_ortho_scale():
    cam = Camera(np.eye(4), pixx=100, pixy=50, kind="ORTHO", ortho_scale=4.0)
    origins, dirs = eye_rays(cam, np.array([0, 99]), np.array([[0.0, 0.0], [1.0, 0.0]]))
    np.testing.assert_allclose(dirs, [[0, 0, -1], [0, 0, -1]])
    assert origins[1, 0] - origins[0, 0] == pytest.approx(4.0)


def test_spot_cone_matches_cycles_smoothstep():
    spot = SpotLight((0, 0, 0), (0, 0, -1), 10.0, spot_size=math.radians(60), blend=0.5)
    cos_half = math.cos(math.radians(30))

    def toward(angle):
        return np.array([[math.sin(angle), 0.0, -math.cos(angle)]])

    assert spot_attenuation(spot, toward(0.0))[0] == pytest.approx(1.0)
    assert spot_attenuation(spot, toward(math.radians(30.01)))[0] == 0.0
    angle = math.radians(25)
    x = (math.cos(angle) - cos_half) / ((1 - cos_half) * 0.5)
    assert spot_attenuation(spot, toward(angle))[0] == pytest.approx(x * x * (3 - 2 * x))


def square_map(estimate, cell=0.01, size=1.0):
    verts = np.array([[0, 0, 0], [size, 0, 0], [size, size, 0], [0, size, 0]], dtype=float)
    chart = PlaneChart(np.array([size / 2, size / 2, 0.0]), np.array([0.0, 0.0, 1.0]), verts)
    return IlluminationMap("square", chart, cell, estimate)


@pytest.mark.parametrize("k", [None, 32])
def test_uniform_photons_read_back_as_their_irradiance(k):
    """Flux spread evenly over a square of area A reads back as flux / A,
    in the paper's bilinear map and in the adaptive one."""
    imap = square_map(MapEstimate(k))
    rng = np.random.default_rng(0)
    n = 400_000
    xy = rng.random((n, 2))
    points = np.c_[xy, np.zeros(n)]
    imap.deposit(np.zeros(n, int), np.zeros(n), np.zeros(n), points, np.full((n, 3), 2.0 / n))
    assert imap.flux.sum() == pytest.approx(3 * 2.0)
    probe = 0.2 + 0.6 * rng.random((2000, 2)) + imap.chart.origin
    e = imap.irradiance_at(probe)
    assert e.mean() == pytest.approx(2.0, rel=0.01)
    outside = imap.irradiance_at(imap.chart.origin + np.array([[-0.5, 0.5], [0.5, 1.5]]))
    np.testing.assert_array_equal(outside, 0.0)


def test_map_scale_sets_the_cell_and_the_paper_scheme_splats_to_four_cells():
    imap = square_map(MapEstimate(None), cell=0.1)
    assert imap.shape == (10, 10)
    # one photon between four cell centres lands a quarter in each
    point = np.array([[0.5, 0.5, 0.0]])
    imap.deposit(np.zeros(1, int), np.zeros(1), np.zeros(1), point, np.ones((1, 3)))
    imap.prepare()
    np.testing.assert_allclose(imap.count[4:6, 4:6], 0.25)
    assert imap.count.sum() == pytest.approx(1.0)
