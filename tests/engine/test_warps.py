"""The warps' contracts (sampling/warps.py, spherical_rectangle.py): frames
are orthonormal and right-handed about any unit axis, and the maps of the
unit square have the densities they promise, checked by moments with
closed forms or quadratures over a fine midpoint grid."""

import numpy as np
import pytest

from caustic_addon import AreaLight
from caustic_addon.emission.lamp_samples import sample_lamp
from caustic_addon.sampling.warps import (concentric_disc, cone_directions, cosine_hemisphere, frames,
                                          orthonormal_basis)


def square_grid(k: int = 200) -> np.ndarray:
    ticks = (np.arange(k) + 0.5) / k
    return np.stack(np.meshgrid(ticks, ticks), -1).reshape(-1, 2)


def test_frames_are_right_handed_and_orthonormal_about_any_axis():
    """Duff et al.'s basis has no singular axis: along +-z, at z = +-0 and in between."""
    rng = np.random.default_rng(3)
    axes = np.concatenate([[[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, -0.0], [1, 0, 0.0]], rng.normal(size=(500, 3))])
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    t, b = frames(axes)
    basis = np.stack([t, b, axes], axis=1)
    np.testing.assert_allclose(basis @ basis.transpose(0, 2, 1), np.broadcast_to(np.eye(3), basis.shape), atol=1e-12)
    np.testing.assert_allclose(np.cross(t, b), axes, atol=1e-12)
    one_t, one_b = orthonormal_basis(axes[7])
    assert np.array_equal(one_t, t[7]) and np.array_equal(one_b, b[7])


def test_the_concentric_disc_has_the_uniform_discs_moments():
    """Uniform on the unit disc: E[r^2] = 1/2, E[r^4] = 1/3, E[x] = E[y] = 0."""
    disc = concentric_disc(square_grid())
    r2 = disc[:, 0] ** 2 + disc[:, 1] ** 2
    assert r2.mean() == pytest.approx(0.5, abs=1e-4)
    assert (r2 * r2).mean() == pytest.approx(1.0 / 3.0, abs=1e-4)
    np.testing.assert_allclose(disc.mean(axis=0), 0.0, atol=1e-12)


@pytest.mark.parametrize("cos_max", [0.999962, 0.5, -1.0])
def test_cone_directions_are_uniform_in_solid_angle(cos_max):
    """Uniform over the cap cos(theta) >= c: E[cos theta] = (1 + c) / 2,
    E[cos^2 theta] = (1 + c + c^2) / 3."""
    axis = np.array([0.3, -0.4, -np.sqrt(0.75)])
    dirs = cone_directions(axis, cos_max, square_grid())
    cos = dirs @ axis
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-12)
    assert cos.min() >= cos_max - 1e-12
    assert cos.mean() == pytest.approx((1 + cos_max) / 2, abs=1e-4 * (1 - cos_max))
    assert (cos * cos).mean() == pytest.approx((1 + cos_max + cos_max ** 2) / 3, abs=1e-4 * (1 - cos_max))


def test_the_cosine_hemisphere_has_density_cos_over_pi():
    """Density cos(theta) / pi: E[cos theta] = 2/3, E[cos^2 theta] = 1/2 (the
    first slower to converge on a grid: cos = sqrt(1 - r^2) is singular at
    the disc's rim)."""
    uv = square_grid()
    normals = np.broadcast_to([0.0, 0.6, -0.8], (len(uv), 3))
    cos = cosine_hemisphere(normals, uv) @ normals[0]
    assert cos.min() >= 0.0
    assert cos.mean() == pytest.approx(2.0 / 3.0, abs=1e-3)
    assert (cos * cos).mean() == pytest.approx(0.5, abs=1e-4)


@pytest.mark.parametrize("origin", [(0.3, -0.2, 0.0), (2.5, 0.4, 0.9), (0.1, 0.0, 0.9)])
def test_a_rectangle_lamps_samples_are_uniform_over_the_solid_angle_it_spans(origin):
    """An area lamp's rectangle, 1 m at z = 1 facing down, drawn by solid
    angle (sampling/spherical_rectangle.py): every sample's density is
    1 / S, S the quadrature of cos / d^2 over the rectangle, and the
    directions' moments are the quadrature's over that solid angle, near
    it, to its side and far off."""
    lamp = AreaLight((0.0, 0.0, 1.0), (0.5, 0, 0), (0, 0.5, 0), (0, 0, -1), 10.0)
    uv = square_grid(300)
    origin = np.array(origin)
    drawn = sample_lamp(lamp, 1.0, np.tile(origin, (len(uv), 1)), uv, 100.0)
    ticks = (np.arange(2000) + 0.5) / 2000 - 0.5
    x, y = (a.ravel() for a in np.meshgrid(ticks, ticks))
    offset = np.stack([x, y, np.ones_like(x)], axis=1) - origin
    d2 = np.sum(offset ** 2, axis=1)
    d_omega = offset[:, 2] / d2 ** 1.5 / 2000 ** 2
    solid_angle = d_omega.sum()
    assert drawn.pdf == pytest.approx(np.full(len(uv), 1.0 / solid_angle), rel=1e-4)
    dirs = offset / np.sqrt(d2)[:, None]
    for axis in range(3):
        assert drawn.dirs[:, axis].mean() == pytest.approx(np.sum(dirs[:, axis] * d_omega) / solid_angle, abs=1e-4)
        assert (drawn.dirs[:, axis] ** 2).mean() == pytest.approx(np.sum(dirs[:, axis] ** 2 * d_omega) / solid_angle,
                                                                  abs=1e-4)
