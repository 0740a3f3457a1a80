"""Emitting meshes are lamps (scene.MeshLight, emission/mesh_lights.py):
their faces light the scene from both sides, shadow rays sample them by
area, and their caustics come through glass as an area light's do."""

import math

import numpy as np
import pytest

from caustic_addon import (AreaLight, Camera, Dielectric, Diffuse, Object, Reflector, RenderSettings, Scene, SceneError,
                           render, shapes)
from caustic_addon.emission.mesh_lights import mesh_lights, pieces
from caustic_addon.scene import Mesh, MeshLight

HALF, HEIGHT, RADIANCE = 0.5, 1.0, 10.0


def softbox(flipped: bool = False) -> Object:
    """A 1 m emitting square 1 m up, of radiance 10 W/(m^2 sr), facing up
    (or down, `flipped`)."""
    square = shapes.plane(2.0 * HALF)
    triangles = square.triangles[:, ::-1] if flipped else square.triangles
    return Object("Softbox", Mesh(square.vertices + np.array([0.0, 0.0, HEIGHT]), triangles),
                  Diffuse(albedo=0.0, emission=np.full(3, RADIANCE)))


def equal_area_light() -> AreaLight:
    """The area light of the softbox's size and downward power, pi A L."""
    return AreaLight((0.0, 0.0, HEIGHT), (HALF, 0.0, 0.0), (0.0, HALF, 0.0), (0.0, 0.0, -1.0),
                     math.pi * (2.0 * HALF) ** 2, color=np.full(3, RADIANCE))


def corner_form_factor(a: float, b: float, h: float) -> float:
    """From a point to a parallel a x b rectangle h above it, over one of its
    corners (Howell's catalogue, C-11): E = pi L F."""
    x, y = a / h, b / h
    return (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
            + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))) / (2.0 * math.pi)


def floor_below(emitter: Object, floor_material=None) -> Scene:
    """A white floor, and an orthographic camera 1 cm across looking down at
    its centre from under the emitter."""
    camera = Camera.look_at((0.0, 0.0, 0.5), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixx=4, pixy=4, kind="ORTHO",
                            ortho_scale=0.01)
    floor = Object("Floor", shapes.plane(20.0), floor_material or Diffuse(albedo=1.0))
    return Scene(objects=[floor, emitter], lights=[], camera=camera)


@pytest.mark.parametrize("flipped", [False, True], ids=["facing up", "facing down"])
def test_an_emitting_square_lights_the_floor_below_as_the_closed_form(flipped):
    """Under the centre of an emitting square of side 2a at height h, E = pi
    L x 4 F(a, a, h); the white floor shows E / pi, whichever way the square
    faces, as Cycles' emission leaves both sides."""
    result = render(floor_below(softbox(flipped)), RenderSettings(spp=16, lamp_samples=16))
    expected = RADIANCE * 4.0 * corner_form_factor(HALF, HALF, HEIGHT)
    np.testing.assert_allclose(result.image[..., :3].mean(axis=(0, 1)), expected, rtol=0.005)
    assert not result.warnings


def test_a_glowing_ball_lights_the_floor_below_as_the_closed_form():
    """A ball of radius R and radiance L, its centre d above a point: E = pi L
    (R/d)^2. Half of its samples lie on its far side, in its own shadow, and
    those near its outline graze its faces: each shadow ray aims at its
    sample from its lifted origin (before, 2% of the light was lost)."""
    glow = Object("Glow", shapes.uv_sphere(0.3, (0.0, 0.0, 2.0), 96, 48),
                  Diffuse(albedo=0.0, emission=np.full(3, RADIANCE)))
    scene = floor_below(glow)
    scene.camera.pixx = scene.camera.pixy = 32
    result = render(scene, RenderSettings(spp=4, lamp_samples=16))
    assert result.image[..., :3].mean() == pytest.approx(RADIANCE * (0.3 / 2.0) ** 2, rel=0.003)


def test_a_rough_mirror_shows_an_emitter_once():
    """A rough metal floor under the softbox shows its highlight from the
    shadow rays alone, as under the equal area light: its reflected rays
    that meet the emitting faces add nothing more."""
    rough = Reflector(roughness=0.3)
    settings = RenderSettings(spp=64, lamp_samples=8, lamp_rays=0)
    emitter = render(floor_below(softbox(), rough), settings).image[..., :3].mean()
    lamp = floor_below(softbox(), rough)
    lamp.objects, lamp.lights = lamp.objects[:1], [equal_area_light()]
    assert emitter == pytest.approx(render(lamp, settings).image[..., :3].mean(), rel=0.03)


def ball_under(lights, with_softbox: bool) -> Scene:
    ball = Object("Ball", shapes.uv_sphere(0.3, (0.0, 0.0, 0.5), 48, 24), Dielectric(1.5))
    objects = [Object("Floor", shapes.plane(20.0), Diffuse(albedo=1.0)), ball]
    return Scene(objects=objects + ([softbox()] if with_softbox else []), lights=lights,
                 camera=Camera(np.eye(4), pixx=1, pixy=1))


def caustic(scene: Scene, settings: RenderSettings) -> tuple[float, np.ndarray]:
    """(the floor's caustic flux, W, and its irradiance over the middle 5 m square)."""
    imap = render(scene, settings).maps["Floor"]
    floor = imap.irradiance()[..., 0]
    n = floor.shape[0]
    return floor.sum() * imap.cell ** 2, floor[n // 2 - n // 8:n // 2 + n // 8, n // 2 - n // 8:n // 2 + n // 8]


@pytest.mark.parametrize("density, rays, same_flux, tolerance", [("beam", 40_000, 0.005, 0.06),
                                                                  ("adaptive", 200_000, 0.02, 0.15)])
def test_a_softbox_casts_the_caustic_of_the_area_light_of_its_size(density, rays, same_flux, tolerance):
    """A glass ball under the emitting square: the caustic the equal area
    light casts (traced with 4x the rays), the same flux, and within
    `tolerance` relative L2. Beams: the flux to 0.5%, both caustics near
    3.5% of the converged one. Photons: their k-nearest estimate keeps the
    flux to only about 3% (the area light's own moved 3% from 200,000 to
    800,000 photons)."""
    settings = RenderSettings(spp=1, lamp_rays=rays, density=density, eye_pass=False)
    flux, emitted = caustic(ball_under([], True), settings)
    reference_flux, reference = caustic(ball_under([equal_area_light()], False),
                                        RenderSettings(spp=1, lamp_rays=4 * rays, density=density, eye_pass=False))
    assert flux == pytest.approx(reference_flux, rel=same_flux)
    assert np.linalg.norm(emitted - reference) / np.linalg.norm(reference) < tolerance


def test_pieces_tile_large_faces_and_stand_for_small_ones_by_area():
    """A square of two faces is cut into equal triangles that cover it
    exactly; a sphere of many small faces is drawn by area, each piece
    standing for an equal share."""
    square = MeshLight(softbox().mesh.corners, np.ones(3))
    triangles, areas = pieces(square, 50)
    assert len(triangles) == 50 and areas.sum() == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(areas, 1.0 / 50, rtol=1e-9)
    assert np.abs(triangles[..., :2]).max() <= HALF + 1e-12
    ball = MeshLight(shapes.uv_sphere(0.5, (0.0, 0.0, 0.0), 32, 16).corners, np.ones(3))
    triangles, areas = pieces(ball, 60)
    assert len(triangles) == 60 and areas.sum() == pytest.approx(ball.areas.sum(), rel=1e-12)
    assert np.abs(np.linalg.norm(triangles.mean(axis=1), axis=1) - 0.5).max() < 0.05


def test_only_emitting_objects_are_mesh_lights():
    scene = floor_below(softbox())
    assert [light.name for light in mesh_lights(scene)] == ["Softbox"]
    np.testing.assert_allclose(mesh_lights(scene)[0].areas.sum(), 1.0)


def test_an_emitter_too_bright_for_the_image_is_refused_by_name_and_one_of_no_area_lights_nothing():
    bright = softbox()
    bright.material = Diffuse(albedo=0.0, emission=np.full(3, 1e300))
    with pytest.raises(SceneError, match="Softbox: its emission of 1e[+]300 W/[(]m.2 sr[)] is past"):
        render(floor_below(bright), RenderSettings(spp=1))
    square = shapes.plane(1.0)
    flat = Object("Flat", Mesh(square.vertices * np.array([1.0, 0.0, 1.0]) + [0.0, 0.0, 1.0], square.triangles),
                  Diffuse(albedo=0.0, emission=np.full(3, 5.0)))
    scene = ball_under([equal_area_light()], False)
    scene.objects.append(flat)
    assert mesh_lights(scene) == []
    assert render(scene, RenderSettings(spp=1, lamp_rays=4_000, eye_pass=False)).stats["flux_landed_w"][0] > 0


def test_a_closed_emitter_sends_the_pass_from_the_lamps_from_its_outer_side_only():
    """A glowing ball's inner side lights only its inside: its lamp rays go
    out from its outer side, twice as many as from both, for the same
    caustic light. An open emitter, or a closed one around another
    object, keeps both sides."""
    glow = Object("Glow", shapes.uv_sphere(0.2, (0.0, 0.0, 1.6), 24, 12),
                  Diffuse(albedo=0.0, emission=np.full(3, 40.0)))
    scene = ball_under([], False)
    scene.objects.append(glow)
    light = mesh_lights(scene)[0]
    assert light.sides == (True, False)
    settings = RenderSettings(spp=1, lamp_rays=40_000, eye_pass=False)
    outer = caustic(scene, settings)[0]
    glow.mesh = Mesh(glow.mesh.vertices, glow.mesh.triangles[:-1])  # one face short of closed
    assert mesh_lights(scene)[0].sides == (True, True)
    both = caustic(scene, settings)[0]
    assert outer == pytest.approx(both, rel=0.02)
    assert mesh_lights(floor_below(softbox()))[0].sides == (True, True)
    around = Object("Shade", shapes.uv_sphere(0.5, (0.0, 0.0, 0.5), 24, 12), Diffuse(albedo=0.0, emission=np.ones(3)))
    scene.objects.append(around)
    assert mesh_lights(scene)[-1].sides == (True, True)
