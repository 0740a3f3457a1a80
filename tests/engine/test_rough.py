"""Rough glass and metal: GGX microfacet sampling against its closed forms
and against quadratures of the Walter et al. BSDF, Multiscatter GGX's
energy in white furnaces, and rough casters in the passes."""

import math
from dataclasses import replace

import numpy as np
import pytest

from caustic_addon import (Dielectric, Diffuse, Object, PointLight, Reflector, RenderSettings, Scene,
                           SceneError, render, shapes)
from caustic_addon.optics.microfacet import (alpha_of, branch_pdf, bsdf_cosine, ggx_d, ggx_lambda,
                                             sample_visible_normals, sample_visible_normals_local, shadowing_weight)
from caustic_addon.optics.multiscatter import (albedo_at, albedo_cosines, multiscatter_factor,
                                               single_scatter_albedo)
from caustic_addon.optics.specular import fresnel_dielectric, reflect, refract
from caustic_addon.sampling.warps import frames
from caustic_addon.scene.lights import World
from caustic_addon.scene.validate import rough_caster_warnings
from scenes import top_camera

N = 200_000


def incoming(mu: float, n: int = N) -> np.ndarray:
    """(n,3) the local direction toward the light at cosine `mu`."""
    return np.tile([math.sqrt(1.0 - mu * mu), 0.0, mu], (n, 1))


def sphere_grid(m: int):
    """Directions (k,3) on a (theta, phi) midpoint grid of the whole sphere, and their solid angles (k,)."""
    cos_t = 1.0 - 2.0 * (np.arange(m) + 0.5) / m
    phi = (np.arange(2 * m) + 0.5) / (2 * m) * 2.0 * math.pi
    c, p = (g.ravel() for g in np.meshgrid(cos_t, phi, indexing="ij"))
    s = np.sqrt(1.0 - c * c)
    return np.stack([s * np.cos(p), s * np.sin(p), c], axis=1), np.full(len(c), 4.0 * math.pi / (2 * m * m))


def test_roughness_is_squared_into_alpha_as_cycles():
    assert np.allclose(alpha_of([0.0, 0.1, 0.5, 1.0, 1.5, -0.2]), [0.0, 0.01, 0.25, 1.0, 1.0, 0.0])


@pytest.mark.parametrize("alpha", [0.01, 0.16, 0.7])
def test_visible_normals_at_normal_incidence_follow_ggx(alpha):
    """From straight above, the visible normals are D(h) cos(theta_h):
    tan^2(theta_h) has the closed-form CDF x / (alpha^2 + x)."""
    h = sample_visible_normals_local(incoming(1.0), np.full(N, alpha), np.random.default_rng(1).random((N, 2)))
    tan2 = np.sort((1.0 - h[:, 2] ** 2) / h[:, 2] ** 2)
    cdf = tan2 / (alpha ** 2 + tan2)
    assert np.abs(cdf - (np.arange(N) + 0.5) / N).max() < 1.63 / math.sqrt(N)  # Kolmogorov-Smirnov, 1%


@pytest.mark.parametrize("alpha, mu", [(0.16, 0.3), (0.5, 0.8)])
def test_visible_normals_have_heitz_density(alpha, mu):
    """At oblique incidence the sampled normals' distribution over cos(theta_h)
    bins and over azimuth halves matches the quadrature of
    D_wi(h) = G1(wi) max(0, wi.h) D(h) / cos(theta_i) (Heitz 2018, eq. 1),
    which integrates to 1."""
    h = sample_visible_normals_local(incoming(mu), np.full(N, alpha), np.random.default_rng(2).random((N, 2)))
    dirs, dw = sphere_grid(1200)
    up = dirs[:, 2] > 0
    dirs, dw = dirs[up], dw[up]
    g1 = 1.0 / (1.0 + ggx_lambda(np.array([mu]), np.array([alpha])))
    density = g1 * np.maximum(dirs @ incoming(mu, 1)[0], 0.0) * ggx_d(dirs[:, 2], np.full(len(dirs), alpha)) / mu
    assert np.sum(density * dw) == pytest.approx(1.0, abs=2e-3)
    edges = np.linspace(0.0, 1.0, 11)
    for value, sampled in ((dirs[:, 2], h[:, 2]), (np.sign(dirs[:, 0]), np.sign(h[:, 0]))):
        bins = edges if value.min() >= 0 else np.array([-1.5, 0.0, 1.5])
        expected = np.histogram(value, bins, weights=density * dw)[0]
        got = np.histogram(sampled, bins)[0] / N
        assert np.abs(got - expected).max() < 4.0 * math.sqrt(expected.max() / N) + 2e-3


def test_world_normals_turn_with_the_macro_normal():
    """The world sampler is the local one in the frame of the macro normal."""
    rng = np.random.default_rng(3)
    uv = rng.random((1000, 2))
    normal = np.tile([0.0, -1.0, 0.0], (1000, 1))
    wi = np.tile([0.6, -0.8, 0.0], (1000, 1))
    h = sample_visible_normals(wi, normal, np.full(1000, 0.2), uv)
    t, b = frames(normal)
    local_wi = np.stack([wi @ t[0], wi @ b[0], wi @ normal[0]], axis=1)
    local = sample_visible_normals_local(local_wi, np.full(1000, 0.2), uv)
    assert np.allclose(np.stack([h @ t[0], h @ b[0], h @ normal[0]], axis=1), local, atol=1e-12)


def brdf_albedo(alpha: float, mu: float) -> float:
    """int f_r cos(theta_o) dw_o of Walter et al.'s GGX BRDF,
    D G2 / (4 cos_i cos_o), by quadrature over the upper hemisphere."""
    wo, dw = sphere_grid(1600)
    up = wo[:, 2] > 0
    wo, dw = wo[up], dw[up]
    wi = incoming(mu, 1)[0]
    h = wo + wi
    h /= np.linalg.norm(h, axis=1)[:, None]
    a = np.full(len(wo), alpha)
    g2 = 1.0 / (1.0 + ggx_lambda(np.full(len(wo), mu), a) + ggx_lambda(wo[:, 2], a))
    return float(np.sum(ggx_d(h[:, 2], a) * g2 / (4.0 * mu) * dw))


def btdf_parts(alpha: float, mu: float, eta: float) -> tuple[float, float]:
    """(reflected, transmitted) flux fractions of Walter et al.'s rough
    dielectric for light from cosine `mu`, eta = n_light / n_other, by
    quadrature over the sphere: reflection F D G2 / (4 cos_i), transmission
    (1 - F) D G2 |i.h| |o.h| / (cos_i (eta i.h + o.h)^2), the generalised
    half vector h = -(eta i + o) (eq. 16, 21), per unit solid angle of o;
    no 1/eta^2: flux, not radiance."""
    wo, dw = sphere_grid(1600)
    wi = incoming(mu, 1)[0]
    a = np.full(len(wo), alpha)
    lam_i = ggx_lambda(np.full(len(wo), mu), a)
    g2 = 1.0 / (1.0 + lam_i + ggx_lambda(np.abs(wo[:, 2]), a))
    up = wo[:, 2] > 0
    h = np.where(up[:, None], wo + wi, -(eta * wi + wo))
    h /= np.linalg.norm(h, axis=1)[:, None]
    h *= np.sign(h[:, 2])[:, None]
    i_h, o_h = h @ wi, np.einsum("ij,ij->i", h, wo)
    f = fresnel_dielectric(np.abs(i_h), eta)
    reflected = np.where(up & (i_h > 0), f * ggx_d(h[:, 2], a) * g2 / (4.0 * mu), 0.0)
    ok = ~up & (i_h > 0) & (o_h < 0)
    transmitted = np.where(ok, (1.0 - f) * ggx_d(h[:, 2], a) * g2 * np.abs(i_h * o_h)
                           / (mu * (eta * i_h + o_h) ** 2), 0.0)
    return float(np.sum(reflected * dw)), float(np.sum(transmitted * dw))


def sampled_parts(alpha: float, mu: float, eta):
    """(reflected, transmitted) mean weights of paths sampled as the passes
    do: a visible normal, Fresnel there, both branches, G2/G1, none past the horizon."""
    wi = incoming(mu)
    a = np.full(N, alpha)
    h = sample_visible_normals_local(wi, a, np.random.default_rng(4).random((N, 2)))
    d = -wi
    out = reflect(d, h)
    kept = np.where(out[:, 2] > 0, shadowing_weight(mu, out[:, 2], a), 0.0)
    if eta is None:
        return kept.mean(), 0.0
    f = fresnel_dielectric(np.einsum("ij,ij->i", wi, h), eta)
    through, tir = refract(d, h, eta)
    crossed = np.where(~tir & (through[:, 2] < 0), shadowing_weight(mu, -through[:, 2], a), 0.0)
    return (f * kept).mean(), ((1.0 - f) * crossed).mean()


@pytest.mark.parametrize("alpha, mu", [(0.16, 0.9), (0.25, 0.5), (0.49, 0.2)])
def test_sampled_metal_albedo_is_the_brdf_integral(alpha, mu):
    """What a path keeps at a reflectance-1 rough mirror, on average, is the
    GGX BRDF's directional albedo, the single-scattering energy: the
    sampler and its weight G2/G1 are Walter et al.'s BRDF."""
    reflected, _ = sampled_parts(alpha, mu, None)
    assert reflected == pytest.approx(brdf_albedo(alpha, mu), abs=3e-3)
    assert reflected < 1.0 - 1e-3


@pytest.mark.parametrize("alpha, mu, eta", [(0.16, 0.9, 1 / 1.5), (0.25, 0.4, 1 / 1.5), (0.25, 0.8, 1.5),
                                            (0.09, 0.6, 1.33)])
def test_sampled_glass_parts_are_the_bsdf_integrals(alpha, mu, eta):
    """Reflected and refracted flux of the sampled rough interface, entering
    and leaving glass (TIR included), against the quadrature of Walter et
    al.'s BRDF and BTDF; with the Fresnel at each microfacet, the split
    matches the exact Fresnel of the smooth interface as alpha goes to 0."""
    reflected, transmitted = sampled_parts(alpha, mu, eta)
    quad_r, quad_t = btdf_parts(alpha, mu, eta)
    assert reflected == pytest.approx(quad_r, abs=3e-3)
    assert transmitted == pytest.approx(quad_t, abs=3e-3)
    smooth_r, smooth_t = sampled_parts(1e-6, mu, eta)
    f = float(fresnel_dielectric(np.array([mu]), eta)[0])
    assert smooth_r == pytest.approx(f, abs=1e-6) and smooth_t == pytest.approx(1.0 - f, abs=1e-6)


@pytest.mark.parametrize("alpha, mu, eta", [(0.16, 0.9, 1.5), (0.25, 0.4, 1 / 1.5), (0.49, 0.7, 1.33)])
def test_each_branchs_density_is_where_the_sampler_sends_it(alpha, mu, eta):
    """branch_pdf, which multiple importance sampling weighs a rough
    caster's rays by, is the density of the directions the passes' branches
    take (a visible normal, then reflection or refraction about it): its
    integrals of 1, x and z^2 over each branch's side are the sampled ones;
    and bsdf_cosine over it is what a branch keeps, F G2/G1 or (1 - F) G2/G1."""
    wi = incoming(mu)
    a = np.full(N, alpha)
    h = sample_visible_normals_local(wi, a, np.random.default_rng(7).random((N, 2)))
    reflected = reflect(-wi, h)
    refracted, tir = refract(-wi, h, eta)
    grid, dw = sphere_grid(800)
    m = len(grid)
    density = branch_pdf(incoming(mu, m), grid, np.tile([0.0, 0.0, 1.0], (m, 1)), np.full(m, alpha), np.full(m, eta))
    for sampled, side in ((reflected[reflected[:, 2] > 0], grid[:, 2] > 0),
                          (refracted[~tir & (refracted[:, 2] < 0)], grid[:, 2] < 0)):
        for moment in (lambda d: np.ones(len(d)), lambda d: d[:, 0], lambda d: d[:, 2] ** 2):
            assert moment(sampled).sum() / N == pytest.approx(np.sum((moment(grid) * density * dw)[side]), abs=4e-3)
    view, up = incoming(mu, m), np.tile([0.0, 0.0, 1.0], (m, 1))
    ok = density > 1e-3
    f_cos = bsdf_cosine(view, grid, up, np.full(m, alpha), np.full(m, eta), np.zeros(m, dtype=bool))
    half = np.where((grid[:, 2] > 0)[:, None], view + grid, -(eta * view + grid))
    half /= np.linalg.norm(half, axis=1)[:, None] * np.sign(half[:, 2])[:, None]
    fresnel = fresnel_dielectric(np.abs(half @ view[0]), eta)
    kept = np.where(grid[:, 2] > 0, fresnel, 1.0 - fresnel) * shadowing_weight(np.full(m, mu), np.abs(grid[:, 2]),
                                                                               np.full(m, alpha))
    assert (f_cos / np.where(ok, density, 1.0))[ok] == pytest.approx(kept[ok], rel=1e-6, abs=1e-9)


def test_albedo_tables_and_multiscatter_factor():
    """The tables hold the sampled albedo; the multiscatter factor is 1/E for
    a white surface, and for a coloured one Kulla and Conty's, below 1/E."""
    mu = albedo_cosines()
    for eta in (None, 1 / 1.5, 1.5):
        table = single_scatter_albedo(0.25, eta)
        for k in (4, 20):
            assert table[k] == pytest.approx(sum(sampled_parts(0.25, mu[k], eta)), abs=2e-3)
    table = single_scatter_albedo(0.49, None)[None]
    e = albedo_at(np.repeat(table, 2, axis=0), np.array([0.5, 0.5]))
    factor = multiscatter_factor(e, np.full(2, 0.8), np.array([[1.0, 1.0, 1.0], [0.5, 0.5, 0.5]]))
    assert np.allclose(factor[0], 1.0 / e[0])
    assert np.all((factor[1] > 1.0) & (factor[1] < 1.0 / e[1]))


def furnace(material, pixels=48, max_depth=12) -> tuple[np.ndarray, np.ndarray]:
    """(red radiance (k,), cosine of incidence (k,)) of the k pixels whose
    centres see a unit sphere of `material`, within 0.9 of its radius, in a
    uniform white world of radiance 1, from straight above."""
    scene = Scene([Object("Ball", shapes.uv_sphere(1.0, (0, 0, 0), 256, 128), material)], [],
                  top_camera(1.0, pixels, 10.0), world=World(color=1.0))
    image = render(scene, RenderSettings(spp=16, max_depth=max_depth)).image[..., 0].ravel()
    centre = (np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0
    x, y = np.meshgrid(centre, centre)
    return image[(x * x + y * y).ravel() < 0.9 ** 2], np.sqrt(np.maximum(0.0, 1.0 - x * x - y * y)).ravel()[
        (x * x + y * y).ravel() < 0.9 ** 2]


@pytest.mark.parametrize("roughness", [0.3, 0.7])
def test_white_furnace_rough_metal_gives_back_all_light(roughness):
    """A reflectance-1 rough metal sphere in a white world (the white furnace):
    with Multiscatter GGX every pixel's expected radiance is the world's, 1;
    with plain GGX it is the single-scattering albedo at the pixel's
    cosine, which loses light."""
    seen, _ = furnace(Reflector(1.0, roughness=roughness))
    assert seen.mean() == pytest.approx(1.0, abs=2e-3)
    plain, mu = furnace(Reflector(1.0, roughness=roughness, multiscatter=False))
    table = np.repeat(single_scatter_albedo(roughness ** 2, None)[None], len(mu), axis=0)
    assert plain.mean() == pytest.approx(albedo_at(table, mu).mean(), abs=2e-3)
    assert plain.mean() < 0.995


def test_white_furnace_rough_glass_keeps_the_light():
    """A clear rough glass sphere in a white world looks as bright as the
    world: what it reflects and what it lets through sum to 1, given the
    bounces for the light that rough facets trap inside by total internal
    reflection (12 bounces lose 1% of it, 32 lose 0.15%)."""
    seen, _ = furnace(Dielectric(1.5, roughness=0.5), max_depth=32)
    assert seen.mean() == pytest.approx(1.0, abs=3e-3)


MIRROR_Z, LAMP_Z, HALF = 1.0, 0.5, 0.15
# Rings over the floor: 5 cm wide out to 3 m, then wider out to 20 m
# (beyond it, under 0.1% of the flux lands for Roughness 0.6).
NEAR = 61
RINGS = np.concatenate([np.linspace(0.0, 3.0, NEAR), np.geomspace(3.0, 20.0, 21)[1:]])


def ceiling(roughness: float, multiscatter: bool = True) -> Scene:
    """A square rough mirror (reflectance 1, side 2 HALF) at MIRROR_Z over a
    point lamp, facing down onto a 40 m floor; smooth, it would light a
    square of side 6 HALF."""
    objects = [Object("Floor", shapes.plane(40.0), Diffuse(albedo=1.0)),
               Object("Mirror", shapes.plane(2 * HALF, (0, 0, MIRROR_Z)),
                      Reflector(1.0, roughness=roughness, multiscatter=multiscatter))]
    return Scene(objects, [PointLight((0, 0, LAMP_Z), 1000.0)], top_camera(2.0, 8))


def ceiling_irradiance(roughness: float, multiscatter: bool, floor_xy: np.ndarray, side: int = 32) -> np.ndarray:
    """(n,) the closed form of the floor's irradiance at `floor_xy (n,2)`
    under the rough ceiling mirror: over the mirror's points p (a side x side
    midpoint grid; 32 is within 1e-4 of 128), E(x) = int I D(h) G2(i, o)
    M(o) cos_floor / (4 d_lamp^2 d_floor^2) dA: Walter et al.'s BRDF
    D G2 / (4 cos_i cos_o) times the irradiance I cos_i / d_lamp^2 and the
    transfer cos_o cos_floor / d_floor^2; M is Multiscatter GGX's 1/E at the
    cosine toward the floor (the eye's side, as Cycles takes it), or 1."""
    alpha = roughness ** 2
    ticks = ((np.arange(side) + 0.5) / side * 2.0 - 1.0) * HALF
    px, py = (g.ravel() for g in np.meshgrid(ticks, ticks))
    mirror = np.stack([px, py, np.full(len(px), MIRROR_Z)], axis=1)
    to_lamp = np.array([0.0, 0.0, LAMP_Z]) - mirror
    d_lamp2 = np.sum(to_lamp ** 2, axis=1)
    i = to_lamp / np.sqrt(d_lamp2)[:, None]
    floor = np.concatenate([floor_xy, np.zeros((len(floor_xy), 1))], axis=1)
    o = floor[:, None, :] - mirror[None, :, :]
    d_floor = np.linalg.norm(o, axis=2)
    o /= d_floor[..., None]
    h = i[None] + o
    cos_h = -h[..., 2] / np.linalg.norm(h, axis=2)
    a = np.full(cos_h.shape, alpha)
    g2 = 1.0 / (1.0 + ggx_lambda(-i[None, :, 2], a) + ggx_lambda(-o[..., 2], a))
    factor = 1.0
    if multiscatter:
        table = single_scatter_albedo(alpha, None)[None]
        factor = 1.0 / albedo_at(np.repeat(table, o[..., 2].size, axis=0), -o[..., 2].ravel()).reshape(o.shape[:2])
    integrand = ggx_d(cos_h, a) * g2 * factor * (MIRROR_Z / d_floor) / (4.0 * d_lamp2[None] * d_floor ** 2)
    return 1000.0 / (4.0 * math.pi) * integrand.sum(axis=1) * (2.0 * HALF / side) ** 2


def ring_profile(ring_means: np.ndarray, rings: np.ndarray) -> tuple[float, float, float]:
    """(the flux within the outer ring, W; the radii within which half and
    three quarters of it land, m) from the mean irradiance of each ring
    between `rings`' radii."""
    flux = np.concatenate([[0.0], np.cumsum(ring_means * math.pi * np.diff(rings ** 2))])
    return flux[-1], *(float(np.interp(share * flux[-1], flux, rings)) for share in (0.5, 0.75))


def test_a_rough_mirrors_caustic_is_the_microfacet_closed_form():
    """The floor under the rough ceiling mirror against the closed form's
    quadrature, single scattering and Multiscatter GGX, as photons (the
    paper's splat map, whose cells blur least) and in beam mode (photons
    for a lamp that lights a rough caster, the adaptive estimate): the flux landed (within
    0.12% of it, the floor's rim and the quadrature's error), and ring by
    ring out to 3 m the radii that hold half and three quarters of the flux
    (within 0.6%, the map cell's blur; the adaptive estimate's reach adds
    up to 1.4%). The width grows with roughness as the closed form's."""
    angles = (np.arange(6) + 0.5) / 6 * math.pi / 4
    mid = 0.5 * (RINGS[1:] + RINGS[:-1])
    polar = np.stack([np.repeat(mid, len(angles)) * np.cos(np.tile(angles, len(mid))),
                      np.repeat(mid, len(angles)) * np.sin(np.tile(angles, len(mid)))], axis=1)
    rng = np.random.default_rng(6)
    ring = np.repeat(np.arange(NEAR - 1), 4000)
    r = np.sqrt(RINGS[ring] ** 2 + rng.random(len(ring)) * (RINGS[ring + 1] ** 2 - RINGS[ring] ** 2))
    phi = 2.0 * math.pi * rng.random(len(ring))
    samples = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    widths = {}
    for roughness, multiscatter, density, tolerance in ((0.3, False, "splat", 0.015), (0.6, True, "splat", 0.015),
                                                        (0.3, True, "beam", 0.025)):
        means = ceiling_irradiance(roughness, multiscatter, polar).reshape(len(mid), -1).mean(axis=1)
        total = ring_profile(means, RINGS)[0]
        exact = ring_profile(means[:NEAR - 1], RINGS[:NEAR])
        result = render(ceiling(roughness, multiscatter), RenderSettings(lamp_rays=200_000, density=density, spp=1))
        seen = result.maps["Floor"].irradiance_at(samples)[:, 0]
        ours = ring_profile(np.bincount(ring, weights=seen) / np.bincount(ring), RINGS[:NEAR])
        case = f"roughness {roughness}, multiscatter {multiscatter}, {density}"
        assert result.stats["flux_landed_w"][0] == pytest.approx(total, rel=3e-3), case
        assert ours[1] == pytest.approx(exact[1], rel=tolerance), case
        assert ours[2] == pytest.approx(exact[2], rel=tolerance), case
        widths[roughness] = (ours[2], exact[2])
    assert widths[0.6][1] > 1.8 * widths[0.3][1]
    assert widths[0.6][0] / widths[0.3][0] == pytest.approx(widths[0.6][1] / widths[0.3][1], rel=0.02)


def flux_radius(imap, radius: float, share: float = 0.75) -> float:
    """The radius within which `share` of the caustic flux inside `radius`
    lands, from irradiance samples uniform in area."""
    rng = np.random.default_rng(5)
    r = radius * np.sqrt(rng.random(400_000))
    phi = 2.0 * math.pi * rng.random(len(r))
    e = imap.irradiance_at(np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1))[:, 0]
    order = np.argsort(r)
    return float(r[order][np.searchsorted(np.cumsum(e[order]), share * e.sum())])


def test_a_rough_ball_lens_spreads_its_focus_as_roughness_grows():
    """The ball lens's bright disc (0.13 m to its fold) spreads with
    roughness: the radius holding three quarters of its flux grows with
    Roughness 0.1, 0.2, 0.4 (0.1 blurs the fold by about a centimetre),
    and at 0.4 is more than twice the smooth glass's."""
    from scenes import ball_lens
    widths = []
    for roughness in (0.0, 0.1, 0.2, 0.4):
        scene = ball_lens(pixels=8)
        scene.objects[1].material.roughness = roughness
        result = render(scene, RenderSettings(lamp_rays=40_000, density="adaptive", spp=1))
        widths.append(flux_radius(result.maps["Floor"], 1.2))
    assert widths[0] < widths[2] and widths[1] < widths[2] < widths[3] and widths[3] > 2.0 * widths[0]


def test_rough_caster_is_named_in_one_warning_and_bad_roughness_is_an_error():
    scene = ceiling(0.5)
    warnings = render(scene, RenderSettings(lamp_rays=1000, spp=1)).warnings
    named = [w for w in warnings if "Mirror" in w]
    assert named == ["Mirror: rough (Roughness 0.5): in beam mode its caustic comes as photons, with their noise; "
                     "the view through it or in it takes one microfacet normal per eye sample (more Samples smooth "
                     "its grain)"]
    photons = render(scene, RenderSettings(lamp_rays=1000, spp=1, density="adaptive")).warnings
    assert [w for w in photons if "Mirror" in w] == ["Mirror: rough (Roughness 0.5): the view through it or in it "
                                                     "takes one microfacet normal per eye sample (more Samples "
                                                     "smooth its grain)"]
    for smooth in (0.0, 1e-6):
        assert not any("Mirror" in w for w in render(ceiling(smooth), RenderSettings(lamp_rays=1000, spp=1)).warnings)
    scene.objects[1].material.roughness = 1.5
    with pytest.raises(SceneError, match="Mirror: roughness must be between 0 and 1"):
        render(scene)


def test_rough_casters_are_named_together_in_one_warning():
    """A gem's five rough prongs make one warning, not five: it names every
    rough caster, in scene order, and the range of their Roughness."""
    scene = ceiling(0.4)
    scene.objects.append(Object("Mirror.001", shapes.plane(HALF, (0, 0, MIRROR_Z - 0.5)),
                                Reflector(1.0, roughness=0.2)))
    scene.objects.append(Object("Smooth", shapes.plane(HALF, (0, 0, MIRROR_Z - 1.0)), Reflector(1.0)))
    assert rough_caster_warnings(scene, "adaptive") == [
        "Mirror, Mirror.001: rough (Roughness 0.2-0.4): the view through them or in them takes one microfacet "
        "normal per eye sample (more Samples smooth their grain)"]
    assert rough_caster_warnings(scene, "beam") == [
        "Mirror, Mirror.001: rough (Roughness 0.2-0.4): in beam mode their caustics come as photons, with their "
        "noise; the view through them or in them takes one microfacet normal per eye sample (more Samples smooth "
        "their grain)"]


def test_beam_mode_sends_the_light_of_lamps_that_light_a_rough_caster_as_photons():
    """In beam mode a lamp that can light a rough caster sends photons, the
    photon pass's own: the same render as the adaptive density; with the
    mirror smooth it sends beams."""
    beams = render(ceiling(0.3), RenderSettings(lamp_rays=4000, spp=1))
    photons = render(ceiling(0.3), RenderSettings(lamp_rays=4000, spp=1, density="adaptive"))
    assert beams.stats["landed"] == photons.stats["landed"] > 2000 and beams.stats["lamp_rays_refined"] == 0
    assert np.allclose(beams.image, photons.image, rtol=1e-6, atol=1e-9)
    assert render(ceiling(0.0), RenderSettings(lamp_rays=4000, spp=1)).stats["lamp_rays_refined"] > 0


def two_balls(apart: float, rough: bool = True) -> Scene:
    """A smooth glass ball (radius 0.5 m) at x = -`apart` and, if `rough`, a
    rough one (Roughness 0.2) at x = `apart`, both 1 m over the floor, under
    a point lamp 4 m up."""
    objects = [Object("Floor", shapes.plane(20.0), Diffuse(albedo=1.0)),
               Object("Smooth", shapes.uv_sphere(0.5, (-apart, 0, 1.0), 64, 32), Dielectric(1.5))]
    if rough:
        objects.append(Object("Rough", shapes.uv_sphere(0.5, (apart, 0, 1.0), 64, 32),
                              Dielectric(1.5, roughness=0.2)))
    return Scene(objects, [PointLight((0, 0, 4.0), 1000.0)], top_camera(3.0, 16))


def test_beam_mode_keeps_beams_toward_smooth_casters_beside_a_rough_one():
    """A lamp over a smooth glass ball and a rough one 3 m apart sends
    photons toward the rough ball and beams toward the smooth one. The
    smooth ball's caustic is beams, as with no rough ball beside it (the
    floor's mean irradiance under it within 0.2% of that render's, whose
    grid has all the rays; as photons it is 3% off), and the rough ball's
    light lands as the photon pass's does (the flux landed within 2% of the
    adaptive density's)."""
    from caustic_addon.emission.aims import casters_and_bounds, smooth_and_rough
    from caustic_addon.passes.beam import photon_lamps
    scene = two_balls(1.5)
    assert photon_lamps(scene.lights, *smooth_and_rough(scene, casters_and_bounds(scene)[0])) == ([], scene.lights)
    rng = np.random.default_rng(1)
    r, phi = 0.7 * np.sqrt(rng.random(20_000)), 2.0 * math.pi * rng.random(20_000)
    under_smooth = np.stack([r * np.cos(phi) - 1.5, r * np.sin(phi)], axis=1)
    settings = RenderSettings(spp=1)
    both = render(two_balls(1.5), settings)
    alone = render(two_balls(1.5, rough=False), settings)
    photons = render(two_balls(1.5), replace(settings, density="adaptive"))
    assert both.stats["lamp_rays_refined"] > 0
    assert (both.maps["Floor"].irradiance_at(under_smooth).mean()
            == pytest.approx(alone.maps["Floor"].irradiance_at(under_smooth).mean(), rel=2e-3))
    assert both.stats["flux_landed_w"][0] == pytest.approx(photons.stats["flux_landed_w"][0], rel=0.02)


def test_beams_and_photons_share_a_lamps_overlapping_aims():
    """A smooth glass ball over a rough one beside it, whose cones from the
    lamp overlap: a ray that meets the smooth ball's bounding sphere is the
    beams', one that meets only the rough ball's the photons'. No light is
    counted twice: the flux landed is the photon pass's at 1,000,000 lamp
    rays within 1% (with the photons that meet the smooth ball's sphere
    kept, 8% more lands), and the smooth ball's light still makes beams."""
    from caustic_addon.emission.aims import aims, casters_and_bounds, overlapping, smooth_and_rough
    objects = [Object("Floor", shapes.plane(20.0), Diffuse(albedo=1.0)),
               Object("Smooth", shapes.uv_sphere(0.5, (0, 0, 1.6), 64, 32), Dielectric(1.5)),
               Object("Rough", shapes.uv_sphere(0.4, (0.8, 0, 0.5), 64, 32), Dielectric(1.5, roughness=0.2))]
    scene = Scene(objects, [PointLight((0, 0, 4.0), 1000.0)], top_camera(3.0, 16))
    targets, scene_sphere = casters_and_bounds(scene)
    cones = [aims(scene.lights[0], spheres, scene_sphere)[0] for spheres in smooth_and_rough(scene, targets)]
    assert list(overlapping(cones)[1]) == [0, 1]
    beams = render(scene, RenderSettings(spp=1))
    photons = render(scene, RenderSettings(spp=1, density="adaptive", lamp_rays=1_000_000))
    assert beams.stats["lamp_rays_refined"] > 0
    assert beams.stats["flux_landed_w"][0] == pytest.approx(photons.stats["flux_landed_w"][0], rel=0.01)


def test_beam_grid_paths_past_a_rough_surface_bound_no_beam(monkeypatch):
    """Grid paths that meet a rough surface after all (a lamp taken not to
    light it, as a spot whose light another caster turns toward it) bound
    no beam (their neighbours took other microfacets; no landing counts
    as a beam's): they land as photons, with the flux the photon pass
    brings, and refinement spends no rays on them."""
    from caustic_addon.passes import beam
    monkeypatch.setattr(beam, "smooth_and_rough", lambda scene, targets: (targets, []))
    result = render(ceiling(0.3), RenderSettings(lamp_rays=40_000, spp=1, beam_refinement=2))
    photons = render(ceiling(0.3), RenderSettings(lamp_rays=40_000, spp=1, density="adaptive"))
    assert result.stats["lamp_rays_refined"] == 0 and result.stats["landed"] == 0
    assert result.stats["flux_landed_w"][0] == pytest.approx(photons.stats["flux_landed_w"][0], rel=0.01)


def test_roughness_zero_is_the_smooth_interface_exactly():
    """Roughness 0, and any Roughness Cycles renders as perfectly specular
    (alpha^2 <= 2e-10), give the smooth glass's render bit for bit, as beams
    and as photons; the sampler at alpha 0 returns the macro normal."""
    from scenes import ball_lens
    assert np.array_equal(alpha_of([0.0, 1e-6, 0.0037]), [0.0, 0.0, 0.0]) and alpha_of(0.004) > 0.0
    for density in ("beam", "adaptive"):
        images = []
        for roughness in (None, 0.0, 1e-6):
            scene = ball_lens(pixels=24)
            if roughness is not None:
                scene.objects[1].material.roughness = roughness
            images.append(render(scene, RenderSettings(lamp_rays=5_000, density=density, spp=1)).image)
        assert np.array_equal(images[0], images[1]) and np.array_equal(images[0], images[2]), density
    uv = np.random.default_rng(7).random((1000, 2)) * 0.999
    h = sample_visible_normals_local(incoming(0.4, 1000), np.zeros(1000), uv)
    assert np.array_equal(h, np.tile([0.0, 0.0, 1.0], (1000, 1)))


def test_the_rough_path_tends_to_the_smooth_one():
    """A Roughness of 0.01 (alpha 1e-4) scatters each photon and eye ray
    about a normal within about 1e-4 of the shading normal, by the same
    Fresnel choices: nearly the smooth image, as photons."""
    from scenes import ball_lens
    images = []
    for roughness in (0.0, 0.01):
        scene = ball_lens(pixels=32)
        scene.objects[1].material.roughness = roughness
        images.append(render(scene, RenderSettings(lamp_rays=20_000, density="adaptive", spp=1)).image)
    assert np.linalg.norm(images[1] - images[0]) < 1e-2 * np.linalg.norm(images[0])


@pytest.mark.parametrize("alpha, mu, eta", [(0.16, 0.7, None), (0.25, 0.4, 1 / 1.5), (0.09, 0.8, 1.5)])
def test_bsdf_evaluation_integrates_to_what_the_sampler_keeps(alpha, mu, eta):
    """The evaluated interface (the lamps' highlights), f |cos| integrated
    over the light's sphere, reflected and transmitted apart, is what the
    visible-normal sampler keeps from the same view (sampled_parts):
    evaluation and sampling are one BSDF, Cycles' (no eta^2 factor)."""
    dirs, dw = sphere_grid(1200)
    view = incoming(mu, len(dirs))
    normal = np.tile([0.0, 0.0, 1.0], (len(dirs), 1))
    mirror = np.full(len(dirs), eta is None)
    f = bsdf_cosine(view, dirs, normal, np.full(len(dirs), alpha), np.full(len(dirs), eta or 1.0), mirror)
    up = dirs[:, 2] > 0
    reflected, transmitted = sampled_parts(alpha, mu, eta)
    assert np.sum((f * dw)[up]) == pytest.approx(reflected, abs=3e-3)
    assert np.sum((f * dw)[~up]) == pytest.approx(transmitted, abs=3e-3)


def test_a_lamps_highlight_on_a_rough_mirror_is_the_brdf_times_its_irradiance():
    """Seen from straight above, a rough metal floor (Roughness 0.4, colour
    0.8) under a point lamp shows the lamp's highlight: in each pixel, on
    average, the lamp's irradiance times f |cos| (bsdf_cosine), the colour
    and Multiscatter GGX's factor 1/E(1) for a view along the normal."""
    alpha, color, lamp = 0.16, 0.8, np.array([0.4, 0.0, 1.5])
    scene = Scene([Object("Metal", shapes.plane(4.0), Reflector(color, roughness=0.4))],
                  [PointLight(tuple(lamp), 1000.0)], top_camera(1.0, 16))
    seen = render(scene, RenderSettings(spp=16)).passes["direct"][..., 0].reshape(16, 16)
    ticks = (np.arange(64) + 0.5) / 64 * 2.0 - 1.0
    x, y = np.meshgrid(ticks, -ticks)
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    offset = lamp - points
    dist2 = np.sum(offset ** 2, axis=1)
    n = len(points)
    f = bsdf_cosine(np.tile([0.0, 0.0, 1.0], (n, 1)), offset / np.sqrt(dist2)[:, None], np.tile([0.0, 0.0, 1.0], (n, 1)),
                    np.full(n, alpha), np.ones(n), np.ones(n, dtype=bool))
    e1 = albedo_at(single_scatter_albedo(alpha, None)[None], np.array([1.0]))[0]
    expected = (1000.0 / (4.0 * math.pi) / dist2 * f * color / e1).reshape(16, 4, 16, 4).mean(axis=(1, 3))
    assert seen.max() > 5.0 * seen.min()
    assert np.sqrt(np.mean((seen - expected) ** 2)) < 0.01 * np.sqrt(np.mean(expected ** 2))


def test_roughness_and_distribution_key_the_kept_maps():
    """The maps kept between renders are redone when a caster's Roughness
    or its distribution changes."""
    from caustic_addon.maps.cache import lamp_pass_key
    settings = RenderSettings()
    keys = {lamp_pass_key(ceiling(r, m), settings) for r, m in ((0.3, True), (0.4, True), (0.3, False))}
    assert len(keys) == 3 and lamp_pass_key(ceiling(0.3), settings) in keys
