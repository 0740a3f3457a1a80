"""The camera follows Blender's view plane; lamps follow Cycles' units; maps
keep the flux they are given."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, SpotLight
from caustic_addon.emission.radiometry import spot_attenuation
from caustic_addon.maps.charts import PlaneChart
from caustic_addon.maps.grid import add_cell_means, as_rgb, bilinear_splat, channel_tables, rect_means
from caustic_addon.maps.illumination_map import IlluminationMap, MapEstimate
from caustic_addon.passes.camera_rays import eye_rays, ray_differentials


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
    imap.add_photons(imap.chart.coords(None, None, None, points), np.full((n, 3), 2.0 / n), np.ones(n))
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
    imap.add_photons(imap.chart.coords(None, None, None, point), np.ones((1, 3)), np.ones(1))
    imap.prepare()
    np.testing.assert_allclose(imap.count[4:6, 4:6], 0.25)
    assert imap.count.sum() == pytest.approx(1.0)


def tilted_camera(kind: str = "PERSP") -> Camera:
    """A camera 5 m from the origin, 2.5 m up, looking down past it."""
    return Camera.look_at((0.0, -5.0, 2.5), (0.0, 0.3, 0.0), pixx=320, pixy=240, fov=math.radians(30),
                          kind=kind, ortho_scale=6.0, clip_start=0.1)


@pytest.mark.parametrize("kind", ["PERSP", "ORTHO"])
def test_ray_differentials_are_the_derivatives_of_eye_rays(kind):
    cam = tilted_camera(kind)
    rng = np.random.default_rng(4)
    pixels, offsets = rng.integers(0, 320 * 240, 200), rng.random((200, 2))
    _, dirs = eye_rays(cam, pixels, offsets)
    d_origins, d_dirs = ray_differentials(cam, dirs)
    for axis in (0, 1):
        step = np.zeros(2)
        step[axis] = 1e-5
        (o1, d1), (o0, d0) = eye_rays(cam, pixels, offsets + step), eye_rays(cam, pixels, offsets - step)
        np.testing.assert_allclose(d_origins[:, axis], (o1 - o0) / 2e-5, atol=1e-8)
        np.testing.assert_allclose(d_dirs[:, axis], (d1 - d0) / 2e-5, atol=1e-8)


def test_a_pixel_footprint_stands_as_the_rectangle_of_its_mean_and_spread():
    """The rectangle a pixel's caustic is averaged over has the centre and,
    along each axis, the variance of where rays spread evenly over the pixel
    meet the floor (to 1%), and is narrower than those points' bounding box
    where the footprint is sheared, at the image's corner."""
    cam = tilted_camera()
    floor = square_map(MapEstimate(None), size=8.0).chart
    pixel = np.array([5])
    origins, dirs = eye_rays(cam, pixel, np.array([[0.5, 0.5]]))
    lo, hi, ok = floor.footprint(origins, dirs, *ray_differentials(cam, dirs), 1.0)
    assert ok.all()
    ticks = (np.arange(64) + 0.5) / 64
    spread = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    o, d = eye_rays(cam, np.repeat(pixel, len(spread)), spread)
    hits = floor.plane_coords(o - (o[:, 2] / d[:, 2])[:, None] * d)
    np.testing.assert_allclose(0.5 * (lo + hi)[0], hits.mean(axis=0), atol=1e-3 * np.ptp(hits, axis=0).max())
    np.testing.assert_allclose((hi - lo)[0] ** 2 / 12.0, hits.var(axis=0), rtol=1e-2)
    assert (hi - lo)[0, 0] < 0.97 * np.ptp(hits[:, 0])


def exact_rect_means(grid: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Means of the cell-constant `grid (h,w,c)` (unit cells from 0) over
    rectangles: each cell weighted by its overlap, per axis, with the box."""
    h, w = grid.shape[:2]
    over_y = np.clip(np.minimum(hi[:, 1:], np.arange(1, h + 1)) - np.maximum(lo[:, 1:], np.arange(h)), 0, None)
    over_x = np.clip(np.minimum(hi[:, :1], np.arange(1, w + 1)) - np.maximum(lo[:, :1], np.arange(w)), 0, None)
    return np.einsum("ni,nj,ijc->nc", over_y, over_x, grid) / ((hi - lo).prod(axis=1))[:, None]


@pytest.mark.parametrize("channels", [3, 1])
def test_rectangle_means_of_a_grid_are_exact(channels):
    """Means over rectangles that straddle cells and the grid's edge, from
    summed-area tables, match the exact overlap-weighted sums; white light
    keeps one table for all three channels."""
    rng = np.random.default_rng(2)
    grid = np.repeat(rng.random((7, 9, channels)), 3 // channels, axis=2)
    lo = rng.random((500, 2)) * [10.0, 8.0] - 0.5
    hi = lo + 0.05 + rng.random((500, 2)) * 3.0
    tables = channel_tables(np.moveaxis(grid, -1, 0))
    assert len(tables) == channels
    ours = as_rgb(rect_means(tables, np.zeros(2), 1.0, lo, hi))
    inside = np.clip(lo, 0, [9, 7]), np.clip(hi, 0, [9, 7])
    covered = (inside[1] - inside[0]).prod(axis=1) / (hi - lo).prod(axis=1)
    np.testing.assert_allclose(ours, exact_rect_means(grid, lo, hi), rtol=1e-9, atol=1e-12)
    assert covered.min() < 0.5  # some rectangles reach off the grid


@pytest.mark.parametrize("channels", [3, 1])
@pytest.mark.parametrize("step", [0.3, 1.0, 2.5])
def test_a_grids_cell_means_over_another_grids_cells_are_its_rectangle_means(channels, step):
    """The means over each cell of a finer, equal or coarser grid laid
    across the grid's edge (a bake's map cells over a beam layer), each
    widened to at least one of the grid's cells, are rect_means' for those
    rectangles bit for bit, and nothing off the grid; one table's mean
    goes to all three channels."""
    rng = np.random.default_rng(4)
    grid = rng.random((channels, 7, 9))
    tables = channel_tables(grid)
    origin, grid_origin = np.array([0.25, -0.5]), np.array([-1.1, -0.7])
    rows, columns = range(2, 9), 8
    cells = np.stack(np.meshgrid(np.arange(columns), np.arange(rows.start, rows.stop)), axis=-1).reshape(-1, 2)
    lo = grid_origin + step * cells
    hi = lo + step
    centre, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 0.5)
    expected = np.zeros((len(cells), 3))
    meets = ((centre + half > origin) & (centre - half < origin + [9.0, 7.0])).all(axis=1)
    expected[meets] += rect_means(tables, origin[::-1], 1.0, (centre - half)[meets], (centre + half)[meets])
    ours = np.zeros((len(cells), 3))
    add_cell_means(tables, origin, 1.0, grid_origin, step, rows, columns, ours)
    assert not meets.all() and (ours[~meets] == 0.0).all()
    np.testing.assert_array_equal(ours, expected)


@pytest.mark.parametrize("photons", [10, 100_000])
def test_few_or_many_photons_splat_the_same_as_one_at_a_time(photons):
    """A small batch and a large one both equal adding each photon's four
    shares in turn."""
    rng = np.random.default_rng(3)
    rc = rng.random((photons, 2)) * [60, 40] - 1.0
    values = rng.random((photons, 2))
    planes = np.zeros((2, 60, 40))
    bilinear_splat(planes, rc, values)
    expected = np.zeros((2, 60, 40))
    base = np.floor(rc).astype(int)
    for di in (0, 1):
        for dj in (0, 1):
            share = np.abs(1 - di - (rc[:, 0] - base[:, 0])) * np.abs(1 - dj - (rc[:, 1] - base[:, 1]))
            rows, cols = np.clip(base[:, 0] + di, 0, 59), np.clip(base[:, 1] + dj, 0, 39)
            for c in range(2):
                np.add.at(expected[c], (rows, cols), share * values[:, c])
    np.testing.assert_allclose(planes, expected, rtol=1e-10, atol=1e-12)
