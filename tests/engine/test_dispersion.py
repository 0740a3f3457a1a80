"""Dispersion (Cauchy IOR from an Abbe number, wavelength bands to RGB) and
coloured glass (Beer-Lambert from a colour at a distance)."""

import math

import numpy as np
import pytest

from caustic_addon import Dielectric, Diffuse, Object, RenderSettings, Scene, SceneError, render, shapes
from caustic_addon.maps.illumination_map import IlluminationMap
from caustic_addon.optics.dispersion import LAMBDA_C, LAMBDA_D, LAMBDA_F, cauchy_ior
from caustic_addon.optics.media import absorption_from_color, volume_absorption
from caustic_addon.optics.spectrum import XYZ_TO_REC709, bands, cie_xyz, photon_band
from caustic_addon.scene import SunLight
from benchmarks.scenes import prism, slab
from scenes import ball_lens, quick, shadow_radius, top_camera, unobstructed_irradiance


@pytest.mark.parametrize("ior, abbe", [(2.417, 55.3), (1.5168, 64.17), (2.15, 33.0), (1.333, 55.7)])
def test_cauchy_ior_keeps_n_d_and_the_abbe_number(ior, abbe):
    n_d, n_f, n_c = cauchy_ior(ior, abbe, [LAMBDA_D, LAMBDA_F, LAMBDA_C])
    assert n_d == pytest.approx(ior, abs=1e-12)
    assert (n_d - 1) / (n_f - n_c) == pytest.approx(abbe, rel=1e-9)
    assert n_f > n_d > n_c


def test_cauchy_ior_matches_a_real_glass():
    """Schott N-BK7 (n_d 1.5168, V_d 64.17) has n_g = 1.52668 at 435.8 nm and
    n_r = 1.51289 at 706.5 nm (Schott data sheet); two Cauchy terms get
    within 2e-4, a tenth of the spread they model."""
    np.testing.assert_allclose(cauchy_ior(1.5168, 64.17, [435.8, 706.5]), [1.52668, 1.51289], atol=2e-4)


def test_infinite_abbe_number_does_not_disperse():
    assert np.all(cauchy_ior(1.5, math.inf, [400.0, 550.0, 700.0]) == 1.5)


@pytest.mark.parametrize("count", [1, 3, 6, 8])
def test_band_weights_sum_to_white_and_split_the_light_evenly(count):
    b = bands(count)
    np.testing.assert_allclose(b.weights.sum(axis=0), 1.0, atol=1e-12)
    assert np.all(b.weights >= 0)
    assert np.all(np.diff(b.wavelengths) > 0)
    # equal light per band, to the half-nanometre the edges are cut at
    np.testing.assert_allclose(b.weights.sum(axis=1), 3.0 / count, rtol=0.03)
    if count > 1:
        assert np.argmax(b.weights[0]) == 2 and np.argmax(b.weights[-1]) == 0


def test_colour_matching_fit_gives_white_for_d65_like_flat_light():
    """An equal-energy spectrum (CIE illuminant E) has x = y = z in the 1931
    functions' integrals; the analytic fit keeps that within 1%, and E is a
    near-neutral colour in Rec.709."""
    lam = np.arange(360.0, 830.0, 0.5)
    xyz = cie_xyz(lam).sum(axis=0)
    np.testing.assert_allclose(xyz / xyz[1], 1.0, atol=0.01)
    rgb = XYZ_TO_REC709 @ (xyz / xyz[1])
    np.testing.assert_allclose(rgb, 1.0, atol=0.25)


def test_each_run_of_band_count_photons_takes_every_band_once():
    ids = np.arange(6000, 6600)
    band = photon_band(ids, 6, seed=3).reshape(-1, 6)
    assert np.all(np.sort(band, axis=1) == np.arange(6))
    assert len({tuple(row) for row in band}) > 1


def test_absorption_from_a_colour_at_a_distance():
    color = np.array([0.8, 0.5, 0.2])
    sigma = absorption_from_color(color, 0.25)
    np.testing.assert_allclose(np.exp(-sigma * 0.25), color, rtol=1e-14)
    np.testing.assert_allclose(np.exp(-sigma * 0.5), color ** 2, rtol=1e-14)


def test_volume_absorption_is_cycles_density_times_one_minus_color():
    np.testing.assert_allclose(volume_absorption([0.5, 0.8, 1.0], 2.0), [1.0, 0.4, 0.0])
    np.testing.assert_allclose(volume_absorption([0.5, 0.8, 1.0], -1.0), 0.0)


def test_white_point_beams_with_no_dispersion_equal_the_plain_render():
    """With an Abbe number so large the bands refract alike, the K bands'
    grids are K copies of the plain grid weighted by the band weights, which
    sum to (1,1,1): the beams' caustic and the landed flux equal the plain
    render's, to rounding. (The few fallback photons go through the k-nearest
    estimate, which counts K of them where the plain render has one.)"""
    paths = 2000
    plain = render(ball_lens(pixels=8), quick(lamp_rays=paths, density="beam"))
    scene = ball_lens(pixels=8)
    scene.objects[1].material.abbe = 1e12
    spectral = render(scene, quick(lamp_rays=6 * paths, density="beam", bands=6))
    assert spectral.stats["lamp_rays"] == 6 * plain.stats["lamp_rays"]
    np.testing.assert_allclose(spectral.stats["flux_landed_w"], plain.stats["flux_landed_w"], rtol=1e-9)

    def beams_only(result):
        floor = result.maps["Floor"]
        xy = floor.chart.coords(None, None, None, np.c_[np.linspace(0.0, shadow_radius(), 400), np.zeros((400, 2))])
        return floor.irradiance_at(xy) - IlluminationMap.irradiance_at(floor, xy)

    expected = beams_only(plain)
    assert expected.max() > 5 * unobstructed_irradiance(np.zeros((1, 2)))[0]
    np.testing.assert_allclose(beams_only(spectral), expected, atol=1e-9 * expected.max())


def test_white_point_photons_with_no_dispersion_keep_the_flux_white():
    """The same photons land in the same places; each carries K times its
    band's weight instead of 1. That factor has mean 1 and a relative spread
    s (about 1.2 at K = 6) per channel, so each channel's landed flux is the
    plain one within 4 s / sqrt(landed photons)."""
    settings = quick(lamp_rays=200_000, bands=6)
    plain = render(ball_lens(pixels=8), settings)
    scene = ball_lens(pixels=8)
    scene.objects[1].material.abbe = 1e12
    spectral = render(scene, settings)
    weights = 6 * bands(6).weights
    spread = np.sqrt((weights ** 2).mean(axis=0) - 1.0)
    landed = plain.stats["landed"]
    assert spectral.stats["landed"] == landed
    np.testing.assert_allclose(spectral.stats["flux_landed_w"], plain.stats["flux_landed_w"],
                               rtol=4 * spread.max() / math.sqrt(landed))


def sun_ball_lens(abbe: float) -> Scene:
    """A glass ball (R = 1, n_d = 1.5) in a vertical sun of 1000 W/m^2, its
    centre D = 3 above the floor: beyond the paraxial foci of all bands."""
    glass = Dielectric(1.5, abbe=abbe)
    return Scene(objects=[Object("Floor", shapes.plane(12.0), Diffuse(albedo=1.0)),
                          Object("Glass", shapes.uv_sphere(1.0, (0, 0, 3.0), 256, 128), glass)],
                 lights=[SunLight((0, 0, -1), 1000.0)], camera=top_camera(1.0, 8))


@pytest.mark.parametrize("density, paths, tolerance", [("splat", 1_000_000, 3 * 0.013 + 0.02),
                                                      ("beam", 30_000, 0.03)])
def test_blue_focuses_closer_to_the_lens_than_red(density, paths, tolerance):
    """A ball lens of index n focuses paraxial light at f = n R / (2 (n - 1))
    from its centre (Hecht, 6.2), so a higher index (blue) focuses closer.
    On a floor D beyond every focus, light from near the axis has spread
    over (D - f) / f of its width, so within a small radius of the axis the
    floor's irradiance is S (1 - F)^2 (f / (D - f))^2, F the normal-incidence
    Fresnel reflectance: red, focused farther away, is brighter there. Each
    channel is the band-weighted sum of that. Measured: the mean irradiance
    within rho = 0.1 m. Tolerance: 2% for the lens's spherical aberration
    over that aperture ((h / R)^2, h <= 0.1), plus for photons 3 times the
    colour noise of the ~8,000 landing there (1.2 / sqrt(N), 1.3%) and for
    beams 1% for their grid (30,000 paths, 5,000 a band).
    Photons make two specular events at most (in and out): light reflected
    twice inside the ball also exits downward, and for n near 1.54 it comes
    to a focus near this floor (8% more light there, in blue)."""
    b = bands(6)
    n = cauchy_ior(1.5, 15.0, b.wavelengths)
    focus = n / (2.0 * (n - 1.0))
    assert np.all(np.diff(focus) > 0)  # blue (short) wavelengths focus closer to the lens
    fresnel = ((n - 1) / (n + 1)) ** 2
    per_band = 1000.0 * (1 - fresnel) ** 2 * (focus / (3.0 - focus)) ** 2
    expected = per_band @ b.weights

    settings = RenderSettings(lamp_rays=paths, density=density, map_scale=10.0 if density == "splat" else None, spp=1,
                              max_depth=2)
    floor = render(sun_ball_lens(15.0), settings).maps["Floor"]
    ticks = np.linspace(-0.1, 0.1, 81)
    x, y = (a.ravel() for a in np.meshgrid(ticks, ticks))
    disc = x ** 2 + y ** 2 < 0.1 ** 2
    xy = floor.chart.coords(None, None, None, np.c_[x[disc], y[disc], np.zeros(disc.sum())])
    measured = floor.irradiance_at(xy).mean(axis=0)
    np.testing.assert_allclose(measured, expected, rtol=tolerance)
    assert measured[0] > 1.15 * measured[2]


def test_a_prism_fans_the_bands_as_snell_and_cauchy_say():
    """benchmarks/scenes/prism.py: a 45-degree prism (n_d 1.5, Abbe number 20) in
    a sun throws its spectrum on a floor; paths of two specular events (in
    at one face, out at the other). Its closed form traces Snell's law with
    Fresnel's transmittance at both faces for each band's Cauchy index,
    weighted by the band's RGB weights. Beams of flat faces land exactly:
    what is left is at the faces' edges, where beams that straddle one fall
    back to photons (0.5 mm measured at 60,000 to 120,000 lamp rays). So
    each channel's centroid is the closed form's within 1 mm (a quarter of
    the map's 4.4 mm cell), the red-blue spread (82 mm; 41 mm at twice the
    Abbe number) within 1%, and each channel's light within 0.5%."""
    b = bands(6)
    settings = RenderSettings(lamp_rays=120_000, density="beam", spp=1, max_depth=2)
    floor = render(prism.scene(20.0), settings).maps["Floor"]
    ticks = np.linspace(0.0, 1.3, 2601)
    x, y = (a.ravel() for a in np.meshgrid(ticks, np.linspace(-1.0, 1.0, 21)))
    irradiance = floor.irradiance_at(floor.chart.coords(None, None, None, np.c_[x, y, np.zeros(len(x))]))
    measured = (irradiance * x[:, None]).sum(axis=0) / irradiance.sum(axis=0)
    expected = prism.centroids(20.0, b.wavelengths, b.weights)
    np.testing.assert_allclose(measured, expected, atol=1e-3)
    spread = expected[0] - expected[2]
    assert spread > 0.08
    assert measured[0] - measured[2] == pytest.approx(spread, rel=0.01)
    # the light of a metre of the prism on the 1.3 m of floor measured
    np.testing.assert_allclose(irradiance.mean(axis=0), prism.landed_power(20.0, b.wavelengths, b.weights) / 1.3,
                               rtol=0.005)


def test_coloured_glass_slab_is_beer_lambert_exact():
    """benchmarks/scenes/slab.py: a slab whose absorption is the colour c at its
    thickness gives the floor S (1 - F)^2 c / (1 - F^2 c^2), to 4 standard
    deviations of the photon noise."""
    photons = 400_000
    np.testing.assert_allclose(slab.measured_irradiance(photons), slab.exact_irradiance(),
                               rtol=4 * slab.relative_noise(photons))


@pytest.mark.parametrize("abbe, why", [(0.0, "Abbe number must be > 0"), (-5.0, "Abbe number must be > 0"),
                                       (math.nan, "Abbe number must be > 0"), (0.05, "IOR <= 0")])
def test_bad_abbe_numbers_name_the_object(abbe, why):
    scene = ball_lens(pixels=4)
    scene.objects[1].material.abbe = abbe
    with pytest.raises(SceneError, match=f"Glass: .*{why}"):
        render(scene, quick(lamp_rays=10))


def test_bands_setting_is_checked():
    with pytest.raises(ValueError, match="bands must be in 1..64"):
        RenderSettings(bands=0).validate()
