"""Objects' ray visibility and holdouts (scene.Visibility), and objects
that are parts of one body: against closed forms on the ball lens, and
against the same scene without the object."""

import dataclasses

import numpy as np

from caustic_addon import Diffuse, Object, PointLight, Scene, Visibility, render, shapes
from caustic_addon.tracing.accelerator import Accelerator

from scenes import ball_lens, floor_points, quick, shadow_radius, unobstructed_irradiance

PIXELS = 48
HALF = 2.0


def lens(**glass) -> Scene:
    """The ball lens (R = 1 at z = 1.5 over a white floor, lamp at z = 6),
    the glass with the Object fields `glass`."""
    scene = ball_lens(pixels=PIXELS, half_width=HALF, segments=48)
    scene.objects[1] = dataclasses.replace(scene.objects[1], **glass)
    return scene


def radii(scene: Scene) -> np.ndarray:
    """(pixy, pixx) distance from the axis of the floor point under each pixel."""
    return np.linalg.norm(floor_points(scene), axis=-1)


def halves(scene: Scene, body):
    """The scene with its glass cut into the triangles above and below its
    centre, two objects of body `body`."""
    glass = scene.objects[1]
    upper = glass.mesh.corners.mean(axis=1)[:, 2] > 1.5
    parts = [Object(f"Glass [{side}]", glass.mesh.subset(np.flatnonzero(rows)), glass.material, body=body)
             for side, rows in (("top", upper), ("bottom", ~upper))]
    return Scene([scene.objects[0], *parts], scene.lights, scene.camera)


def test_parts_of_one_body_are_one_closed_surface_and_render_as_the_whole():
    whole = lens()
    split = halves(whole, "Glass")
    accel = Accelerator(split.objects, split.extent(), threads=1)
    assert accel.closed.tolist() == [False, True, True] and accel.warnings == []
    assert accel.medium_at(np.array([[0.0, 0.0, 1.5]])).tolist()[0] in (1, 2)
    accel.close()
    apart = Accelerator(halves(whole, None).objects, whole.extent(), threads=1)
    assert sum("is not a closed mesh" in w for w in apart.warnings) == 2
    apart.close()
    settings = quick(lamp_rays=20_000, density="beam")
    ours, reference = render(split, settings), render(whole, settings)
    # One material on both halves: the same aims, paths and beams as the one mesh.
    for name in ("direct", "ambient", "caustic"):
        np.testing.assert_allclose(ours.passes[name], reference.passes[name], rtol=1e-5, atol=1e-6)
    split.lights = [PointLight((0.0, 0.0, 1.5), 100.0, name="Inner")]
    assert "light 'Inner' is inside 'Glass'" in " ".join(render(split, settings).warnings)


def test_a_glass_hidden_from_the_camera_keeps_its_shadow_and_its_caustic():
    settings = quick(lamp_rays=20_000, density="beam")
    seen, unseen = render(lens(), settings), render(lens(visibility=Visibility(camera=False)), settings)
    np.testing.assert_array_equal(unseen.maps["Floor"].irradiance(), seen.maps["Floor"].irradiance())
    r = radii(lens())
    # Seen straight down, the floor under the ball: unlit but by the caustic.
    assert unseen.passes["direct"][r < 0.9].max() == 0.0
    assert unseen.passes["caustic"][r < 0.2].max() > 10.0 * seen.passes["direct"][r > 1.5].max()
    assert np.abs(seen.passes["direct"][r < 0.9] - unseen.passes["direct"][r < 0.9]).max() > 0.0


def test_a_glass_hidden_from_shadow_rays_lets_the_lamp_light_its_shadow():
    settings = quick(lamp_rays=20_000, density="beam")
    scene = lens(visibility=Visibility(shadow=False))
    result = render(scene, settings)
    r = radii(scene)
    annulus = (r > 1.05) & (r < 0.95 * shadow_radius())
    expected = unobstructed_irradiance(floor_points(scene)) / np.pi
    np.testing.assert_allclose(result.passes["direct"][annulus][:, 0], expected[annulus], rtol=1e-3)
    assert render(lens(), settings).passes["direct"][annulus].max() == 0.0


def test_an_object_hidden_from_transmission_rays_is_not_seen_through_glass():
    coin = Object("Coin", shapes.plane(0.6, (0.0, 0.0, 0.01)), Diffuse(albedo=(0.9, 0.1, 0.1)),
                  Visibility(transmission=False))
    settings = quick(lamp_rays=5_000, density="beam", edge_samples=0)  # the same samples in every pixel
    without = lens()
    without.ambient = np.full(3, 0.5)
    hidden = dataclasses.replace(without, objects=[*without.objects, coin])
    shown = dataclasses.replace(hidden, objects=[*without.objects, dataclasses.replace(coin,
                                                                                         visibility=Visibility())])
    # The coin lies wholly under the ball: the camera sees it only through the glass.
    np.testing.assert_allclose(render(hidden, settings).passes["ambient"], render(without, settings).passes["ambient"],
                               rtol=1e-6, atol=1e-9)
    assert not np.allclose(render(shown, settings).passes["ambient"], render(without, settings).passes["ambient"])


def test_a_holdout_cuts_out_what_camera_rays_see_of_it_but_not_what_they_see_through_glass():
    scene = lens()
    scene.objects[0] = dataclasses.replace(scene.objects[0], visibility=Visibility(holdout=True))
    result = render(scene, quick(lamp_rays=5_000, density="beam", spp=4, edge_samples=0))
    alpha, rgb = result.image[..., 3], result.image[..., :3]
    r = radii(scene)
    assert np.all(alpha[r > 1.1] == 0.0) and np.all(rgb[r > 1.1] == 0.0)
    # Through the glass, refracted rays see the floor as usual.
    assert np.all(alpha[r < 0.9] == 1.0) and rgb[r < 0.3].min() > 0.0
    assert np.all(np.isin(alpha[(r > 0.9) & (r < 1.1)], np.arange(5) / 4.0))


def test_a_holdout_glass_cuts_out_the_pixels_that_see_it():
    """Camera rays that meet a specular holdout stop there (bounce.Interface.select
    dropped the microfacet fields, a TypeError)."""
    scene = lens(visibility=Visibility(holdout=True))
    alpha = render(scene, quick(lamp_rays=2_000, density="beam", spp=1, edge_samples=0)).image[..., 3]
    r = radii(scene)
    assert np.all(alpha[r < 0.9] == 0.0) and np.all(alpha[r > 1.1] == 1.0)
