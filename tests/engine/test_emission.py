"""Photon emission: the paper's sphere grid and targeted cones carry the lamp's flux."""

import math

import numpy as np
import pytest

from caustic_addon import PointLight, SpotLight, SunLight
from caustic_addon.emission.aims import Aim, Sphere, aims, balance_density, meets_any, overlapping
from caustic_addon.emission.photons import PointSphereEmitter, make_emitters
from caustic_addon.sampling.warps import sample_disc


def test_sphere_mode_carries_the_whole_power_uniformly():
    """Eq. (1)'s grid weighted by cell solid angle: total flux = P, and every
    octant of directions gets an eighth of it."""
    light = PointLight((0, 0, 0), 100.0)
    emitter = PointSphereEmitter(light, 1.0, 20_000)
    photons = emitter.emit(0, emitter.count)
    assert photons.flux[:, 0].sum() == pytest.approx(100.0, rel=1e-9)
    octant = (photons.dirs > 0) @ np.array([1, 2, 4])
    per_octant = np.bincount(octant, weights=photons.flux[:, 0], minlength=8)
    np.testing.assert_allclose(per_octant, 100.0 / 8, rtol=0.02)


def test_targeted_flux_is_the_intensity_times_the_cones_union():
    """Two overlapping target spheres: the photons' total flux equals
    I * solid angle of the union of their cones, measured independently by
    counting uniform directions that fall in either cone."""
    light = PointLight((0, 0, 5), 4 * math.pi)  # I = 1 W/sr
    targets = [Sphere(np.array([0.0, 0.0, 0.0]), 1.0), Sphere(np.array([0.8, 0.0, 0.0]), 1.0)]
    (emitter,) = make_emitters([light], targets, Sphere(np.zeros(3), 10.0), "targeted", 1.0, 200_000, 0)
    flux = emitter.emit(0, emitter.count).flux[:, 0].sum()

    rng = np.random.default_rng(5)
    dirs = rng.normal(size=(4_000_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    inside = np.zeros(len(dirs), dtype=bool)
    for s in targets:
        axis = (s.center - light.position) / np.linalg.norm(s.center - light.position)
        cos_max = math.sqrt(1 - (s.radius / np.linalg.norm(s.center - light.position)) ** 2)
        inside |= dirs @ axis >= cos_max
    union = 4 * math.pi * inside.mean()
    assert flux == pytest.approx(union, rel=0.01)


def test_cone_samples_stay_in_the_cone_and_are_uniform():
    axis = np.array([0.0, 0.6, -0.8])
    cos_max = math.cos(0.3)
    uv = np.random.default_rng(2).random((100_000, 2))
    origins, dirs = Aim(PointLight((1, 2, 3), 1.0), axis, cos_max=cos_max).rays(sample_disc(1.0, uv))
    np.testing.assert_array_equal(origins, np.tile([1.0, 2.0, 3.0], (len(uv), 1)))
    cos = dirs @ axis
    assert cos.min() >= cos_max - 1e-12
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-12)
    # uniform in solid angle: cos(theta) is uniform on [cos_max, 1]
    hist, _ = np.histogram(cos, bins=10, range=(cos_max, 1.0))
    np.testing.assert_allclose(hist / hist.mean(), 1.0, atol=0.05)


def test_sun_discs_carry_irradiance_times_area():
    sun = SunLight((0, 0, -1), 3.0)
    target = Sphere(np.array([0.0, 0.0, 1.0]), 0.5)
    (emitter,) = make_emitters([sun], [target], Sphere(np.zeros(3), 4.5), "targeted", 1.0, 10_000, 0)
    photons = emitter.emit(0, emitter.count)
    assert photons.flux[:, 0].sum() == pytest.approx(3.0 * math.pi * 0.25, rel=1e-9)
    np.testing.assert_allclose(photons.dirs, np.tile([0.0, 0.0, -1.0], (len(photons.dirs), 1)))
    assert np.all(photons.origins[:, 2] > 10.0)


def test_a_spot_that_misses_every_target_emits_nothing():
    spot = SpotLight((0, 0, 5), (1, 0, 0), 100.0, spot_size=math.radians(30))
    targets = [Sphere(np.array([0.0, 0.0, 0.0]), 1.0)]
    assert make_emitters([spot], targets, targets[0], "targeted", 1.0, 1000, 0) == []
    aimed = SpotLight((0, 0, 5), (0, 0, -1), 100.0, spot_size=math.radians(30))
    assert len(make_emitters([aimed], targets, targets[0], "targeted", 1.0, 1000, 0)) == 1


def test_photon_budget_follows_the_flux_each_lamp_sends_to_the_targets():
    targets = [Sphere(np.array([0.0, 0.0, 0.0]), 1.0)]
    near = PointLight((0, 0, 3), 100.0)
    far = PointLight((0, 0, 30), 100.0)
    emitters = make_emitters([near, far], targets, targets[0], "targeted", 1.0, 100_000, 0)
    counts = [e.count for e in emitters]
    # each lamp's flux toward the sphere: P / (4 pi) times its cone's solid angle
    fluxes = [1.0 - math.sqrt(1.0 - (1.0 / d) ** 2) for d in (3.0, 30.0)]
    assert counts[0] / counts[1] == pytest.approx(fluxes[0] / fluxes[1], rel=0.01)
    ids = np.concatenate([e.emit(0, e.count).ids for e in emitters])
    assert len(np.unique(ids)) == len(ids)


@pytest.mark.parametrize("light", [PointLight((0.0, 0.0, 4.0), 100.0, radius=0.3),
                                   SunLight((0.3, -0.2, -1.0), 3.0, angle=math.radians(2.0))],
                         ids=["point", "sun"])
def test_an_aim_shares_its_rays_only_with_the_aims_that_can_hold_them(light):
    """Many casters: each aim's rays are weighed against only the aims that
    may hold them (aims.overlapping), which is what keeps a lamp's pass
    linear in the casters. Over casters strewn near and far, every aim that
    holds a ray of another is among its overlapping ones, and the density
    summed over those alone is the sum over all, to the bit."""
    rng = np.random.default_rng(5)
    targets = [Sphere(np.array([x, y, 0.3]), r) for x, y, r in
               zip(rng.uniform(-3, 3, 60), rng.uniform(-3, 3, 60), rng.uniform(0.05, 0.6, 60))]
    every = aims(light, targets, Sphere(np.zeros(3), 6.0))
    density = rng.uniform(1.0, 2.0, len(every))
    near = overlapping(every)
    assert all(i in held for i, held in enumerate(near)) and 60 < sum(map(len, near)) < 60 * 30
    disc = sample_disc(1.0, rng.uniform(size=(4000, 2)))
    for i, aim in enumerate(every):
        origins, dirs = aim.rays(disc, rng.uniform(size=(4000, 2)))
        holding = {j for j, other in enumerate(every) if other.contains(origins, dirs).any()}
        assert holding <= set(near[i].tolist())
        assert np.array_equal(balance_density([every[j] for j in near[i]], density[near[i]], origins, dirs),
                              balance_density(every, density, origins, dirs))


def test_rays_meet_a_sphere_within_their_closest_approach_ahead():
    """A unit sphere 3 m along +z from the origin: rays from the origin meet
    it up to asin(1/3) off the axis and not beyond, not backwards, and a ray
    from inside meets it in any direction; the fraction of directions
    uniform over the sphere that meet it is its cone's share, (1 - cos)/2."""
    sphere = Sphere(np.array([0.0, 0.0, 3.0]), 1.0)
    edge = math.asin(1.0 / 3.0)
    tilts = np.array([0.0, edge - 1e-6, edge + 1e-6, math.pi])
    dirs = np.stack([np.sin(tilts), np.zeros(4), np.cos(tilts)], axis=1)
    assert list(meets_any([sphere], np.zeros((4, 3)), dirs)) == [True, True, False, False]
    assert meets_any([sphere], np.tile([0.0, 0.0, 3.5], (4, 1)), dirs).all()
    rng = np.random.default_rng(2)
    everywhere = rng.normal(size=(400_000, 3))
    everywhere /= np.linalg.norm(everywhere, axis=1)[:, None]
    share = meets_any([sphere], np.zeros_like(everywhere), everywhere).mean()
    assert share == pytest.approx((1.0 - math.cos(edge)) / 2.0, abs=2e-3)
