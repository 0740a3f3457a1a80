"""A sized lamp's highlight on a rough surface, taken by the lamp's samples
and by the surface's own rays weighed by the power heuristic
(passes/direct_light.py): a Principled receiver's specular layer, whose
rays the eye pass draws for it, and a rough metal caster, whose rays are
its bounce's branches. Against the integral over the lamp's surface: the
two strategies' weights must sum to one in every direction, for a narrow
lobe and a wide one, whichever density the lamp samples by."""

import math

import numpy as np
import pytest

from caustic_addon import (AreaLight, Diffuse, Object, PointLight, Reflector, RenderSettings, Scene, Specular,
                           render, shapes)
from caustic_addon.optics.microfacet import alpha_of, bsdf_cosine
from caustic_addon.optics.principled import Layer, Lobe
from scenes import floor_points, top_camera

HEIGHT = 1.0
POWER = 100.0
UP = np.array([0.0, 0.0, 1.0])


def glossy_floor(lamp, roughness: float, pixels: int = 12) -> Scene:
    """A black floor with a specular layer of `roughness` (IOR 1.5), seen straight down."""
    return Scene([Object("Floor", shapes.plane(20.0), Diffuse(0.0, specular=Specular(roughness=roughness, ior=1.5)))],
                 [lamp], top_camera(1.0, pixels))


def layer_brdf(roughness: float, m: int):
    """f cos of a Principled layer of `roughness` (IOR 1.5) toward a view
    straight up, for m light directions (optics.principled, tested against
    its closed form)."""
    layer = Layer.of(roughness, 1.5, 0.5, np.ones(3), True)
    gain, _ = layer.toward(np.array([1.0]))
    lobe = Lobe(np.ones(m, dtype=bool), np.tile(layer.f0, (m, 1)), np.full(m, layer.eta), np.full(m, layer.alpha),
                np.tile(gain, (m, 1)))
    up = np.tile(UP, (m, 1))
    return lambda l: lobe.weight(up, up, l)[:, 0]


def metal_brdf(roughness: float, color: float, m: int):
    """f cos of plain GGX metal of `roughness` and `color` toward a view
    straight up, for m light directions (optics.microfacet.bsdf_cosine,
    tested against Walter et al.'s integrals)."""
    up = np.tile(UP, (m, 1))
    return lambda l: color * bsdf_cosine(up, l, up, np.full(m, alpha_of(roughness)), np.ones(m), np.ones(m, dtype=bool))


def highlight(xy: np.ndarray, brdf, lamp_points: np.ndarray, lamp_normals: np.ndarray, cell_areas: np.ndarray,
              radiance: float) -> np.ndarray:
    """(n,) radiance straight up at floor points `xy (n,2)`: the sum over
    the lamp's cells (m,) of L f cos_l cos_lamp dA / d^2, `brdf` giving
    f cos_l of the m directions toward the cells."""
    out = np.empty(len(xy))
    for i, (x, y) in enumerate(xy):
        offset = lamp_points - np.array([x, y, 0.0])
        d2 = np.sum(offset ** 2, axis=1)
        l = offset / np.sqrt(d2)[:, None]
        cos_lamp = np.maximum(-np.sum(l * lamp_normals, axis=1), 0.0)
        out[i] = radiance * np.sum(brdf(l) * cos_lamp / d2 * cell_areas)
    return out


def assert_near(scene: Scene, expected: np.ndarray) -> None:
    """The render's direct light at the pixels' centres (no edge samples,
    which would average a pixel across the highlight's edge), 256 lamp
    samples and lobe rays each, against `expected`: its sum within 1%, each
    pixel within the estimate's noise. Without the lobe's rays a narrow
    lobe's highlight is off by up to 25% a pixel at these samples."""
    settings = RenderSettings(lamp_rays=0, spp=1, lamp_samples=256, edge_samples=0)
    image = render(scene, settings).passes["direct"][..., 0].ravel()
    assert image.sum() == pytest.approx(expected.sum(), rel=0.01)
    assert np.sqrt(np.mean((image - expected) ** 2)) < 0.04 * expected.max()


def square_lamp(half: float = 0.5, cells: int = 300):
    """(the lamp, its cells' centres (m,3), normals (m,3), areas (m,), its radiance)."""
    lamp = AreaLight((0.3, 0.0, HEIGHT), (half, 0, 0), (0, half, 0), (0, 0, -1), POWER)
    grid = ((np.arange(cells) + 0.5) / cells * 2.0 - 1.0) * half
    gx, gy = (a.ravel() for a in np.meshgrid(grid, grid))
    points = np.stack([gx + 0.3, gy, np.full(gx.shape, HEIGHT)], axis=1)
    return (lamp, points, np.tile(-UP, (len(points), 1)), np.full(len(points), (2 * half / cells) ** 2),
            POWER / (math.pi * (2 * half) ** 2))


@pytest.mark.parametrize("roughness", [0.1, 0.25, 0.6])
def test_a_square_lamps_highlight_is_its_integral_over_the_lamp(roughness):
    lamp, *cells = square_lamp()
    scene = glossy_floor(lamp, roughness)
    assert_near(scene, highlight(floor_points(scene).reshape(-1, 2), layer_brdf(roughness, len(cells[0])), *cells))


@pytest.mark.parametrize("roughness", [0.2, 0.35, 0.6])
def test_a_square_lamps_highlight_on_rough_metal_is_its_integral_over_the_lamp(roughness):
    """A rough caster's highlight: the lamp's samples at its surface, and
    the bounce's reflected branch, which meets the lamp."""
    lamp, *cells = square_lamp()
    scene = Scene([Object("Metal", shapes.plane(20.0), Reflector(0.8, roughness=roughness, multiscatter=False))],
                  [lamp], top_camera(1.0, 12))
    assert_near(scene, highlight(floor_points(scene).reshape(-1, 2), metal_brdf(roughness, 0.8, len(cells[0])),
                                 *cells))


@pytest.mark.parametrize("roughness", [0.1, 0.4])
def test_a_sphere_lamps_highlight_is_its_integral_over_the_sphere(roughness):
    """A sphere light's samples draw the cap it shows uniformly by solid
    angle; the lobe's rays meet it by the lobe's density."""
    radius, center = 0.3, np.array([0.2, 0.1, HEIGHT])
    scene = glossy_floor(PointLight(center, POWER, radius=radius, soft_falloff=False), roughness)
    rings, sectors = 300, 600
    theta, phi = np.meshgrid((np.arange(rings) + 0.5) / rings * math.pi,
                             (np.arange(sectors) + 0.5) / sectors * 2 * math.pi)
    normals = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1).reshape(-1, 3)
    areas = (np.sin(theta) * (math.pi / rings) * (2 * math.pi / sectors)).ravel() * radius ** 2
    # the far side of the sphere faces away from each floor point: cos_lamp clamps it to 0
    expected = highlight(floor_points(scene).reshape(-1, 2), layer_brdf(roughness, len(areas)),
                         center + radius * normals, normals, areas, POWER / (4 * math.pi ** 2 * radius ** 2))
    assert_near(scene, expected)
