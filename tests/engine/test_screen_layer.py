"""The screen layer: a flat receiver's beams as the camera sees them, each
pixel their exact mean over it, at folds and cusps too."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, RenderSettings, render
from caustic_addon.maps.beam_map import BeamMap
from caustic_addon.maps.cache import MapCache
from caustic_addon.maps.charts import PlaneChart
from caustic_addon.maps.illumination_map import MapEstimate
from caustic_addon.maps.raster import signed_areas
from caustic_addon.maps.screen_layer import ScreenLayer
from caustic_addon.passes.camera_rays import eye_rays, image_view

FLOOR = np.array([[-20.0, -20.0, 0.0], [20.0, -20.0, 0.0], [20.0, 20.0, 0.0], [-20.0, 20.0, 0.0]])


def floor_layer(camera: Camera) -> tuple[PlaneChart, ScreenLayer]:
    chart = PlaneChart(np.zeros(3), np.array([0.0, 0.0, 1.0]), FLOOR)
    receiver = chart.plane_coords(FLOOR[[0, 1, 2, 0, 2, 3]]).reshape(2, 3, 2)
    return chart, ScreenLayer(image_view(camera), chart, receiver)


def on_floor(camera: Camera, chart: PlaneChart, pixels: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(n,2) chart metres where the eye rays through `pixels` at `offsets` meet the floor z = 0."""
    origins, dirs = eye_rays(camera, pixels, offsets)
    return chart.plane_coords(origins - (origins[:, 2] / dirs[:, 2])[:, None] * dirs)


CAMERAS = {
    "perspective, shifted, vertical fit": Camera.look_at((1.0, -4.0, 3.0), (0.3, 0.5, 0.0), pixx=40, pixy=30,
                                                         fov=math.radians(50.0), shift_x=0.1, shift_y=-0.07,
                                                         sensor_fit="VERTICAL"),
    "orthographic": Camera.look_at((0.5, -3.0, 4.0), (0.0, 0.0, 0.0), pixx=36, pixy=36, kind="ORTHO",
                                   ortho_scale=3.0),
}


@pytest.mark.parametrize("name", CAMERAS)
def test_a_beam_over_a_pixels_footprint_lights_that_pixel_alone(name):
    """The image of a beam whose corners are where a pixel's corner rays
    meet the floor is that pixel's square: it alone shows the beam's
    irradiance, exactly (the projection is camera_rays.eye_rays' inverse)."""
    camera = CAMERAS[name]
    chart, layer = floor_layer(camera)
    pixel = np.full(4, 13 * camera.pixx + 17)
    quad = on_floor(camera, chart, pixel, np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    layer.add(quad[[0, 1, 2, 0, 2, 3]].reshape(2, 3, 2), np.full((2, 3), 5.0))
    seen = layer.at(np.arange(camera.pixx * camera.pixy))[:, 0]
    assert seen[pixel[0]] == pytest.approx(5.0, rel=1e-9)
    assert np.abs(np.delete(seen, pixel[0])).max() < 1e-9


@pytest.mark.parametrize("name", CAMERAS)
def test_light_even_over_the_receiver_shows_even_in_its_edge_pixels(name):
    """Beams of even irradiance over all of a 1 m square receiver: every
    pixel that sees any of it shows that irradiance, those its edges cut
    too, since a pixel is the mean over the part of it that sees the receiver."""
    camera = CAMERAS[name]
    square = FLOOR / 20.0
    chart = PlaneChart(np.zeros(3), np.array([0.0, 0.0, 1.0]), square)
    receiver = chart.plane_coords(square[[0, 1, 2, 0, 2, 3]]).reshape(2, 3, 2)
    layer = ScreenLayer(image_view(camera), chart, receiver)
    layer.add(receiver, np.full((2, 3), 3.0))
    seen = layer.at(np.arange(camera.pixx * camera.pixy))[:, 0]
    lit = seen > 0
    np.testing.assert_allclose(seen[lit], 3.0, rtol=1e-9)
    pixels = np.arange(camera.pixx * camera.pixy)
    centres = on_floor(camera, chart, pixels, np.full((len(pixels), 2), 0.5))
    assert lit.sum() > (np.abs(centres) <= 1.0).all(axis=1).sum() + 10


def test_a_beam_reaching_behind_the_camera_shows_only_where_it_is_seen():
    """A camera 1 m above the floor looking level: a beam from 10 m behind
    it to 10 m ahead is cut at the clip plane, not mirrored through the eye.
    Each pixel shows the share of it the beam covers, as counting 16 x 16
    eye rays a pixel says."""
    camera = Camera.look_at((0.0, 0.0, 1.0), (0.0, 5.0, 1.0), pixx=32, pixy=24, fov=math.radians(70.0),
                            clip_start=0.1)
    chart, layer = floor_layer(camera)
    beam = chart.plane_coords(np.array([[-3.0, -10.0, 0.0], [3.0, -10.0, 0.0], [0.5, 10.0, 0.0]]))
    layer.add(beam[None], np.ones((1, 3)))
    below = np.arange(camera.pixx * camera.pixy)[camera.pixx * (camera.pixy // 2 + 1):]
    ticks = (np.arange(16) + 0.5) / 16
    offsets = np.stack(np.meshgrid(ticks, ticks), -1).reshape(-1, 2)
    xy = on_floor(camera, chart, np.repeat(below, 256), np.tile(offsets, (len(below), 1)))
    a, b, c = beam
    inside = np.ones(len(xy), dtype=bool)
    for p, q in ((a, b), (b, c), (c, a)):
        inside &= (q[0] - p[0]) * (xy[:, 1] - p[1]) - (q[1] - p[1]) * (xy[:, 0] - p[0]) >= 0
    counted = inside.reshape(len(below), 256).mean(axis=1)
    seen = layer.at(below)[:, 0]
    assert seen.sum() == pytest.approx(counted.sum(), rel=0.01)
    assert np.abs(seen - counted).max() < 0.1


def test_a_fold_is_exact_in_every_pixel():
    """Light folded over at a line: the beams of a source grid mapped by
    X = s u^2, Y = v (u in [-1, 1]) pile up at X = 0 with irradiance
    rho / sqrt(s X), a 1/sqrt singularity. A pixel over [x0, x1] x [y0, y1]
    (x0 >= 0) receives rho (y1 - y0) 2 (sqrt(x1 / s) - sqrt(x0 / s)):
    each pixel's mean is that over its area, whatever the map's cells."""
    matrix = np.eye(4)
    matrix[:3, 3] = (0.3, 0.0, 5.0)
    camera = Camera(matrix, pixx=24, pixy=8, kind="ORTHO", ortho_scale=0.96)
    chart, layer = floor_layer(camera)
    imap = BeamMap("Floor", chart, 0.05, MapEstimate(16), screen=layer)
    s, rho = 0.6, 2.0
    u, v = np.linspace(-1.0, 1.0, 2001), np.linspace(-0.2, 0.2, 41)
    grid = np.stack(np.meshgrid(s * u ** 2, v), -1)
    quads = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]], axis=2)
    corners = chart.plane_coords(np.c_[quads.reshape(-1, 2), np.zeros(len(quads.reshape(-1, 2)))])
    triangles = corners.reshape(-1, 4, 2)[:, [0, 1, 2, 0, 2, 3]].reshape(-1, 3, 2)
    area = np.abs(signed_areas(triangles))
    source_area = 0.5 * (u[1] - u[0]) * (v[1] - v[0])
    imap.add_beams(triangles, np.repeat((rho * source_area / area)[:, None], 3, axis=1))
    imap.prepare()
    pixels = np.arange(camera.pixx * camera.pixy)
    seen = imap.seen_mean(pixels, np.zeros((len(pixels), 2)), np.zeros((len(pixels), 2)))[:, 0]
    step = camera.ortho_scale / camera.pixx
    x0 = 0.3 - 0.5 * camera.ortho_scale + step * (pixels % camera.pixx)
    y1 = 0.5 * step * camera.pixy - step * (pixels // camera.pixx)
    lo, hi = np.clip(x0, 0.0, s), np.clip(x0 + step, 0.0, s)
    band = np.clip(y1, -0.2, 0.2) - np.clip(y1 - step, -0.2, 0.2)
    exact = rho * band * 2.0 * (np.sqrt(hi / s) - np.sqrt(lo / s)) / step ** 2
    assert exact.max() > 3.0 * np.median(exact[exact > 0])
    np.testing.assert_allclose(seen, exact, rtol=1e-4, atol=1e-9 * exact.max())


def test_the_ball_lens_at_one_sample_shows_the_exact_pixel_means():
    """Issue 18, item 3: the ball lens's caustic (a focus on the axis and a
    fold ring) against its exact value box-filtered over each pixel, at 1
    sample a pixel. Read from the map's cells it was 0.77% off at 100,000
    lamp rays (0.57% at 4 samples), the cells' light put in the wrong
    pixels where the irradiance rises steeply; the screen layer gives
    0.48% (what is left is the 256-segment sphere and the beams' grid)."""
    from benchmarks.scenes import ball_lens

    scene = ball_lens.scene()
    truth = ball_lens.pixel_reference(scene)
    caustic = render(scene, RenderSettings(lamp_rays=100_000, spp=1)).passes["caustic"][..., 0]
    exact = truth.irradiance / math.pi
    error = np.sqrt(np.sum((caustic - exact)[truth.region] ** 2) / np.sum(exact[truth.region] ** 2))
    assert error < 0.006


def test_a_moved_camera_gets_its_own_screen_layer_from_the_kept_beams(monkeypatch):
    """The maps of a render are kept (MapCache): when only the camera moves,
    the kept beams make the new view's screen layer, with no lamp pass, and
    the image is the one a fresh render gives. Past KEPT_BEAMS the beams are
    not kept, and the lamps are traced again."""
    from benchmarks.scenes import ball_lens

    cache = MapCache()
    scene = ball_lens.scene(64, 48)
    render(scene, RenderSettings(lamp_rays=20_000), cache=cache)
    scene.camera.matrix[0, 3] += 0.2
    moved = render(scene, RenderSettings(lamp_rays=20_000), cache=cache)
    assert moved.stats["maps_cached"] and moved.stats["rays_lamp_pass"] == 0
    fresh = render(scene, RenderSettings(lamp_rays=20_000))
    np.testing.assert_allclose(moved.passes["caustic"], fresh.passes["caustic"], rtol=1e-5, atol=1e-7)
    assert np.abs(fresh.passes["caustic"]).max() > 0.1

    small = MapCache()
    monkeypatch.setattr(BeamMap, "KEPT_BEAMS", 1000)
    render(scene, RenderSettings(lamp_rays=20_000), cache=small)
    scene.camera.matrix[0, 3] -= 0.2
    again = render(scene, RenderSettings(lamp_rays=20_000), cache=small)
    assert not again.stats["maps_cached"] and again.stats["rays_lamp_pass"] > 0
