"""The specular layer of a Principled receiver (optics/microfacet.py,
optics/principled.py) against closed forms: GGX's normalisation and
Smith's visible-normal identity, a white furnace, reciprocity, the smooth
limit (a dielectric's Fresnel reflection), the hemispherical Fresnel fit;
and in renders: a point lamp's highlight on the floor, the caustic times
the diffuse share only, a layer that reflects nothing."""

import math

import numpy as np
import pytest

from caustic_addon import Diffuse, MapCache, Object, PointLight, Scene, SceneError, Specular, render, shapes
from caustic_addon.optics.microfacet import ggx_d, ggx_lambda
from caustic_addon.optics.principled import (E_NODES, S_NODES, Layer, Lobe, albedo_curves, dielectric_fss,
                                             f0_from_ior, ior_from_f0, specular_f0)
from caustic_addon.optics.specular import fresnel_dielectric
from caustic_addon.sampling.warps import frames
from scenes import LAMP_Z, POWER, ball_lens, floor_points, quick, top_camera

UP = np.array([0.0, 0.0, 1.0])


def sphere_grid(n_theta=800, n_phi=400):
    """(dirs (m,3), solid angles (m,)) of a midpoint grid over the upper
    hemisphere, fine enough for lobes of alpha >= 0.04."""
    theta = (np.arange(n_theta) + 0.5) * (0.5 * math.pi / n_theta)
    phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
    t, p = (a.ravel() for a in np.meshgrid(theta, phi))
    dirs = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=1)
    return dirs, np.sin(t) * (0.5 * math.pi / n_theta) * (2.0 * math.pi / n_phi)


def lobe_of(layer: Layer, cos_v: float, n: int) -> Lobe:
    gain, _ = layer.toward(np.array([cos_v]))
    return Lobe(np.ones(n, dtype=bool), np.tile(layer.f0, (n, 1)), np.full(n, layer.eta), np.full(n, layer.alpha),
                np.tile(gain, (n, 1)))


def view_at(cos_v: float) -> np.ndarray:
    return np.array([math.sqrt(1.0 - cos_v * cos_v), 0.0, cos_v])


@pytest.mark.parametrize("alpha", [0.04, 0.2, 0.6])
def test_ggx_normals_project_to_the_unit_disc_and_smith_sees_cos_v(alpha):
    """int D(h) (n.h) dw_h = 1 (Walter et al. 2007, eq. 4), and
    int G1(v) max(0, v.h) D(h) dw_h = n.v (Heitz 2014, eq. 2)."""
    h, dw = sphere_grid()
    alphas = np.full(len(h), alpha)
    d = ggx_d(h[:, 2], alphas)
    assert np.sum(d * h[:, 2] * dw) == pytest.approx(1.0, abs=2e-3)
    for cos_v in (0.2, 0.6, 1.0):
        v = view_at(cos_v)
        g1 = 1.0 / (1.0 + ggx_lambda(np.full(len(h), cos_v), alphas))
        assert np.sum(g1 * np.maximum(h @ v, 0.0) * d * dw) == pytest.approx(cos_v, rel=3e-3)


@pytest.mark.parametrize("node", [10, 16, 25])
@pytest.mark.parametrize("mu_node", [8, 20, 31])
def test_a_white_furnace_reflects_all_its_light_with_multiple_scattering(node, mu_node):
    """F0 = 1 (a Specular Tint that saturates it) makes F = 1 everywhere and
    F_ss = 1, so Multiscatter GGX reflects exactly E / E = 1, at the nodes
    of Cycles' tables where no interpolation stands between E and its table."""
    roughness, cos_v = node / 31, mu_node / 31
    layer = Layer.of(roughness, 1.5, 0.5, np.full(3, 100.0), multiscatter=True)
    assert np.all(layer.f0 == 1.0)
    dirs, dw = sphere_grid()
    lobe = lobe_of(layer, cos_v, len(dirs))
    reflected = np.sum(lobe.weight(np.tile(UP, (len(dirs), 1)), np.tile(view_at(cos_v), (len(dirs), 1)), dirs)
                       * dw[:, None], axis=0)
    assert reflected == pytest.approx(np.ones(3), abs=3e-3)


def upper_hemisphere(rng, n):
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2])
    return d / np.linalg.norm(d, axis=1)[:, None]


def test_single_scattering_is_reciprocal():
    """Without the compensation (which Cycles takes from the view only),
    f(v, l) = f(l, v) for any pair: F(h.v) D(h) G2(v, l) / (4 cos_v cos_l)."""
    rng = np.random.default_rng(1)
    n = 2000
    a, b = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    layer = Layer.of(0.4, 1.45, 0.5, np.ones(3), multiscatter=False)
    lobe = lobe_of(layer, 1.0, n)
    normal = np.tile(UP, (n, 1))
    forward = lobe.weight(normal, a, b) / b[:, 2:3]
    backward = lobe.weight(normal, b, a) / a[:, 2:3]
    assert np.all(lobe.gain == 1.0) and forward.max() > 1.0
    assert np.allclose(forward, backward, rtol=1e-12, atol=0.0)


def lobe_albedo(layer: Layer, cos_v: float, n: int = 100_000, normal=UP) -> float:
    """The lobe's directional albedo (red) toward `cos_v`, as the mean of
    weight / pdf over n stratified samples of its visible normals."""
    g = (np.arange(int(math.sqrt(n))) + 0.5) / int(math.sqrt(n))
    uv = np.stack([a.ravel() for a in np.meshgrid(g, g)], axis=1)
    m = len(uv)
    lobe = lobe_of(layer, cos_v, m)
    normals, view = np.tile(normal, (m, 1)), np.tile(view_at(cos_v), (m, 1))
    t, b = frames(normals)
    dirs = lobe.sample(normals, t, b, view, uv)
    up = dirs[:, 2] > 0.0
    w = lobe.weight(normals, view, dirs)[:, 0] / np.maximum(lobe.pdf(normals, view, dirs), 1e-300)
    return float(np.mean(np.where(up, w, 0.0)))


@pytest.mark.parametrize("ior", [1.33, 1.5, 2.4])
@pytest.mark.parametrize("cos_v", [0.3, 0.7, 1.0])
def test_the_smooth_limit_is_a_dielectrics_fresnel_reflection(ior, cos_v):
    """As roughness goes to 0 the lobe's directional albedo tends to the
    exact Fresnel reflectance of a smooth dielectric (Hecht), and the
    diffuse base keeps 1 - F: at Roughness 0.05 (alpha 0.0025) to 0.2% of
    F; the share to 0.005, what the linear interpolation between the 16
    cosines of Cycles' table leaves of the Fresnel curve."""
    exact = float(fresnel_dielectric(np.array([cos_v]), 1.0 / ior)[0])
    layer = Layer.of(0.05, ior, 0.5, np.ones(3), multiscatter=False)
    assert lobe_albedo(layer, cos_v) == pytest.approx(exact, rel=2e-3)
    assert layer.toward(np.array([cos_v]))[1][0] == pytest.approx(1.0 - exact, abs=0.005)


def test_the_layer_reads_its_curves_linearly_between_cycles_nodes():
    """Layer.toward reads s and E as Cycles' lookup_table_read does: the
    tabulated values at the nodes i / (k - 1), straight lines between them,
    the end values past 0 and 1. Without multiscatter the share is
    1 - (F0 + (1 - F0) s(mu)), with it the closed form of toward1."""
    layer = Layer.of(0.3, 1.5, 0.5, np.ones(3), multiscatter=False)
    nodes = np.arange(S_NODES) / (S_NODES - 1)
    mid = 0.5 * (nodes[:-1] + nodes[1:])
    cos_v = np.concatenate([nodes, mid, [-0.5, 1.5]])
    s = np.concatenate([layer.s_curve, 0.5 * (layer.s_curve[:-1] + layer.s_curve[1:]),
                        layer.s_curve[[0, -1]]])
    _, share = layer.toward(cos_v)
    assert share == pytest.approx(1.0 - (layer.f0[0] + (1.0 - layer.f0[0]) * s), rel=1e-12, abs=1e-15)
    rich = Layer.of(0.3, 1.5, 0.5, np.ones(3), multiscatter=True)
    e_nodes = np.arange(E_NODES) / (E_NODES - 1)
    gain, _ = rich.toward(0.5 * (e_nodes[:-1] + e_nodes[1:]))
    e = 0.5 * (rich.e_curve[:-1] + rich.e_curve[1:])
    fms = rich.fss[0] * rich.e_avg / (1.0 - rich.fss[0] * (1.0 - rich.e_avg))
    assert gain[:, 0] == pytest.approx(1.0 + fms * (1.0 - e) / e, rel=1e-12)


def test_specular_ior_level_scales_f0_and_its_ior_follows():
    """F0 = ((n - 1) / (n + 1))^2 at level 0.5, 2 level F0 otherwise, and the
    Fresnel curve's IOR is the one of that F0; level 0 leaves no layer."""
    assert specular_f0(1.5, 0.5) == (pytest.approx(0.04), 1.5)
    f0, eta = specular_f0(1.5, 1.0)
    assert f0 == pytest.approx(0.08) and f0_from_ior(eta) == pytest.approx(0.08)
    assert ior_from_f0(f0_from_ior(2.4)) == pytest.approx(2.4)
    assert Layer.of(0.3, 1.5, 0.0, np.ones(3), True) is None
    assert Layer.of(0.3, 1.0, 0.5, np.ones(3), True) is None
    tinted = Layer.of(0.3, 1.5, 0.5, np.array([1.0, 0.5, 0.0]), True)
    assert tinted.f0 == pytest.approx([0.04, 0.02, 0.0])


@pytest.mark.parametrize("ior", [0.75, 1.05, 1.2, 1.5, 2.0, 3.0])
def test_the_hemispherical_fresnel_fit_is_near_the_integral(ior):
    """Kulla and Conty's fit of F_ss = 2 int F_d(mu) mu dmu, which Cycles
    uses, is within 0.007 of the integral (2.5% at IOR 1.5, 15% at 1.2,
    where F_ss is 0.04 and only weighs the lobe's multiple scattering)."""
    mu = (np.arange(20000) + 0.5) / 20000
    exact = np.mean(2.0 * mu * fresnel_dielectric(mu, 1.0 / ior))
    assert dielectric_fss(ior) == pytest.approx(exact, abs=0.007)


def test_a_layer_over_a_white_base_reflects_no_more_than_comes_in():
    """Diffuse share plus the lobe's albedo, seen from any angle, stays at
    most 1 (Cycles' layering takes what the layer reflects from the base)."""
    dirs, dw = sphere_grid()
    for roughness in (0.1, 0.3, 0.6, 1.0):
        layer = Layer.of(roughness, 1.5, 1.0, np.ones(3), multiscatter=True)
        for cos_v in (0.1, 0.4, 0.8, 1.0):
            lobe = lobe_of(layer, cos_v, len(dirs))
            glossy = np.sum(lobe.weight(np.tile(UP, (len(dirs), 1)), np.tile(view_at(cos_v), (len(dirs), 1)),
                                        dirs)[:, 0] * dw)
            assert glossy + layer.toward(np.array([cos_v]))[1][0] <= 1.005


def test_the_albedo_curves_start_at_a_mirror_and_darken_with_roughness():
    e_smooth, s_smooth, avg_smooth = albedo_curves(0.0, 1.5)
    e_rough, _, avg_rough = albedo_curves(1.0, 1.5)
    assert e_smooth[1:] == pytest.approx(1.0, abs=2e-3) and avg_smooth == pytest.approx(1.0, abs=2e-3)
    assert e_rough[-1] < 0.35 and avg_rough < 0.6
    assert s_smooth[-1] == pytest.approx(0.0, abs=1e-3) and s_smooth[0] == pytest.approx(1.0, abs=0.02)


def principled_floor_scene(specular, albedo=0.5, pixels=32, glass=False):
    scene = ball_lens(pixels=pixels, albedo=albedo) if glass else Scene(
        [Object("Floor", shapes.plane(8.0), Diffuse(albedo))], [PointLight((0, 0, LAMP_Z), POWER)],
        top_camera(2.0, pixels))
    floor = scene.objects[0]
    scene.objects[0] = Object(floor.name, floor.mesh, Diffuse(albedo, specular=specular))
    return scene


def test_a_point_lamps_highlight_on_the_floor_is_the_ggx_closed_form():
    """Straight down on a floor lit from straight above: at each pixel
    L = E cos_l (share albedo / pi) + E F(h.v) D(h) G2 / (4 cos_v) gain, with
    D, Lambda and F written out here (Walter et al. 2007; Heitz 2014; Hecht)."""
    spec = Specular(roughness=0.3, ior=1.5)
    image = render(principled_floor_scene(spec), quick(lamp_rays=0, spp=1)).passes["direct"][..., 0]
    xy = floor_points(principled_floor_scene(spec)).reshape(-1, 2)
    to_lamp = np.concatenate([-xy, np.full((len(xy), 1), LAMP_Z)], axis=1)
    d2 = np.sum(to_lamp ** 2, axis=1)
    l = to_lamp / np.sqrt(d2)[:, None]
    cos_l = l[:, 2]
    irradiance = POWER / (4 * math.pi) / d2
    h = (l + UP) / np.linalg.norm(l + UP, axis=1)[:, None]
    a2 = 0.3 ** 4
    d = a2 / (math.pi * (h[:, 2] ** 2 * (a2 - 1.0) + 1.0) ** 2)
    lam_l = 0.5 * (np.sqrt(1.0 + a2 * (1.0 - cos_l ** 2) / cos_l ** 2) - 1.0)
    c = h[:, 2]                                     # h.v with v straight up
    g = np.sqrt(1.5 ** 2 - 1.0 + c * c)
    fresnel = 0.5 * ((g - c) / (g + c)) ** 2 * (1.0 + ((c * (g + c) - 1.0) / (c * (g - c) + 1.0)) ** 2)
    layer = Layer.of(0.3, 1.5, 0.5, np.ones(3), True)
    gain, share = (a[0] for a in layer.toward(np.array([1.0])))
    expected = irradiance * (cos_l * 0.5 * share / math.pi + fresnel * d / (4.0 * (1.0 + lam_l)) * gain[0])
    assert image.ravel() == pytest.approx(expected, rel=1e-5)       # the passes are float32


def test_the_caustic_on_a_principled_floor_is_its_diffuse_share_only():
    """The map holds irradiance, not its directions: the caustic pass under
    a layer is the plain floor's times the diffuse share toward the eye.
    The lamp stands aside, so the caustic falls outside the ball's
    silhouette, where the eye looks straight down."""
    def scene(spec):
        built = principled_floor_scene(spec, glass=True)
        built.lights = [PointLight((5.0, 0.0, LAMP_Z), POWER)]
        return built

    settings = quick(lamp_rays=40_000, density="beam")
    plain = render(scene(None), settings).passes["caustic"][..., 0]
    layered = render(scene(Specular(roughness=0.3, ior=1.5, level=1.0)), settings).passes["caustic"][..., 0]
    share = Layer.of(0.3, 1.5, 1.0, np.ones(3), True).toward(np.array([1.0]))[1][0]
    outside = np.linalg.norm(floor_points(scene(None)), axis=-1) > 1.05
    lit = outside & (plain > 1e-2 * plain.max())
    assert lit.sum() > 20
    assert layered[lit] == pytest.approx(plain[lit] * share, rel=1e-5)
    assert 0.9 < share < 0.93


def test_a_layer_that_reflects_nothing_changes_nothing():
    plain = render(principled_floor_scene(None), quick(lamp_rays=0, spp=1)).image
    for spec in (Specular(ior=1.0), Specular(level=0.0)):
        assert np.array_equal(render(principled_floor_scene(spec), quick(lamp_rays=0, spp=1)).image, plain)


def test_the_layer_changes_no_map():
    """Maps hold irradiance: a new roughness re-runs only the eye pass."""
    cache = MapCache()
    render(principled_floor_scene(Specular(roughness=0.3), glass=True), quick(lamp_rays=5_000), cache=cache)
    again = render(principled_floor_scene(Specular(roughness=0.6), glass=True), quick(lamp_rays=5_000), cache=cache)
    assert again.stats["maps_cached"]


@pytest.mark.parametrize("spec, message", [
    (Specular(roughness=1.5), "roughness must be in 0..1"),
    (Specular(ior=0.0), "IOR must be positive"),
    (Specular(level=-1.0), "must not be negative"),
    (Specular(roughness=math.nan), "NaN"),
])
def test_a_bad_layer_is_named(spec, message):
    with pytest.raises(SceneError, match=f"Floor: .*{message}"):
        render(principled_floor_scene(spec), quick(lamp_rays=0))


def test_sampling_the_lobe_about_any_normal_gives_its_albedo():
    """weight / pdf over the lobe's own samples integrates what a grid of
    directions does, for a normal along z and a tilted one."""
    layer = Layer.of(0.4, 1.5, 0.5, np.ones(3), True)
    dirs, dw = sphere_grid()
    lobe = lobe_of(layer, 0.6, len(dirs))
    grid = lobe.weight(np.tile(UP, (len(dirs), 1)), np.tile(view_at(0.6), (len(dirs), 1)), dirs)[:, 0] @ dw
    assert lobe_albedo(layer, 0.6) == pytest.approx(grid, rel=2e-3)
    n = 40_000
    tilt = np.array([0.6, 0.0, 0.8])
    t, b = (a[0] for a in frames(tilt[None]))
    local = np.stack([t, b, tilt])
    view = np.tile(view_at(0.6) @ local, (n, 1))
    normal = np.tile(tilt, (n, 1))
    lobe = lobe_of(layer, 0.6, n)
    rng = np.random.default_rng(3)
    sampled = lobe.sample(normal, *frames(normal), view, rng.random((n, 2)))
    w = lobe.weight(normal, view, sampled)[:, 0] / np.maximum(lobe.pdf(normal, view, sampled), 1e-300)
    assert np.mean(np.where(sampled @ tilt > 0.0, w, 0.0)) == pytest.approx(grid, rel=1e-2)
