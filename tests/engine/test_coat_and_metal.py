"""A Principled receiver's metal and coat (optics/metal.py, optics/layers.py)
against closed forms: the F82-tint curve's defining points and mean, a
white metal in the white furnace, and the caustic and direct light seen
through a clear, then a tinted, coat from straight above."""

import math

import numpy as np
import pytest
from test_rough import furnace

from caustic_addon import Coat, Diffuse, PointLight, Specular, render
from caustic_addon.optics.metal import f82_b, f82_fresnel1, f82_fss
from caustic_addon.optics.principled import f0_from_ior
from scenes import LAMP_Z, POWER, floor_points, quick
from test_principled import principled_floor_scene


def f82(mu, f0, tint):
    """The F82-tint curve at cosines `mu (k,)`, through the kernels' scalar form."""
    b = f82_b(np.asarray(f0, dtype=np.float64), np.asarray(tint, dtype=np.float64))
    return np.array([f82_fresnel1(m, tuple(f0), tuple(b)) for m in mu])


def test_the_metal_s_fresnel_is_its_base_colour_head_on_white_at_grazing_and_tinted_at_82_degrees():
    """F(1) = F0, F(0) = 1, and at cos = 1/7 Schlick's value times the
    Specular Tint (Kutz et al. 2021); its hemispherical mean 2 int F mu dmu
    is f82_fss's closed form."""
    f0, tint = (0.9, 0.6, 0.2), (1.0, 0.8, 0.5)
    assert f82([1.0], f0, tint)[0] == pytest.approx(f0)
    assert f82([0.0], f0, tint)[0] == pytest.approx([1.0, 1.0, 1.0])
    schlick = np.array(f0) + (1.0 - np.array(f0)) * (6.0 / 7.0) ** 5
    assert f82([1.0 / 7.0], f0, tint)[0] == pytest.approx(schlick * np.array(tint))
    mu = (np.arange(20000) + 0.5) / 20000
    mean = 2.0 * np.mean(f82(mu, f0, tint) * mu[:, None], axis=0)
    b = f82_b(np.array(f0), np.array(tint))
    assert f82_fss(np.array(f0), b) == pytest.approx(mean, abs=1e-6)


@pytest.mark.parametrize("metallic", [1.0, 0.5])
@pytest.mark.parametrize("roughness", [0.3, 0.7])
def test_a_white_metal_in_the_white_furnace_gives_back_all_light(metallic, roughness):
    """A Principled ball of Base Color 1 and IOR 1 (no specular layer) in a
    white world: its metal reflects F = 1 at every angle, and with
    Multiscatter GGX's gain all of it; the rest is a white diffuse base. So
    every pixel's expected radiance is the world's, 1, whatever the share
    of metal."""
    seen, _ = furnace(Diffuse(1.0, specular=Specular(roughness=roughness, ior=1.0, metallic=metallic)))
    assert seen.mean() == pytest.approx(1.0, abs=4e-3)


COATS = {
    "clear": Coat(weight=1.0, roughness=0.0, ior=1.5),
    "half, tinted": Coat(weight=0.5, roughness=0.0, ior=1.8, tint=(0.9, 0.6, 0.3)),
}


@pytest.mark.parametrize("layering", ["4.2", "4.5", "5.3"])
@pytest.mark.parametrize("coat", COATS)
def test_the_caustic_and_the_lamp_s_light_show_through_a_coat_as_cycles_layers_it(coat, layering):
    """Seen from straight above, a smooth coat of weight c and IOR n
    reflects F0 = ((n - 1) / (n + 1))^2 and shows its Coat Tint t: Blender
    4.x leaves the base under it (1 - c F0)(1 - c + c t) of its light,
    5.3 1 - c + c t (1 - F0) (the coated part of the surface, tinted),
    in the caustic as in the lamp's direct light, whose mirror image in the
    coat Cycles does not evaluate. The lamp stands aside, so the caustic
    falls outside the ball's silhouette, where the eye looks straight down."""
    def scene(specular):
        built = principled_floor_scene(specular, glass=True)
        built.lights = [PointLight((5.0, 0.0, LAMP_Z), POWER)]
        return built

    settings = quick(lamp_rays=40_000, density="beam")
    layers = COATS[coat]
    plain, coated = (render(scene(specular), settings).passes
                     for specular in (None, Specular(ior=1.0, coat=layers, layering=layering)))
    c, f0, t = layers.weight, f0_from_ior(layers.ior), np.asarray(layers.tint)
    expected = 1.0 - c + c * t * (1.0 - f0) if layering == "5.3" else (1.0 - c * f0) * (1.0 - c + c * t)
    outside = np.linalg.norm(floor_points(scene(None)), axis=-1) > 1.05
    for name in ("caustic", "direct"):
        lit = plain[name][..., 1] > 1e-2 * plain[name][..., 1].max()
        # away from the shadow's and the caustic's edges, whose pixels the edge pass refines by what it sees there
        lit = outside & np.all([np.roll(lit, shift, axis) for shift in (-1, 0, 1) for axis in (0, 1)], axis=0)
        assert lit.sum() > 20, name
        assert coated[name][lit] == pytest.approx(plain[name][lit] * expected, rel=2e-4), name


def test_a_rough_coat_adds_its_ggx_highlight_over_what_it_leaves_of_the_base():
    """Straight down on a coated floor lit from straight above: at each
    pixel L = E cos_l (albedo / pi)(1 - c F0) + c E F(h.v) D(h) G2 / (4 cos_v),
    as Blender 4.2 layers it: the coat's lobe without multiple scattering,
    its Fresnel the real dielectric curve, what it leaves of the base that
    of a smooth coat, head on; D, Lambda and F written out here (Walter et
    al. 2007; Heitz 2014; Hecht)."""
    c, roughness, n = 0.7, 0.3, 1.5
    specular = Specular(ior=1.0, coat=Coat(weight=c, roughness=roughness, ior=n), layering="4.2")
    image = render(principled_floor_scene(specular), quick(lamp_rays=0, spp=1)).passes["direct"][..., 0]
    xy = floor_points(principled_floor_scene(specular)).reshape(-1, 2)
    to_lamp = np.concatenate([-xy, np.full((len(xy), 1), LAMP_Z)], axis=1)
    d2 = np.sum(to_lamp ** 2, axis=1)
    cos_l = to_lamp[:, 2] / np.sqrt(d2)
    irradiance = POWER / (4 * math.pi) / d2
    h = to_lamp / np.sqrt(d2)[:, None] + [0.0, 0.0, 1.0]
    cos_h = h[:, 2] / np.linalg.norm(h, axis=1)
    a2 = roughness ** 4
    d = a2 / (math.pi * (cos_h ** 2 * (a2 - 1.0) + 1.0) ** 2)
    lam_l = 0.5 * (np.sqrt(1.0 + a2 * (1.0 - cos_l ** 2) / cos_l ** 2) - 1.0)
    g = np.sqrt(n ** 2 - 1.0 + cos_h ** 2)
    fresnel = 0.5 * ((g - cos_h) / (g + cos_h)) ** 2 * (
        1.0 + ((cos_h * (g + cos_h) - 1.0) / (cos_h * (g - cos_h) + 1.0)) ** 2)
    expected = irradiance * (cos_l * 0.5 * (1.0 - c * f0_from_ior(n)) / math.pi
                             + c * fresnel * d / (4.0 * (1.0 + lam_l)))
    assert image.ravel() == pytest.approx(expected, rel=1e-5)       # the passes are float32


def test_an_emitting_base_glows_through_its_coat():
    """Cycles puts a Principled BSDF's emission under its coat: seen head
    on through a smooth clear coat of weight c, 1 - c F0 of it shows."""
    scene = principled_floor_scene(Specular(ior=1.0, coat=Coat(weight=0.8, roughness=0.0, ior=1.5)))
    scene.lights = []
    floor = scene.objects[0]
    floor.material = Diffuse(0.0, emission=2.0, receiver=False, specular=floor.material.specular)
    seen = render(scene, quick(lamp_rays=0, spp=1)).image[..., :3]
    assert seen == pytest.approx(np.full(seen.shape, 2.0 * (1.0 - 0.8 * f0_from_ior(1.5))), rel=1e-5)
