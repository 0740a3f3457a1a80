"""Snell refraction, mirror reflection, total internal reflection and Fresnel."""

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from caustic_addon.optics.specular import fresnel_dielectric, reflect, refract, valid_reflection_normal1
from caustic_addon.passes.bounce import scatter1
from caustic_addon.util.vectors import dot

UP = np.array([[0.0, 0.0, 1.0]])


def incoming(theta: float, phi: float = 0.3) -> np.ndarray:
    """A unit direction (1,3) hitting the plane z = 0 from above at angle theta."""
    return np.array([[math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -math.cos(theta)]])


@settings(max_examples=300, deadline=None)
@given(theta=st.floats(0.0, math.pi / 2 - 1e-9), eta=st.floats(0.25, 4.0), phi=st.floats(0.0, 2 * math.pi))
def test_refraction_obeys_snell(theta, eta, phi):
    d = incoming(theta, phi)
    t, tir = refract(d, UP, eta)
    sin_i = math.sin(theta)
    if eta * sin_i > 1.0 + 1e-12:
        assert tir[0]
        return
    assert not tir[0]
    assert abs(np.linalg.norm(t) - 1.0) < 1e-12
    sin_t = np.linalg.norm(np.cross(t[0], UP[0]))
    assert abs(sin_i - sin_t / eta) < 1e-6 or abs(eta * sin_i - sin_t) < 1e-6
    assert t[0, 2] <= 0.0
    # refracted ray stays in the plane of incidence
    assert abs(np.dot(np.cross(d[0], UP[0]), t[0])) < 1e-9


def test_total_internal_reflection_starts_at_the_critical_angle():
    eta = 1.5  # glass to air
    critical = math.asin(1.0 / eta)
    for delta, expect_tir in ((-1e-7, False), (1e-7, True)):
        _, tir = refract(incoming(critical + delta), UP, eta)
        assert tir[0] == expect_tir
        f = fresnel_dielectric(np.array([math.cos(critical + delta)]), eta)[0]
        assert (f == 1.0) == expect_tir


def test_reflection_mirrors_about_the_normal():
    rng = np.random.default_rng(1)
    d = rng.normal(size=(100, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    n = rng.normal(size=(100, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    r = reflect(d, n)
    np.testing.assert_allclose(dot(r, n), -dot(d, n), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(r, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.cross(r, n), np.cross(d, n), atol=1e-12)


def test_fresnel_known_values():
    # normal incidence: ((n1 - n2) / (n1 + n2))^2
    assert math.isclose(fresnel_dielectric(np.array([1.0]), 1 / 1.5)[0], 0.04, rel_tol=1e-12)
    # Brewster's angle: Rp = 0, so F = Rs / 2
    brewster = math.atan(1.5)
    cos_i, cos_t = math.cos(brewster), math.cos(math.asin(math.sin(brewster) / 1.5))
    rs = ((cos_i - 1.5 * cos_t) / (cos_i + 1.5 * cos_t)) ** 2
    assert math.isclose(fresnel_dielectric(np.array([cos_i]), 1 / 1.5)[0], rs / 2, rel_tol=1e-9)
    # grazing incidence reflects everything; index matching reflects nothing
    assert math.isclose(fresnel_dielectric(np.array([0.0]), 1 / 1.5)[0], 1.0)
    np.testing.assert_allclose(fresnel_dielectric(np.linspace(0, 1, 50), 1.0), 0.0, atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(cos_i=st.floats(0.0, 1.0), eta=st.floats(0.2, 5.0))
def test_fresnel_is_a_probability_and_symmetric(cos_i, eta):
    f = fresnel_dielectric(np.array([cos_i]), eta)[0]
    assert 0.0 <= f <= 1.0
    sin2_t = eta * eta * (1 - cos_i * cos_i)
    # Fresnel's slope is infinite at the critical angle, which grazing
    # incidence becomes when seen from the other side
    if sin2_t < 1.0 - 1e-6 and cos_i > 1e-3:
        # reciprocity: the same interface seen from the other side reflects the same
        cos_t = math.sqrt(1.0 - sin2_t)
        back = fresnel_dielectric(np.array([cos_t]), 1.0 / eta)[0]
        assert abs(f - back) < 1e-9


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


@settings(max_examples=300, deadline=None)
@given(theta=st.floats(0.01, math.pi / 2 - 0.01), phi=st.floats(0.0, 2 * math.pi),
       tilt=st.floats(0.0, 1.4), azimuth=st.floats(0.0, 2 * math.pi))
def test_a_raised_normal_reflects_the_ray_off_the_surface_as_cycles_requires(theta, phi, tilt, azimuth):
    """valid_reflection_normal1 against its definition (Cycles'
    ensure_valid_specular_reflection): the mirror reflection of the ray
    about the normal it returns leaves the surface at least min(0.9 cos,
    0.01) above it; the normal is the shading one where that already holds,
    and otherwise lies between it and the geometric normal."""
    ng = np.array([0.0, 0.0, 1.0])
    i = -incoming(theta, phi)[0]
    n = np.array([math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), math.cos(tilt)])
    raised = np.array(valid_reflection_normal1(tuple(ng), tuple(i), tuple(n)))
    threshold = min(0.9 * i[2], 0.01)
    assert abs(np.linalg.norm(raised) - 1.0) < 1e-9
    reflected = 2.0 * raised.dot(i) * raised - i
    assert reflected[2] >= threshold - 1e-7
    if (2.0 * n.dot(i) * n - i)[2] >= threshold:
        np.testing.assert_array_equal(raised, n)
    else:
        assert abs(np.dot(raised, np.cross(n, ng))) < 1e-9
        assert raised[2] >= n[2] - 1e-12


def test_a_ray_the_shading_normal_sends_to_the_wrong_side_ends():
    """A ray inside smooth glass meets its face at 3 degrees, where the
    shading normal leans 61 degrees off the face's: refracted out about it,
    it turns back into the glass. Cycles ends such a path
    (bsdf_microfacet_sample); scatter1 keeps nothing of it, and all of a
    ray that the shading normal sends out."""
    facing, eta = (0.0, 0.0, 1.0), 1.5
    shading = (-math.sin(math.radians(61)), 0.0, math.cos(math.radians(61)))
    grazing = (math.cos(math.radians(3)), 0.0, -math.sin(math.radians(3)))
    out, crossed, kept = scatter1(grazing, shading, facing, shading, eta, 0.0, False)
    assert crossed and out[2] > 0.0 and kept == 0.0
    steep = (math.sin(math.radians(20)), 0.0, -math.cos(math.radians(20)))
    out, crossed, kept = scatter1(steep, facing, facing, facing, eta, 0.0, False)
    assert crossed and out[2] < 0.0 and kept == 1.0
