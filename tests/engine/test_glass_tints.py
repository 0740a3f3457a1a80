"""Glass tints as Cycles applies them (svm/closure.h): a Glass BSDF's Color
at every reflection and refraction, a Principled BSDF's square root of Base
Color at each refraction and white reflections, a Refraction BSDF's Color
at each refraction and no reflection at all."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, render, shapes

IOR, SUN, ALBEDO = 1.5, 1000.0, 0.5
F0 = ((IOR - 1) / (IOR + 1)) ** 2
BASE = np.array([0.2, 0.75, 0.3])


def floor_under_pane(glass: Dielectric) -> Scene:
    """A pane 5 cm thick, 0.3 m over a floor, under a vertical sun, seen
    straight down through the pane by an orthographic camera."""
    camera = np.eye(4)
    camera[2, 3] = 20.0
    return Scene(objects=[Object("Floor", shapes.plane(8.0), Diffuse(albedo=ALBEDO)),
                          Object("Pane", shapes.cylinder(2.0, 0.05, (0, 0, 0.3)), glass)],
                 lights=[SunLight((0, 0, -1), SUN)],
                 camera=Camera(camera, pixx=8, pixy=8, kind="ORTHO", ortho_scale=1.0))


def pane_transmittance(reflection: np.ndarray, transmission: np.ndarray, fresnel: float) -> np.ndarray:
    """(3,) what crosses a pane at normal incidence, every round trip inside
    it counted: (1 - F)^2 t^2 / (1 - F^2 r^2) for tints r at reflections
    and t at refractions."""
    return (1 - fresnel) ** 2 * transmission ** 2 / (1 - fresnel ** 2 * reflection ** 2)


@pytest.mark.parametrize("kind, glass, crossing", [
    ("Principled BSDF", Dielectric(IOR, reflection_tint=1.0, transmission_tint=np.sqrt(BASE)),
     pane_transmittance(np.ones(3), np.sqrt(BASE), F0)),
    ("Glass BSDF", Dielectric(IOR, reflection_tint=BASE, transmission_tint=BASE), pane_transmittance(BASE, BASE, F0)),
    ("Refraction BSDF", Dielectric(IOR, reflection_tint=0.0, transmission_tint=BASE, fresnel=False),
     pane_transmittance(np.zeros(3), BASE, 0.0)),
])
def test_a_tinted_pane_passes_the_light_cycles_gives_it(kind, glass, crossing):
    """The sun crosses the pane to the floor and the eye crosses it back:
    the floor shows the pane's transmittance twice, against a clear pane's
    on the same paths (the clear pane's own light is held to its closed form
    in test_radiance_through_interfaces.py). A Principled pane's green, Base
    Color 0.75, passes 0.75 of the light and shows 0.75^2, where a tint at
    every event passed 0.75^2 and showed 0.75^4."""
    clear = render(floor_under_pane(Dielectric(IOR)), RenderSettings()).image[..., :3]
    tinted = render(floor_under_pane(glass), RenderSettings()).image[..., :3]
    exact = (crossing / pane_transmittance(np.ones(3), np.ones(3), F0)) ** 2
    np.testing.assert_allclose(tinted.mean(axis=(0, 1)) / clear.mean(axis=(0, 1)), exact, rtol=2e-3)
    assert clear.mean() == pytest.approx(ALBEDO * SUN / math.pi * pane_transmittance(1.0, 1.0, F0) ** 2, rel=0.01)
