"""Caustic beams: noise-free, flux-conserving, and exact against the ball-lens reference."""

import math

import numpy as np
import pytest

from caustic_addon import render
from caustic_addon.beams import concentric_disc, grid_triangles
from metrics import annulus_means, annulus_points, relative_l2
from scenes import ball_lens, quick, shadow_radius


def test_concentric_map_is_equal_area_and_fills_the_disc():
    ticks = (np.arange(200) + 0.5) / 200
    uv = np.stack(np.meshgrid(ticks, ticks), -1).reshape(-1, 2)
    disc = concentric_disc(uv)
    r = np.linalg.norm(disc, axis=1)
    assert r.max() <= 1.0 + 1e-12
    # equal area: the fraction of points within radius rho is rho^2
    for rho in (0.25, 0.5, 0.75):
        assert np.mean(r <= rho) == pytest.approx(rho ** 2, abs=0.01)


def test_grid_triangles_tile_the_grid_once():
    tris = grid_triangles(4, 5)
    assert len(tris) == 2 * 3 * 4
    rows, cols = tris // 5, tris % 5
    area = 0.5 * np.abs((rows[:, 1] - rows[:, 0]) * (cols[:, 2] - cols[:, 0])
                        - (rows[:, 2] - rows[:, 0]) * (cols[:, 1] - cols[:, 0]))
    assert area.sum() == pytest.approx(3 * 4)


def radial_error(photons: int) -> float:
    import reference

    r_edges = np.linspace(0.0, shadow_radius(), 61)
    exact = reference.ball_lens_irradiance(1.0, 1.5, 1.5, 6.0, 1000.0 / (4 * math.pi), r_edges)
    result = render(ball_lens(pixels=8, segments=256), quick(photons=photons, density="beam"))
    ours = annulus_means(result.maps["Floor"].irradiance_at(annulus_points(r_edges, 200))[:, 0], r_edges)
    return relative_l2(ours, exact.caustic, r_edges)


def test_beams_match_the_exact_reference_with_few_paths():
    """40,000 grid paths give the ball lens's radial caustic to within 2.5%;
    photon splatting needs millions of photons for 5%. (What is left is the
    rasterisation layers' cell size, about 1 mm at the focus.)"""
    assert radial_error(40_000) < 0.025


def test_beams_carry_the_same_flux_as_photons():
    beams = render(ball_lens(pixels=8), quick(photons=40_000, density="beam")).stats["flux_landed_w"]
    photons = render(ball_lens(pixels=8), quick(photons=400_000)).stats["flux_landed_w"]
    np.testing.assert_allclose(beams, photons, rtol=0.01)


def test_beam_caustic_has_no_noise():
    """No random number decides a beam: renders with different seeds give
    the same map, where photon maps differ by their noise."""
    xy = np.stack([np.linspace(0.0, 0.9, 50), np.zeros(50)], axis=1)

    def caustic(**kwargs):
        return render(ball_lens(pixels=8), quick(photons=40_000, **kwargs)).maps["Floor"].irradiance_at(xy)

    np.testing.assert_allclose(caustic(density="beam", seed=1), caustic(density="beam", seed=2), rtol=1e-9)
    assert not np.allclose(caustic(seed=1), caustic(seed=2), rtol=1e-3)


def test_beam_renders_are_finite_and_conserve_flux_under_glass_colour_and_absorption():
    result = render(ball_lens(pixels=16, absorption=0.4, ior=2.41), quick(photons=20_000, density="beam", spp=4))
    assert np.isfinite(result.image).all()
    assert np.isfinite(result.maps["Floor"].irradiance()).all()
