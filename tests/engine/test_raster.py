"""Exact-area triangle rasterisation, against polygon clipping."""

import numpy as np
import pytest

from caustic_addon.maps.raster import Coverage, rasterise_triangles


def clipped_area(triangle: np.ndarray, x0: float, x1: float, y0: float, y1: float) -> float:
    """Area of `triangle (3,2)` inside the box, by Sutherland-Hodgman clipping."""
    poly = list(triangle)
    for axis, bound, keep_above in ((0, x0, True), (0, x1, False), (1, y0, True), (1, y1, False)):
        out = []
        for p, q in zip(poly, poly[1:] + poly[:1]):
            p_in = (p[axis] >= bound) if keep_above else (p[axis] <= bound)
            q_in = (q[axis] >= bound) if keep_above else (q[axis] <= bound)
            if p_in:
                out.append(p)
            if p_in != q_in:
                out.append(p + (bound - p[axis]) / (q[axis] - p[axis]) * (q - p))
        poly = out
        if len(poly) < 3:
            return 0.0
    p = np.array(poly)
    return 0.5 * abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - p[:, 1] * np.roll(p[:, 0], -1)))


def clipped_grid(shape, triangles, values):
    """(c,h,w) planes: each cell's clipped area of every triangle times its value."""
    h, w = shape
    grid = np.zeros((values.shape[1], h, w))
    for tri, value in zip(triangles, values):
        for r in range(h):
            for c in range(w):
                grid[:, r, c] += value * clipped_area(tri, c, c + 1, r, r + 1)
    return grid


@pytest.mark.parametrize("seed", range(4))
def test_each_cell_gets_the_exact_area_of_random_triangles(seed):
    """Triangles of both windings, inside, across and beyond every border."""
    rng = np.random.default_rng(seed)
    shape = (9, 13)
    triangles = rng.uniform([-6.0, -6.0], [19.0, 15.0], size=(12, 3, 2))
    values = rng.uniform(0.5, 2.0, size=(12, 2))
    np.testing.assert_allclose(rasterise_triangles(shape, triangles, values),
                               clipped_grid(shape, triangles, values), atol=1e-11)


def test_small_triangles_on_grid_lines_and_corners_keep_their_area():
    triangles = np.array([[[2.3, 3.1], [2.7, 3.2], [2.5, 3.9]],     # inside one cell
                          [[1.0, 1.0], [5.0, 1.0], [1.0, 5.0]],     # corners on grid points
                          [[4.0, 0.5], [4.0, 2.5], [6.0, 2.0]],     # an edge along a grid line
                          [[3.5, 3.5], [3.5 + 1e-9, 3.5], [3.5, 3.5 + 1e-9]]])
    values = np.ones((4, 1))
    grid = rasterise_triangles((8, 8), triangles, values)
    np.testing.assert_allclose(grid, clipped_grid((8, 8), triangles, values), atol=1e-12)
    assert grid.sum() == pytest.approx(0.5 * 0.4 * 0.75 + 8.0 + 2.0 + 0.5e-18, rel=1e-12)


def test_triangles_off_the_grid_leave_nothing():
    left = np.array([[[-9.0, 1.0], [-2.0, 2.0], [-5.0, 6.0]]])
    above = left + [12.0, 20.0]
    grid = rasterise_triangles((8, 8), np.concatenate([left, above]), np.ones((2, 3)))
    assert np.abs(grid).max() < 1e-12


def test_bands_of_rows_add_the_whole_to_the_bit_and_share_out_a_crowded_caustic():
    """A caustic crowds into a few rows: 2,000 small triangles in rows 40
    to 45 of 100, and 200 anywhere. Up to eight bands of rows, in any order,
    sum to the whole to the bit, and none of them holds most of the
    triangles (bands of equal rows would give one band all the crowd)."""
    rng = np.random.default_rng(7)
    crowd = np.array([50.0, 42.5]) + rng.uniform([-50.0, -2.5], [50.0, 2.5], (2000, 1, 2))
    spread = rng.uniform(0.0, 100.0, (200, 1, 2))
    corners = np.concatenate([crowd, spread]) + rng.uniform(-0.6, 0.6, (2200, 3, 2))
    values = rng.uniform(0.5, 2.0, (2200, 1))
    whole, banded = Coverage((100, 100), 1), Coverage((100, 100), 1)
    whole.add(corners, values)
    jobs = banded.add_jobs(corners, values, bands=8)
    for job in reversed(jobs):
        job()
    assert np.array_equal(whole.planes(), banded.planes())
    assert max(len(job.args[8]) for job in jobs) < 0.4 * len(corners)
