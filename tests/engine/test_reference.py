"""The float64 ball-lens reference (benchmarks/references/reference.py) against optics it must reproduce."""

import math

import numpy as np
import pytest

from benchmarks.references import reference as ref

R, N_GLASS, CENTRE_Z, LAMP_Z = 1.0, 1.5, 1.5, 6.0
SCENE = (R, N_GLASS, CENTRE_Z, LAMP_Z)


def sphere_solid_angle(R: float, centre_z: float, lamp_z: float) -> float:
    """Solid angle 2 pi (1 - cos alpha) of a sphere seen from the lamp, cos alpha = sqrt(d^2 - R^2) / d."""
    d = lamp_z - centre_z
    return 2.0 * math.pi * (1.0 - math.sqrt(d * d - R * R) / d)


def shadow_edges(annuli: int, reach: float) -> np.ndarray:
    """Annulus edges (annuli+1,) from the axis out to `reach` times the benchmark's shadow radius."""
    return np.linspace(0.0, reach * ref.shadow_radius(R, CENTRE_Z, LAMP_Z), annuli + 1)


@pytest.fixture(scope="module")
def glass() -> ref.BallLensIrradiance:
    return ref.ball_lens_irradiance(*SCENE, 1.0, shadow_edges(200, 1.0))


@pytest.fixture(scope="module")
def glass_doubled() -> ref.BallLensIrradiance:
    return ref.ball_lens_irradiance(*SCENE, 1.0, shadow_edges(200, 1.0), rays=2 * ref.DEFAULT_RAYS)


def test_fresnel_at_normal_incidence_and_brewster_angle():
    n = N_GLASS
    normal = ref.fresnel_unpolarised(np.array([1.0]), 1.0 / n)[0]
    assert normal == pytest.approx(((n - 1.0) / (n + 1.0)) ** 2, rel=1e-14)
    brewster = math.atan(n)
    refracted = math.asin(math.sin(brewster) / n)
    r_s_squared = (math.sin(brewster - refracted) / math.sin(brewster + refracted)) ** 2
    at_brewster = ref.fresnel_unpolarised(np.array([math.cos(brewster)]), 1.0 / n)[0]
    assert at_brewster == pytest.approx(0.5 * r_s_squared, rel=1e-12)


def test_fresnel_is_total_beyond_the_critical_angle():
    critical = math.asin(1.0 / N_GLASS)
    cos_i = np.cos([critical + 1e-6, 1.2, 1.5])
    np.testing.assert_array_equal(ref.fresnel_unpolarised(cos_i, N_GLASS), 1.0)


@pytest.mark.parametrize("internal_reflections", [0, 1, 2, 3])
def test_exit_directions_follow_descartes_deviation(internal_reflections):
    """After k internal reflections a ray is turned by 2 (i - t) + k (pi - 2 t) (Descartes' rainbow optics)."""
    incidence = np.linspace(0.05, 1.5, 9)
    pos, dirs = ref.first_hits(incidence, R, LAMP_Z - CENTRE_Z)
    incoming_angle = np.arctan2(dirs[:, 1], dirs[:, 0])
    _, inside, _ = ref.split(pos, dirs, 1.0 / N_GLASS, 1.0)
    for _ in range(internal_reflections):
        pos = ref.chord_end(pos, inside)
        inside, _, _ = ref.split(pos, inside, N_GLASS, -1.0)
    pos = ref.chord_end(pos, inside)
    _, out, _ = ref.split(pos, inside, N_GLASS, -1.0)

    refracted = np.arcsin(np.sin(incidence) / N_GLASS)
    deviation = 2.0 * (incidence - refracted) + internal_reflections * (np.pi - 2.0 * refracted)
    turned = np.angle(np.exp(1j * (incoming_angle - np.arctan2(out[:, 1], out[:, 0]))))
    np.testing.assert_allclose(np.cos(turned), np.cos(deviation), atol=1e-12)
    np.testing.assert_allclose(np.sin(turned), np.sin(deviation), atol=1e-12)


@pytest.mark.parametrize("lamp_z", [4.0, 6.0, 20.0, 1e3])
def test_two_surface_image_obeys_the_ball_lens_equation(lamp_z):
    """Both principal planes of a ball lens pass through its centre: 1/s + 1/s' = 1/f from there."""
    f, _ = ref.ball_lens_focal_length(R, N_GLASS)
    s = lamp_z - CENTRE_Z
    expected = CENTRE_Z - 1.0 / (1.0 / f - 1.0 / s)
    assert ref.paraxial_image_z(*SCENE[:3], lamp_z) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    "R_, n, centre_z, lamp_z",
    [(1.0, 1.5, 1.5, 6.0), (0.5, 1.33, 2.0, 9.0), (1.0, 1.9, 1.2, 3.0), (2.0, 1.5, 2.0, 4.5)],
)
def test_paraxial_rays_cross_the_axis_at_the_paraxial_image(R_, n, centre_z, lamp_z):
    theta = 1e-4 * ref.tangent_half_angle(R_, centre_z, lamp_z)
    crossing = ref.traced_axis_crossing_z(R_, n, centre_z, lamp_z, np.array([theta]))[0]
    image = ref.paraxial_image_z(R_, n, centre_z, lamp_z)
    assert abs(crossing - image) <= 1e-6 * abs(centre_z - image)


def test_spherical_aberration_pulls_marginal_rays_towards_the_lens():
    theta = np.linspace(0.01, 0.99, 50) * ref.tangent_half_angle(R, CENTRE_Z, LAMP_Z)
    crossing = ref.traced_axis_crossing_z(*SCENE, theta)
    assert np.all(np.diff(crossing) > 0.0)
    assert crossing[0] > ref.paraxial_image_z(*SCENE)


def test_focus_of_a_far_lamp_approaches_the_focal_point():
    f, back_focal_distance = ref.ball_lens_focal_length(R, N_GLASS)
    focal_point_z = CENTRE_Z - f
    assert ref.paraxial_image_z(*SCENE[:3], math.inf) == pytest.approx(CENTRE_Z - R - back_focal_distance, rel=1e-14)
    for distance in [1e2, 1e3, 1e4]:
        lamp_z = CENTRE_Z + distance
        theta = 1e-5 * ref.tangent_half_angle(R, CENTRE_Z, lamp_z)
        crossing = ref.traced_axis_crossing_z(*SCENE[:3], lamp_z, np.array([theta]))[0]
        newton_shift = f * f / (distance - f)
        assert focal_point_z - crossing == pytest.approx(newton_shift, rel=1e-4)


@pytest.mark.parametrize("n", [1.5, 1.2, 2.4])
def test_every_branch_accounts_for_the_flux_into_the_sphere(n):
    into_sphere = 3.0 * sphere_solid_angle(R, CENTRE_Z, LAMP_Z)
    coarse, fine = (
        ref.ball_lens_irradiance(R, n, CENTRE_Z, LAMP_Z, 3.0, shadow_edges(50, 1.0), rays=rays).budget
        for rays in (4096, 8192)
    )
    for budget in (coarse, fine):
        assert budget.emitted == pytest.approx(into_sphere, rel=1e-12)
        assert budget.accounted == pytest.approx(into_sphere, rel=1e-9)
        assert min(budget.binned, budget.outside_bins, budget.upward) > 0.0
        assert budget.lost < 1e-6 * into_sphere
    assert coarse.horizon / fine.horizon == pytest.approx(2.0, rel=0.05)


def test_a_ball_with_index_one_is_invisible():
    edges = shadow_edges(113, 1.2)
    result = ref.ball_lens_irradiance(R, 1.0, CENTRE_Z, LAMP_Z, 1.0, edges)
    unobstructed = ref.unobstructed_annulus_irradiance(edges, LAMP_Z, 1.0)
    np.testing.assert_allclose(result.caustic + result.direct, unobstructed, rtol=1e-5, atol=0.0)
    radius = ref.shadow_radius(R, CENTRE_Z, LAMP_Z)
    in_shadow, lit = edges[1:] < radius, edges[:-1] > radius
    np.testing.assert_allclose(result.caustic[in_shadow], unobstructed[in_shadow], rtol=1e-5, atol=0.0)
    assert np.all(result.direct[in_shadow] == 0.0)
    assert np.all(result.caustic[lit] < 1e-20 * unobstructed[lit])


def test_direct_annulus_average_matches_fine_sampling():
    edges = shadow_edges(7, 1.6)
    fine = np.linspace(edges[:-1], edges[1:], 20001)
    mid = 0.5 * (fine[1:] + fine[:-1])
    ring = np.diff(fine**2, axis=0)
    sampled = (ref.direct_irradiance(mid, R, CENTRE_Z, LAMP_Z, 2.0) * ring).sum(axis=0) / ring.sum(axis=0)
    exact = ref.direct_annulus_irradiance(edges, R, CENTRE_Z, LAMP_Z, 2.0)
    np.testing.assert_allclose(sampled, exact, rtol=1e-4)


def test_tube_flux_is_shared_by_overlap_on_both_sides_of_the_axis():
    rng = np.random.default_rng(7)
    edges = np.concatenate([[0.1], np.sort(rng.uniform(0.1, 3.0, 30)), [3.0]])
    x_lo = rng.uniform(-3.5, 3.5, 400)
    x_hi = x_lo + rng.choice([1e-3, 0.05, 1.0, 5.0], 400) * rng.uniform(0.1, 1.0, 400)
    flux = rng.uniform(0.5, 2.0, 400)

    binned = ref.bin_segments(*ref.fold_segments(x_lo, x_hi, flux), edges)

    def overlap(lo, hi):
        return np.clip(np.minimum(x_hi[:, None], hi) - np.maximum(x_lo[:, None], lo), 0.0, None)

    sides = overlap(edges[:-1], edges[1:]) + overlap(-edges[1:], -edges[:-1])
    expected = (flux[:, None] * sides / (x_hi - x_lo)[:, None]).sum(axis=0)
    np.testing.assert_allclose(binned, expected, rtol=1e-12)


def test_self_error_by_doubling_the_rays():
    assert ref.self_error(*SCENE, shadow_edges(200, 1.0)) < 1e-6


def test_every_annulus_is_converged(glass, glass_doubled):
    assert np.all(glass.caustic > 0.0)
    np.testing.assert_allclose(glass.caustic, glass_doubled.caustic, rtol=1e-4, atol=0.0)


def test_a_glass_ball_focuses_light(glass):
    unobstructed = ref.unobstructed_annulus_irradiance(glass.r_edges, LAMP_Z, 1.0)
    assert np.max(glass.caustic / unobstructed) > 5.0
