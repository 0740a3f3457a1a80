"""Glass and water that touch or nest (passes/bounce.crossing1,
tracing/joins.py): light crosses from one into the other through a single
interface of the ratio of their indices, however the artist modelled it,
and a ball or slab of glass inside water leaves the light back in the water.

The closed form is that of a stack of flat layers under a vertical or an
oblique sun: each interface reflects its exact Fresnel share, each layer
absorbs by Beer-Lambert, and every round trip between interfaces counts
(incoherent: intensities add)."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, render, shapes
from caustic_addon.optics.specular import fresnel_dielectric

GLASS, WATER, SUN, ALBEDO = 1.5, 1.33, 1000.0, 0.5


def stack_transmittance(indices: list[float], absorbed: list[float], sin_air: float) -> float:
    """What crosses flat layers of `indices` (air first and last) whose
    layers between absorb `absorbed` of a pass straight through (a pass at
    cos c keeps (1 - a)^(1/c)), for light at sin(angle) `sin_air` in the
    air. Each interface in turn joins the stack above it: T' = T t T_i /
    (1 - R t^2 R_i) and, seen from below, R' = R_i + T_i^2 t^2 R / (1 - R
    t^2 R_i), with t what the layer between keeps and R the stack's
    reflectance from below."""
    cosines = [math.sqrt(1 - (sin_air / n) ** 2) for n in indices]
    reflected = [float(fresnel_dielectric(np.array([c]), n / m)[0]) for c, n, m in zip(cosines, indices, indices[1:])]
    through, below = 1 - reflected[0], reflected[0]
    for r, loss, c in zip(reflected[1:], absorbed, cosines[1:]):
        kept = (1 - loss) ** (1 / c)
        loop = 1 - below * kept ** 2 * r
        through, below = through * kept * (1 - r) / loop, r + (1 - r) ** 2 * kept ** 2 * below / loop
    return through


def scene_of(objects: list[Object], sun_angle: float) -> Scene:
    """`objects` over a floor at z = 0 under a sun `sun_angle` degrees from
    the vertical, seen straight down by an orthographic camera."""
    camera = np.eye(4)
    camera[2, 3] = 20.0
    a = math.radians(sun_angle)
    return Scene(objects=[Object("Floor", shapes.plane(12.0), Diffuse(albedo=ALBEDO))] + objects,
                 lights=[SunLight((math.sin(a), 0.0, -math.cos(a)), SUN)],
                 camera=Camera(camera, pixx=8, pixy=8, kind="ORTHO", ortho_scale=1.0))


def assert_lit_by(result, sun_angle: float, through_sun: float, through_eye: float) -> None:
    """The floor's map holds S cos(angle) T_sun in its middle metre (of
    12), and the camera sees it through the stack again: rho E / pi T_eye."""
    irradiance = SUN * math.cos(math.radians(sun_angle)) * through_sun
    floor = result.maps["Floor"].irradiance()
    h, w = floor.shape[:2]
    middle = floor[h // 2 - h // 24:h // 2 + h // 24, w // 2 - w // 24:w // 2 + w // 24]
    assert middle.mean() == pytest.approx(irradiance, rel=3e-3)
    image = result.image[..., :3]
    assert image.mean() == pytest.approx(ALBEDO * irradiance / math.pi * through_eye, rel=5e-3)


# where the water's top lies against the glass's bottom (z = 0.5), in metres
TOPS = {"coincident": 0.5, "0.5 mm below": 0.4995, "1 mm into the glass": 0.501}


@pytest.mark.parametrize("sun_angle", [0.0, 50.0])
@pytest.mark.parametrize("top", list(TOPS), ids=list(TOPS))
def test_glass_on_water_crosses_one_interface_of_the_ratio_of_their_indices(top, sun_angle):
    """A glass slab, 10 cm thick, on 30 cm of water that absorbs 20% a
    pass, over a floor in the air: the light crosses air, glass, water,
    air, three interfaces, whether the water's top coincides with the
    glass's bottom, lies half a millimetre below it, or 1 mm into it. With
    a fourth, an air film between, 7% less light reached the floor at
    normal incidence, and the water's overlap inside the glass read as glass
    entered from the air."""
    water_top = TOPS[top]
    objects = [Object("Glass", shapes.cylinder(2.0, 0.1, (0, 0, 0.5)), Dielectric(GLASS)),
               Object("Water", shapes.cylinder(2.0, water_top - 0.2, (0, 0, 0.2)),
                      Dielectric(WATER, absorption=-math.log(0.8) / (water_top - 0.2)))]
    result = render(scene_of(objects, sun_angle), RenderSettings())
    sin_air = math.sin(math.radians(sun_angle))
    assert_lit_by(result, sun_angle, stack_transmittance([1.0, GLASS, WATER, 1.0], [0.0, 0.2], sin_air),
                  stack_transmittance([1.0, GLASS, WATER, 1.0], [0.0, 0.2], 0.0))


def test_glass_apart_from_water_crosses_the_air_between():
    """10 cm of air between the two is an air gap: four interfaces."""
    objects = [Object("Glass", shapes.cylinder(2.0, 0.1, (0, 0, 0.6)), Dielectric(GLASS)),
               Object("Water", shapes.cylinder(2.0, 0.3, (0, 0, 0.2)), Dielectric(WATER))]
    through = stack_transmittance([1.0, GLASS, 1.0, WATER, 1.0], [0.0, 0.0, 0.0], 0.0)
    assert_lit_by(render(scene_of(objects, 0.0), RenderSettings()), 0.0, through, through)


@pytest.mark.parametrize("sun_angle", [0.0, 50.0])
def test_glass_inside_water_leaves_the_light_back_in_the_water(sun_angle):
    """A glass slab 10 cm thick inside 50 cm of water that absorbs 10% per
    10 cm: air, water, glass, water, air, the water's absorption over its
    40 cm. Before, the light left the glass into the air, and then the
    water's bottom as a face already crossed: neither its absorption below
    the glass nor its interface counted."""
    water = Dielectric(WATER, absorption=-math.log(0.9) / 0.1)
    objects = [Object("Water", shapes.cylinder(3.0, 0.5, (0, 0, 0.2)), water),
               Object("Glass", shapes.cylinder(2.0, 0.1, (0, 0, 0.4)), Dielectric(GLASS))]
    result = render(scene_of(objects, sun_angle), RenderSettings())
    layers = [1 - 0.9 ** 1.0, 0.0, 1 - 0.9 ** 3.0]  # 10 cm of water above the glass, 30 cm below
    indices = [1.0, WATER, GLASS, WATER, 1.0]
    assert_lit_by(result, sun_angle, stack_transmittance(indices, layers, math.sin(math.radians(sun_angle))),
                  stack_transmittance(indices, layers, 0.0))
