"""Caustic beams: noise-free, flux-conserving, and exact against the ball-lens reference."""

import math
from dataclasses import replace

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Object, RenderSettings, Scene, SunLight, render, shapes
from caustic_addon.maps.beam_map import BeamMap, layer_shares
from caustic_addon.maps.cache import MapCache
from caustic_addon.maps.charts import PlaneChart
from caustic_addon.maps.illumination_map import MapEstimate
from caustic_addon.maps.raster import signed_areas
from caustic_addon.sampling.warps import concentric_disc
from benchmarks.references.metrics import annulus_means, annulus_points, relative_l2
from scenes import ball_lens, quick, shadow_radius


def test_concentric_map_is_equal_area_and_fills_the_disc():
    ticks = (np.arange(200) + 0.5) / 200
    uv = np.stack(np.meshgrid(ticks, ticks), -1).reshape(-1, 2)
    disc = concentric_disc(uv)
    r = np.linalg.norm(disc, axis=1)
    assert r.max() <= 1.0 + 1e-12
    # equal area: the fraction of points within radius rho is rho^2
    for rho in (0.25, 0.5, 0.75):
        assert np.mean(r <= rho) == pytest.approx(rho ** 2, abs=0.01)


def radial_error(photons: int) -> float:
    from benchmarks.references import reference

    r_edges = np.linspace(0.0, shadow_radius(), 61)
    exact = reference.ball_lens_irradiance(1.0, 1.5, 1.5, 6.0, 1000.0 / (4 * math.pi), r_edges)
    result = render(ball_lens(pixels=8, segments=256), quick(lamp_rays=photons, density="beam"))
    ours = annulus_means(result.maps["Floor"].irradiance_at(annulus_points(r_edges, 200))[:, 0], r_edges)
    return relative_l2(ours, exact.caustic, r_edges)


def test_beams_match_the_exact_reference_with_few_paths():
    """40,000 grid paths give the ball lens's radial caustic to within 2.5%;
    photon splatting needs millions of photons for 5%. (What is left is the
    rasterisation layers' cell size, about 1 mm at the focus.)"""
    assert radial_error(40_000) < 0.025


def test_the_ball_lens_fold_ring_is_on_the_fine_grid_and_pixel_sharp():
    """The ball lens's caustic ends at a fold ring 125 mm off the axis,
    whose irradiance rises as 1/sqrt(distance) up to it. At 100,000 lamp
    rays the fine grid was laid over where flux times irradiance
    concentrates, which the focus on the axis dominates: its box ended at
    the ring, and the ring's beams went to the map's own 7.8 mm cells, which
    moved their light up to 16 mm inward (2 mm bins across the fold: 69%
    RMS off, the last bin at 20%). On the fine grid the means over those
    bins are exact within the ~1 mm smear of its cells, which leaves the
    last bin 15% dim and spills light just past the fold (15% RMS)."""
    from benchmarks.references import reference

    intensity = 1000.0 / (4 * math.pi)
    edges = np.linspace(0.0, shadow_radius(), 8001)
    exact = reference.ball_lens_irradiance(1.0, 1.5, 1.5, 6.0, intensity, edges).caustic
    fold = edges[np.argmax(exact[80:]) + 81]
    x_edges = np.linspace(fold - 0.016, fold + 0.002, 10)
    exact = reference.ball_lens_irradiance(1.0, 1.5, 1.5, 6.0, intensity, x_edges).caustic
    imap = render(ball_lens(pixels=8, segments=256), quick(lamp_rays=100_000, density="beam")).maps["Floor"]
    # 4 mm strips across the ring where it runs along y, both sides of the axis
    lo = np.stack([x_edges[:-1], np.full(9, -0.002)], axis=1)
    hi = np.stack([x_edges[1:], np.full(9, 0.002)], axis=1)
    ours = 0.5 * (imap.mean_over(lo, hi) + imap.mean_over(-hi, -lo))[:, 0]
    assert np.sqrt(np.mean((ours - exact) ** 2) / np.mean(exact ** 2)) < 0.25
    np.testing.assert_allclose(ours[:7], exact[:7], rtol=0.03)


def test_the_folds_of_water_with_one_wave_converge_to_its_exact_caustic():
    """A slanted sun through water whose top is one cosine wave, meshed
    with its crests along the triangles' diagonals (benchmarks/scenes/sine_slab.py):
    the exact image of that mesh, summed in 1D, has fold lines where the
    light piles up fivefold. At 300,000 lamp rays the beams are within 1.6%
    of it per pixel (Mitsuba's particle tracer needs about 12,000 particles
    a pixel for as much), as close at the folds (the brightest 5% of the
    pixels), and the mean within 0.4%."""
    from benchmarks.scenes import sine_slab

    exact = sine_slab.exact_radiance("sine_slab_diagonal", samples_per_metre=1 << 22)
    region = sine_slab.region("sine_slab_diagonal")
    ours = render(sine_slab.scene("sine_slab_diagonal"),
                  RenderSettings(lamp_rays=300_000, spp=1, beam_refinement=1)).passes["caustic"][..., 0]
    folds = region & (exact >= np.quantile(exact[region], 0.95))
    for where, bound in ((region, 0.02), (folds, 0.02)):
        assert np.linalg.norm(ours[where] - exact[where]) / np.linalg.norm(exact[where]) < bound
    assert abs(ours[region].mean() / exact[region].mean() - 1.0) < 0.006


def test_beams_carry_the_same_flux_as_photons():
    beams = render(ball_lens(pixels=8), quick(lamp_rays=40_000, density="beam")).stats["flux_landed_w"]
    photons = render(ball_lens(pixels=8), quick(lamp_rays=400_000)).stats["flux_landed_w"]
    np.testing.assert_allclose(beams, photons, rtol=0.01)


def test_beam_caustic_has_no_noise():
    """No random number decides a beam: renders with different seeds give
    the same map, where photon maps differ by their noise."""
    xy = np.stack([np.linspace(0.0, 0.9, 50), np.zeros(50)], axis=1)

    def caustic(**kwargs):
        return render(ball_lens(pixels=8), quick(lamp_rays=40_000, **kwargs)).maps["Floor"].irradiance_at(xy)

    np.testing.assert_allclose(caustic(density="beam", seed=1), caustic(density="beam", seed=2), rtol=1e-9)
    assert not np.allclose(caustic(seed=1), caustic(seed=2), rtol=1e-3)


def test_beam_renders_are_finite_and_conserve_flux_under_glass_colour_and_absorption():
    result = render(ball_lens(pixels=16, absorption=0.4, ior=2.41), quick(lamp_rays=20_000, density="beam", spp=4))
    assert np.isfinite(result.image).all()
    assert np.isfinite(result.maps["Floor"].irradiance()).all()


def test_refined_cells_are_tiled_without_cracks():
    """A cell beside split neighbours becomes a fan through their shared
    vertex, so no beam edge ends in the middle of another's."""
    from caustic_addon.passes.beam_grid import Cells, crack_free_triangles

    width = 9
    row, col, size = np.array([0, 0, 2, 0, 2]), np.array([0, 4, 4, 6, 6]), np.array([4, 2, 2, 2, 2])
    traced = np.unique([(r + dr) * width + c + dc for r, c, s in zip(row, col, size)
                        for dr in (0, s) for dc in (0, s)])
    triangles, area, centres = crack_free_triangles(Cells(row, col, size, np.zeros(5, dtype=np.int64)), width, traced)
    assert area.sum() == pytest.approx(float((size ** 2).sum()))
    assert np.all(area > 0)
    np.testing.assert_array_equal(centres, [2 * width + 2])
    hanging = 2 * width + 4
    assert np.count_nonzero((triangles == hanging).any(axis=1)) == 2 + 3  # the fan's 2, the small cells' 3


def facetted_gem():
    from caustic_addon import Camera, Dielectric, Diffuse, Mesh, Object, PointLight, Scene, shapes

    cone = shapes.cone(0.5, 1.0, (0, 0, 0.2), segments=12)
    return Scene(objects=[Object("Floor", shapes.plane(4.0), Diffuse(albedo=1.0)),
                          Object("Gem", Mesh(cone.vertices, cone.triangles), Dielectric(2.41))],
                 lights=[PointLight((0.3, 0.2, 3.0), 1000.0)],
                 camera=Camera.look_at((0, -3, 2.5), (0, 0, 0), pixx=8, pixy=6))


def test_refinement_moves_light_from_fallback_photons_into_beams_on_a_facetted_gem():
    """Facet edges split a plain grid's triangles between families; their
    light falls back to photons, a share proportional to the grid spacing
    along the edges. Refinement follows the edges 2^2 times finer than its
    base grid (3162 paths: 56 a side, so 224 along edges), where a plain
    grid with as many paths in all has about 160 a side: it leaves about
    160/224 = 0.71 as much light to photons. The total is unchanged."""
    def render_gem(photons, levels):
        result = render(facetted_gem(), quick(lamp_rays=photons, density="beam", beam_refinement=levels,
                                              map_scale=10.0, spp=1))
        total = np.array(result.stats["flux_landed_w"])
        return result.maps["Floor"].flux.sum(axis=(0, 1)) / total, total, result.stats["lamp_rays"]

    refined_share, refined_total, paths = render_gem(3162, 2)
    plain_share, plain_total, _ = render_gem(paths, 0)
    assert refined_share[0] < 0.85 * plain_share[0]
    np.testing.assert_allclose(refined_total, plain_total, rtol=0.02)


def test_beams_land_on_a_receiver_listed_after_the_glass():
    """Beam mode once looked up every object index below the last receiver
    as a map, and failed when a non-receiver came first. The object order
    must not change the light."""
    scene = ball_lens(pixels=8)
    reversed_scene = Scene(objects=scene.objects[::-1], lights=scene.lights, camera=scene.camera)
    first = render(scene, quick(lamp_rays=4_000, density="beam")).stats["flux_landed_w"]
    second = render(reversed_scene, quick(lamp_rays=4_000, density="beam")).stats["flux_landed_w"]
    np.testing.assert_allclose(second, first, rtol=1e-9)


def layered_beam_map(threads: int, flush: int = BeamMap.FLUSH_BEAMS) -> tuple[BeamMap, np.ndarray, np.ndarray]:
    """A 4 m square floor of 5 cm cells holding, on one side, one beam wide
    enough for the coarse layer and, on the other, beams of the map's size
    and beams for the fine layer, in both windings and colours. Returns the
    map, and the beams' corners (m,3,2) in its chart and irradiance (m,3)."""
    verts = np.array([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]], dtype=float)
    chart = PlaneChart(np.array([2.0, 2.0, 0.0]), np.array([0.0, 0.0, 1.0]), verts)
    imap = BeamMap("floor", chart, 0.05, MapEstimate(16), threads=threads)
    imap.FLUSH_BEAMS = flush
    rng = np.random.default_rng(5)
    wide = np.array([[[0.2, 0.2], [1.8, 0.3], [0.4, 3.6]]])
    medium = rng.uniform(2.4, 3.4, (40, 1, 2)) + rng.uniform(-0.15, 0.15, (40, 3, 2))
    small = rng.uniform(2.4, 3.4, (400, 1, 2)) + rng.uniform(-0.03, 0.03, (400, 3, 2))
    corners = np.concatenate([wide, medium, small])
    irradiance = rng.uniform(0.5, 2.0, (len(corners), 3))
    order = rng.permutation(len(corners))
    for part in np.array_split(order, 9):
        imap.add_beams(corners[part] + chart.origin, irradiance[part])
    return imap, corners + chart.origin, irradiance


def test_a_beam_map_keeps_every_beams_flux_in_its_layers():
    """Over the whole floor the map holds every beam's flux (irradiance x
    area), with beams in all three layers; inside the wide beam, away from
    the others, it reads that beam's irradiance exactly; two threads
    rasterise the same map as one, and read the same bake from it."""
    imap, corners, irradiance = layered_beam_map(threads=2)
    flux = (irradiance * np.abs(signed_areas(corners))[:, None]).sum(axis=0)
    lo, hi = imap.chart.origin, imap.chart.origin + imap.chart.size
    np.testing.assert_allclose(imap.mean_over(lo[None], hi[None])[0] * 16.0, flux, rtol=1e-12)
    assert len(imap._layers) == 3
    inside = np.array([[0.5, 1.0], [0.6, 1.1]]) + imap.chart.origin
    np.testing.assert_allclose(imap.mean_over(inside[:1], inside[1:])[0], irradiance[0], rtol=1e-12)
    one_thread = layered_beam_map(threads=1)[0]
    rng = np.random.default_rng(6)
    boxes_lo = imap.chart.origin + rng.uniform(0.0, 3.5, (300, 2))
    boxes_hi = boxes_lo + rng.uniform(0.01, 0.5, (300, 2))
    np.testing.assert_array_equal(imap.mean_over(boxes_lo, boxes_hi), one_thread.mean_over(boxes_lo, boxes_hi))
    np.testing.assert_array_equal(imap.irradiance(2), one_thread.irradiance(1))
    np.testing.assert_allclose(imap.irradiance(2).sum(axis=(0, 1)) * imap.cell ** 2, flux, rtol=1e-9)


def wavy_sheet_scene():
    """A sun through an open sheet of water (a plane with 100 cuts displaced
    by four waves, as a Wave or Ocean modifier makes it) 1 m over a floor:
    a network of folds and cusps whose beams range from a tenth of a map
    cell to tens of cells."""
    waves = ((0.02, 0.5, 0.3), (0.015, 0.37, 1.4), (0.01, 0.23, 2.5), (0.006, 0.17, 4.0))
    camera = Camera.look_at((0.0, 0.0, 20.0), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixx=8, pixy=8, kind="ORTHO",
                            ortho_scale=1.0)
    return Scene(objects=[Object("Floor", shapes.plane(2.0), Diffuse(albedo=0.8)),
                          Object("Water", shapes.wavy_sheet(1.0, waves, 100, (0.0, 0.0, 1.0)), Dielectric(1.33))],
                 lights=[SunLight((0.1, 0.05, -1.0), 1000.0)], camera=camera)


def test_a_beam_map_of_a_wavy_sheet_agrees_with_a_dense_photon_map_cell_by_cell_and_row_by_row():
    """The map a bake writes holds, in every 10 mm cell, the beams' flux
    there (their exact mean over the cell, not a point sample of the finer
    layers, which aliased the sharp lines into blocks missing light), so
    each row of cells carries the flux a photon map of 1M photons puts
    there: about 8,000 photons a lit row, 1.1% noise, and their 4 x 4 cell
    blocks 2%. (Before, rows were off by 9% RMS and blocks by 14%.)"""
    scene = wavy_sheet_scene()
    beams = render(scene, quick(lamp_rays=40_000, density="beam", map_scale=10.0)).maps["Floor"].irradiance()
    photons = render(scene, quick(lamp_rays=1_000_000, density="splat", map_scale=10.0)).maps["Floor"].irradiance()
    beams, photons = beams[..., 0], photons[..., 0]
    rows_b, rows_p = beams.sum(axis=1), photons.sum(axis=1)
    lit = rows_p > 0.2 * rows_p.max()
    assert np.sqrt(np.mean(((rows_b - rows_p)[lit] / rows_p[lit].mean()) ** 2)) < 0.025
    h, w = (s // 4 * 4 for s in beams.shape)
    blocks_b, blocks_p = (a[:h, :w].reshape(h // 4, 4, w // 4, 4).sum(axis=(1, 3)) for a in (beams, photons))
    lit = blocks_p > 0.05 * blocks_p.max()
    assert np.sqrt(np.sum((blocks_b - blocks_p)[lit] ** 2) / np.sum(blocks_p[lit] ** 2)) < 0.04


def clipped_area(triangle: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Area of `triangle (3,2)` inside the box [lo, hi] (Sutherland-Hodgman)."""
    polygon = list(triangle)
    for axis, bound, keep_below in ((0, lo[0], False), (0, hi[0], True), (1, lo[1], False), (1, hi[1], True)):
        inside = [(p[axis] <= bound) == keep_below for p in polygon]
        clipped = []
        for k, p in enumerate(polygon):
            q = polygon[k - 1]
            if inside[k] != inside[k - 1]:
                clipped.append(q + (p - q) * (bound - q[axis]) / (p[axis] - q[axis]))
            if inside[k]:
                clipped.append(p)
        polygon = clipped
        if not polygon:
            return 0.0
    x, y = np.array(polygon).T
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def test_a_bakes_map_gives_each_cell_its_beams_exact_mean():
    """A map that no eye pass reads (a bake's, `sub_cell` off) keeps its
    small beams, those of a few cells and under, on its own cells, so each
    cell of its image holds exactly the beams' flux over it divided by its
    area; a fine layer of unaligned cells would approximate it."""
    verts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    chart = PlaneChart(np.array([0.5, 0.5, 0.0]), np.array([0.0, 0.0, 1.0]), verts)
    imap = BeamMap("floor", chart, 0.1, MapEstimate(16), sub_cell=False)
    rng = np.random.default_rng(3)
    corners = rng.uniform(0.2, 0.8, (30, 1, 2)) + rng.uniform(-0.12, 0.12, (30, 3, 2))
    irradiance = rng.uniform(0.5, 2.0, (30, 3))
    imap.add_beams(corners + chart.origin, irradiance)
    image = imap.irradiance()
    exact = np.zeros_like(image)
    for row in range(image.shape[0]):
        for col in range(image.shape[1]):
            lo, hi = np.array([col, row]) * 0.1, np.array([col + 1, row + 1]) * 0.1
            areas = np.array([clipped_area(t, lo, hi) for t in corners])
            exact[row, col] = areas @ irradiance / 0.01
    spans = (corners.max(axis=1) - corners.min(axis=1)).max(axis=1)
    assert (layer_shares(spans / 0.1)[0] > 0.0).all() and min(layer.cell for layer in imap._layers) == 0.1
    np.testing.assert_allclose(image, exact, rtol=1e-9, atol=1e-12)


def test_a_bake_traces_no_eye_pass_and_holds_the_renders_light():
    """Without the eye pass (a bake) the maps hold the light a render's
    maps hold, the same beams on the receiver's own cells; the two are
    kept apart in a cache, since a render's maps carry finer layers."""
    scene, settings = ball_lens(), quick(lamp_rays=4_000, density="beam")
    cache = MapCache(capacity=2)
    rendered = render(scene, settings, cache=cache)
    baked = render(scene, replace(settings, eye_pass=False), cache=cache)
    assert "eye" not in baked.stats["seconds"] and not baked.stats["maps_cached"] and not baked.image[..., :3].any()
    full, bake = rendered.maps["Floor"].irradiance(), baked.maps["Floor"].irradiance()
    np.testing.assert_allclose(bake.sum(axis=(0, 1)), full.sum(axis=(0, 1)), rtol=1e-9)
    assert np.linalg.norm(bake - full) / np.linalg.norm(full) < 0.05


def test_beams_of_about_a_cell_share_their_light_between_layers_smoothly():
    """A beam's share of the fine layer falls, and the coarse layer's
    rises, with its size, without a step: a hard cut put neighbouring beams
    of nearly one size into layers of different cells, whose seam showed
    as stair-steps wherever the map was read finer than its cells."""
    size = np.linspace(0.0, 64.0, 6401)
    fine, coarse = layer_shares(size)
    assert fine[0] == 1.0 and fine[-1] == 0.0 and coarse[0] == 0.0 and coarse[-1] == 1.0
    assert np.abs(np.diff(fine)).max() < 0.01 and np.abs(np.diff(coarse)).max() < 0.01
    assert (fine * coarse == 0.0).all()


def test_a_beam_map_rasterised_in_batches_is_the_map_rasterised_at_once():
    """Beams rasterised as they come, FLUSH_BEAMS at a time (so that memory
    stays bounded whatever the lamp rays), give the map that rasterising
    them all at the end gives: the same flux over the floor and the same
    means inside the fine and the coarse beams' regions."""
    at_once = layered_beam_map(threads=2)[0]
    batched, corners, irradiance = layered_beam_map(threads=2, flush=100)
    assert batched._layers == [] and batched._grids is not None  # rasterised before the map is read
    lo, hi = at_once.chart.origin, at_once.chart.origin + at_once.chart.size
    np.testing.assert_allclose(batched.mean_over(lo[None], hi[None]), at_once.mean_over(lo[None], hi[None]),
                               rtol=1e-12)
    rng = np.random.default_rng(7)
    boxes_lo = at_once.chart.origin + np.concatenate([rng.uniform(2.4, 3.3, (100, 2)), rng.uniform(0.3, 1.0, (100, 2))])
    boxes_hi = boxes_lo + rng.uniform(0.01, 0.1, (200, 2))
    # the few beams that fall outside the fine grid laid out from the first
    # ones go to the map's own grid: their light moves by under a cell
    np.testing.assert_allclose(batched.mean_over(boxes_lo, boxes_hi), at_once.mean_over(boxes_lo, boxes_hi),
                               rtol=1e-3, atol=1e-9)



def test_the_fine_layer_holds_a_ring_of_light_around_a_brighter_focus():
    """A bright focus, a ring of small beams a hundredth as bright around
    it (a ball lens's fold ring), and dim small beams all over the floor:
    the fine layer is laid over the whole ring. Laid over a quantile of
    where the bright light landed, it was the focus's box: the ring's
    beams beyond it fell to the map's own 5 cm cells, at the four sides
    where the ring passes the box, and the ball lens's caustic came out
    9% off at 100k lamp rays (0.8% at 120k)."""
    verts = np.array([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]], dtype=float)
    chart = PlaneChart(np.array([2.0, 2.0, 0.0]), np.array([0.0, 0.0, 1.0]), verts)
    imap = BeamMap("floor", chart, 0.05, MapEstimate(16))
    centre = chart.origin + 2.0
    angle = np.linspace(0.0, 2.0 * np.pi, 7201)

    def annulus(r0, r1):
        inner, outer = (centre + r * np.stack([np.cos(angle), np.sin(angle)], axis=1) for r in (r0, r1))
        return np.concatenate([np.stack([inner[:-1], outer[:-1], outer[1:]], axis=1),
                               np.stack([inner[:-1], outer[1:], inner[1:]], axis=1)])

    focus, ring = annulus(0.0, 0.01), annulus(0.5, 0.504)
    rng = np.random.default_rng(8)
    dim = centre + rng.uniform(-1.9, 1.9, (20_000, 1, 2)) + rng.uniform(-0.01, 0.01, (20_000, 3, 2))
    corners = np.concatenate([focus, ring, dim])
    irradiance = np.concatenate([np.full((len(focus), 3), 1e4), np.full((len(ring), 3), 100.0),
                                 np.full((len(dim), 3), 1e-3)])
    imap.add_beams(corners, irradiance)
    half = 0.015
    for x, y in ((0.502, 0.0), (0.0, 0.502), (-0.502, 0.0), (0.0, -0.502)):
        lo, hi = centre + np.array([[x - half, y - half]]), centre + np.array([[x + half, y + half]])
        # the ring's strip across the box, as good as straight
        assert imap.mean_over(lo, hi)[0, 0] == pytest.approx(100.0 * 0.004 / (2.0 * half), rel=0.05)


def test_the_galloping_search_finds_what_a_binary_search_finds_from_any_hint():
    """The beam grid looks landings up from where the last element's were
    (beam_grid._search_from): any hint, before, after or off the ends,
    gives numpy's searchsorted position, on runs of equal keys too."""
    from caustic_addon.passes.beam_grid import _search_from

    rng = np.random.default_rng(5)
    for size in (0, 1, 2, 7, 300):
        keys = np.sort(rng.integers(0, 40, size))
        for key, hint in zip(rng.integers(-2, 43, 200), rng.integers(-3, size + 4, 200)):
            assert _search_from(keys, key, hint) == np.searchsorted(keys, key), (size, key, hint)
