"""The eye pass does less work where it changes nothing on average: faint
branches through glass play Russian roulette, a pixel's stratified, and a
small lamp's shadow rays stop at two a pixel where they agree."""

import math

import numpy as np
import pytest

from caustic_addon import Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, World, render, shapes
from caustic_addon.passes.bounce import Roulette, orient, split
from caustic_addon.passes.eye import ROULETTE_WEIGHT
from caustic_addon.passes.paths import Paths, relative_floor
from caustic_addon.sampling.hash import stream_key
from caustic_addon.scene.material_table import Materials
from caustic_addon.tracing.accelerator import REFLECTED, Accelerator
from caustic_addon.tracing.hits import MISS
from scenes import floor_points, top_camera


def test_a_clear_glass_ball_in_a_white_world_is_as_bright_as_the_world_with_roulette():
    """A smooth glass sphere in a uniform white world (the white furnace):
    what it reflects and lets through, over every bounce, sums to the
    world's radiance 1; Russian roulette keeps that mean while it stops
    most of the faint internal reflections."""
    pixels, spp = 48, 16
    scene = Scene([Object("Ball", shapes.uv_sphere(1.0, (0, 0, 0), 256, 128), Dielectric(1.5))], [],
                  top_camera(1.0, pixels, 10.0), world=World(color=1.0))
    result = render(scene, RenderSettings(spp=spp, edge_samples=0, max_depth=32))
    centre = (np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0
    x, y = np.meshgrid(centre, centre)
    seen = result.image[..., 0][x * x + y * y < 0.9 ** 2]
    assert seen.mean() == pytest.approx(1.0, abs=3e-3)
    # the whole tree down to 1e-4 of the camera ray's weight takes 8.4 rays an eye sample
    assert result.stats["rays_eye_pass"] / (pixels * pixels * spp) < 6.0


def test_a_small_suns_shadow_takes_one_ray_a_point_where_a_pixels_agree():
    """A sun 0.5 degrees wide over an opaque half-plane 1 m up, seen in 3 mm
    pixels: the open floor gets the sun's whole irradiance and the shadow
    none, with one shadow ray a point of the 16 (16 a pixel); across the 8.7 mm
    penumbra, where a pixel's probes disagree, each pixel shows the visible
    part of the sun's disc averaged over it (a circular segment at
    s = x / (z tan(angle / 2)) of its radius, as in test_lamps), to 2% of
    the sun (1.3% with every ray cast), for under a quarter of the rays."""
    half_angle, z, strength = 0.5 * math.radians(0.5), 1.0, 3.0
    sun = SunLight((0, 0, -1), strength, angle=2.0 * half_angle)
    wall = Object("Edge", shapes.plane(10.0, (-5.0, 0.0, z)), Diffuse(albedo=0.0, receiver=False))
    pixels = 32
    scene = Scene([Object("Floor", shapes.plane(40.0), Diffuse(albedo=1.0)), wall], [sun],
                  top_camera(0.05, pixels, 0.5), world=World())
    result = render(scene, RenderSettings(spp=16, edge_samples=0, lamp_rays=1000, lamp_samples=16))
    seen = result.passes["direct"][..., 0] * math.pi / strength
    step = scene.camera.ortho_scale / pixels
    x = floor_points(scene)[..., 0][..., None] + step * (np.arange(64) + 0.5 - 32) / 64
    s = np.clip(x / (z * math.tan(half_angle)), -1.0, 1.0)
    theta = 2.0 * np.arccos(s)
    visible = (1.0 - (theta - np.sin(theta)) / (2.0 * math.pi)).mean(axis=2)
    np.testing.assert_allclose(seen, visible, atol=0.02)
    assert np.all(seen[visible == 1.0] == pytest.approx(1.0, rel=1e-4)) and np.all(seen[visible == 0.0] == 0.0)
    across = ((visible > 0.0) & (visible < 1.0)).sum()
    assert across >= 3 * pixels
    # the camera rays and a shadow ray each, and 15 more where the probes disagree
    spp = 16
    assert result.stats["rays_eye_pass"] <= spp * (pixels * pixels * 2 + across * 15)
    assert result.stats["rays_eye_pass"] < 0.25 * spp * pixels * pixels * 17


def test_a_pixels_faint_reflections_go_on_in_a_stratified_count():
    """Glass (n = 1.5) seen head-on reflects F = 4% (Fresnel at normal
    incidence): below 5% of the camera ray, each reflection goes on with
    p = F / 0.05 = 0.8, its weight 1 / p. Each one's mean stays F, and of a
    pixel's 4 samples 3 or 4 reflections go on (about p of them, stratified),
    never the binomial count's 2 or fewer, which a pixel would show as a
    speckle of light reflected in the glass."""
    pixels, spp = 4000, 4
    glass = Object("Pane", shapes.plane(4.0, (0.0, 0.0, 0.0)), Dielectric(1.5))
    scene = Scene([glass], [], top_camera(1.0, 8, 5.0), world=World())
    accel = Accelerator(scene.objects, scene.extent(), threads=1)
    materials = Materials.of(scene.objects)
    n = pixels * spp
    origins = np.column_stack([np.zeros((n, 2)), np.ones(n)])
    dirs = np.tile([0.0, 0.0, -1.0], (n, 1))
    weight = np.ones((n, 3))
    paths = Paths.start(origins, dirs, weight, np.arange(n), (MISS, MISS), relative_floor(weight), camera=True)
    hits = accel.intersect(paths.origins, paths.dirs, paths.medium, paths.outer, paths.kind, paths.surface)
    surface = orient(accel, hits, paths.dirs, materials, paths.medium, paths.outer)
    fresnel = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2
    np.testing.assert_allclose(surface.fresnel, fresnel, rtol=1e-9)
    for strata in (spp, 1):
        roulette = Roulette(ROULETTE_WEIGHT, np.arange(n), stream_key(7, 0), strata)
        branches = split(accel, materials, paths, hits, surface, carries_light=False, roulette=roulette)
        reflected = branches.kind == REFLECTED
        kept = np.bincount(branches.ids[reflected] // spp, minlength=pixels)
        assert branches.weight[reflected, 0].sum() / n == pytest.approx(fresnel, rel=0.02)
        if strata == spp:
            assert set(np.unique(kept)) == {3, 4}
            assert kept.mean() == pytest.approx(spp * fresnel / ROULETTE_WEIGHT, rel=0.02)
        else:  # one draw a sample: the binomial count a pixel would speckle with
            assert (kept <= 2).mean() > 0.1
    accel.close()
