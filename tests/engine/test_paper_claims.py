"""The paper's claims (section 4) on its scenes (benchmarks/scenes/paper_scenes.py).

Where physics agrees with the paper a test asserts the paper's trend; where
it does not, it asserts what physics says, and its docstring says why
(benchmarks/PAPER.md has the numbers). The claims are read from the floor's
illumination map, so the camera is 8x8 pixels; the map is the paper's
bilinear splat.
"""

import math
from functools import lru_cache

import numpy as np
import pytest

from benchmarks.scenes import paper_scenes as ps
from caustic_addon import paper, render

PHOTONS = 300_000
TINY = (8, 8)
WATER, ZIRCONIA, DIAMOND = paper.INDICES.values()
ENERGY = ps.PAPER_DEFAULTS["energy"]
PAPER_RAYS = ps.PAPER_DEFAULTS["lamp_rays"]
SMALL_MM, LARGE_MM = ps.PAPER_SWEEPS["map_scale"]
# The floor is tilted 15 (resting) to 21 degrees (raised) from square to the
# lamp's axis through the ball, which stretches the caustic by up to
# 1 / cos(21 deg) = 1.07 one way, and the map blurs it by about a cell.
REFERENCE_RTOL = 0.1


def render_floor(shape: str, ior: float, height: float, floor: float, map_scale: float, photons: int,
                 energy: float = ENERGY):
    """(scene, floor illumination map) of the paper's scene, splat cells of `map_scale` mm."""
    scene = ps.paper_scene(shape, ior, height, TINY, floor)
    result = render(scene, ps.splat_settings(scene, map_scale, lamp_rays=photons, energy=energy, spp=1))
    return scene, result.maps["Floor"]


@lru_cache(maxsize=None)
def caustic(shape: str, ior: float = ps.GLASS_IOR, height: float = 0.0) -> ps.Caustic:
    """The measured caustic of a shape-sweep scene, as paper.py measures it."""
    scene, imap = render_floor(shape, ior, height, paper.FLOOR_SIZE, ps.SHAPE_MAP_SCALE, PHOTONS)
    return ps.measure(imap, scene, ENERGY)


@lru_cache(maxsize=None)
def flat_noise(photons: int, map_scale: float) -> float:
    """Relative noise (ps.noise) in the even patch under the resting glass cylinder."""
    scene, imap = render_floor("flat", ps.GLASS_IOR, 0.0, ps.RESTING_FLOOR, map_scale, photons)
    return ps.noise(imap, *ps.flat_patch(scene))


def exact_r50(ior: float, height: float) -> float:
    return ps.reference_r50(ps.paper_scene("round", ior, height, TINY))


def assert_follows_reference(measured: list[ps.Caustic], exact: list[float]) -> None:
    """Each r50 within REFERENCE_RTOL plus a map cell of the exact ball lens's."""
    cell = ps.SHAPE_MAP_SCALE / 1000.0
    for c, r in zip(measured, exact):
        assert c.r50 == pytest.approx(r, rel=REFERENCE_RTOL, abs=cell)


def test_round_base_at_rest_gathers_and_whitens_until_the_focus_passes_the_floor():
    """Paper: a higher index gathers the round base's caustic into a point
    and makes it whiter. A ball lens of radius R has focal length
    f = n R / (2 (n - 1)) from its centre, so the lamp's image moves toward
    the glass as n grows; the caustic is tightest where the floor meets the
    focus. At rest the floor is 0.52 m from the centre along the lamp's axis
    and the paraxial images lie 1.40 (water), 0.62 (zirconia) and 0.48 m
    (diamond) away, spherical aberration pulling the real focus nearer
    still: from water to zirconia the floor comes nearer the focus and the
    paper holds; diamond focuses inside the glass and its light has spread
    again when it reaches the floor, so it is wider and dimmer than zirconia's."""
    water, zirconia, diamond = (caustic("round", n) for n in (WATER, ZIRCONIA, DIAMOND))
    assert zirconia.r50 < water.r50 and zirconia.whiteness > water.whiteness
    assert diamond.r50 > zirconia.r50 and diamond.whiteness < zirconia.whiteness
    assert_follows_reference([water, zirconia, diamond], [exact_r50(n, 0.0) for n in (WATER, ZIRCONIA, DIAMOND)])


def test_raised_round_base_spreads_and_dims_as_the_index_rises():
    """Contradicts the paper. Raised by 1 m, the floor is 1.60 m from the
    ball's centre along the lamp's axis: water's paraxial image (1.62 m)
    falls on it, zirconia's (0.66 m) and diamond's (0.51 m) far above it,
    so the higher the index, the farther past its focus the light has
    diverged when it lands: a wider, dimmer caustic."""
    water, zirconia, diamond = (caustic("round", n, paper.RAISED) for n in (WATER, ZIRCONIA, DIAMOND))
    assert water.r50 < zirconia.r50 < diamond.r50
    assert water.whiteness > zirconia.whiteness > diamond.whiteness
    assert_follows_reference([water, zirconia, diamond],
                             [exact_r50(n, paper.RAISED) for n in (WATER, ZIRCONIA, DIAMOND)])


def test_flat_base_at_rest_spreads_into_a_larger_circle_as_the_index_rises():
    """Paper: a higher index spreads the flat base's caustic into a larger
    circle. Light through the top face drifts sideways by 0.8 m tan(t)
    inside the cylinder, t the refraction angle, which shrinks as n grows
    (sin t = sin i / n); what drifts past the far wall is folded back by
    total internal reflection into a bright crescent on the far side of the
    base. Less drift at a higher index folds less light, so the lit disc is
    filled more evenly (larger r50) and its centroid comes nearer the base's
    centre."""
    water, zirconia, diamond = (caustic("flat", n) for n in (WATER, ZIRCONIA, DIAMOND))
    assert water.r50 < zirconia.r50 < diamond.r50
    assert math.hypot(*water.centroid) > math.hypot(*zirconia.centroid) > math.hypot(*diamond.centroid)


def test_pointed_base_at_rest_moves_out_with_total_internal_reflection_then_back_in():
    """Paper: a higher index spreads the pointed base's caustic and moves it
    away from the shadow. The cone (half-angle b = 26.6 deg) reflects
    light from its top face totally at one facet (incidence 90 - b = 63.4
    deg for a vertical ray, past the critical angle for every n > 1.12) and
    sends it out through the opposite facet toward the lamp's side, away
    from the shadow. Water's critical angle (48.8 deg) is passed only by
    rays tilted less than 14.7 deg inside, so part of its light leaves
    through the first facet near the shadow: from water to zirconia the
    caustic moves out and spreads, as the paper says. Once all of it is
    reflected, the exit facet refracts it at asin(n cos 3b) from its
    normal, turning it toward the vertical: 43.5 deg from it for zirconia,
    37.9 deg for diamond. Diamond's caustic lands nearer the cone, tighter
    and closer to the shadow than zirconia's."""
    water, zirconia, diamond = (caustic("pointed", n) for n in (WATER, ZIRCONIA, DIAMOND))
    assert zirconia.offset > water.offset and zirconia.r50 > water.r50
    assert diamond.offset < zirconia.offset and diamond.r50 < zirconia.r50


def test_more_lamp_rays_make_the_caustic_clearer():
    """Paper: more lamp rays, a clearer caustic. A cell's estimate averages
    the photons in it, whose number grows as N: independent photons would
    give a relative noise falling as N^(-1/2). The engine's photons leave
    on a low-discrepancy sequence, which spreads them more evenly than
    chance, so the noise falls at least that fast, but no faster than the
    N^(-1) of a perfectly even spread. The tolerance is the uncertainty of
    a standard deviation over the patch's ~2,800 cells, about 1/sqrt(2 * 2800)."""
    counts = [PAPER_RAYS, 4 * PAPER_RAYS, 16 * PAPER_RAYS]
    noise = [flat_noise(n, SMALL_MM) for n in counts]
    slope = np.polyfit(np.log(counts), np.log(noise), 1)[0]
    assert -1.0 - 0.05 < slope < -0.5 + 0.05


def test_lamp_energy_scales_the_caustic_linearly():
    """Paper: more energy, a brighter caustic. Energy multiplies every
    photon's flux and, with the same seed, changes no path: the map and the
    image are exactly proportional to it."""
    low, high = ps.PAPER_SWEEPS["energy"]
    scene = ps.paper_scene("round", pixels=TINY, floor=ps.RESTING_FLOOR)
    results = [render(scene, ps.splat_settings(scene, SMALL_MM, lamp_rays=PAPER_RAYS, energy=e, spp=1))
               for e in (low, high)]
    ratio = high / low
    np.testing.assert_allclose(results[1].maps["Floor"].flux, ratio * results[0].maps["Floor"].flux, rtol=1e-12)
    for name in ("caustic", "direct"):
        np.testing.assert_allclose(results[1].passes[name], ratio * results[0].passes[name], rtol=1e-6)
    assert results[0].passes["caustic"].max() > 0


def test_small_map_scale_is_whiter_and_large_map_scale_smoother():
    """Paper: a small map scale makes the caustic point-like and whiter, a
    large one smoother. A cell reports its flux over its area: 40 mm cells
    average the ball's sharp caustic down (lower peak), 5 mm cells resolve
    it. A cell holds photons in proportion to its area, so its relative
    noise falls with its edge: 8 times from 5 to 40 mm for independent
    photons; asserted at least half that gain."""
    scene_small, small = render_floor("round", ps.GLASS_IOR, 0.0, ps.RESTING_FLOOR, SMALL_MM, PAPER_RAYS)
    scene_large, large = render_floor("round", ps.GLASS_IOR, 0.0, ps.RESTING_FLOOR, LARGE_MM, PAPER_RAYS)
    assert ps.measure(small, scene_small, ENERGY).peak > ps.measure(large, scene_large, ENERGY).peak
    assert flat_noise(PAPER_RAYS, LARGE_MM) < 2.0 * (SMALL_MM / LARGE_MM) * flat_noise(PAPER_RAYS, SMALL_MM)


def test_raising_flat_and_pointed_bases_spreads_their_caustics():
    """Paper: the higher the object, the more its caustic spreads. Light
    leaving the cylinder's bottom face and the cone's facets diverges from
    the lamp's side of the glass; the farther it falls, the wider it lands."""
    for shape in ("flat", "pointed"):
        assert caustic(shape, height=paper.RAISED).r50 > caustic(shape).r50


def test_raising_the_round_base_gathers_its_caustic_until_the_floor_reaches_the_focus():
    """Contradicts the paper below the focus. Glass (n = 1.5) focuses the
    lamp 0.95 m from the ball's centre (paraxial; nearer with spherical
    aberration) but its centre rests 0.52 m from the floor: raising it 0.25 m
    brings the floor to the focus and gathers the caustic; from there on,
    as the paper says, raising it spreads the caustic. The exact ball lens
    agrees."""
    heights = (0.0, 0.25, paper.RAISED)
    resting, focused, raised = (caustic("round", height=h) for h in heights)
    assert focused.r50 < resting.r50 and focused.whiteness > resting.whiteness
    assert raised.r50 > focused.r50 and raised.whiteness < focused.whiteness
    assert_follows_reference([resting, focused, raised], [exact_r50(ps.GLASS_IOR, h) for h in heights])
