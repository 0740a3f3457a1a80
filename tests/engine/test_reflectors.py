"""Reflective caustics: mirrors and metals as casters, against closed-form
geometric optics (the paper's r = i - 2 (i.n) n applied to opaque mirrors)."""

import math

import numpy as np
import pytest

from caustic_addon import Camera, Dielectric, Diffuse, Mesh, Object, PointLight, Reflector, Scene, SunLight, render
from caustic_addon import shapes
from caustic_addon.emission.aims import casters_and_bounds
from caustic_addon.emission.photons import make_emitters
from scenes import quick, top_camera

POWER = 1000.0
INTENSITY = POWER / (4 * math.pi)


def rectangle(center, half_u, half_v) -> Mesh:
    """A flat rectangle of corners center +- half_u +- half_v (each (3,) world), no UVs."""
    c, u, v = (np.asarray(a, dtype=np.float64) for a in (center, half_u, half_v))
    return Mesh(np.array([c - u - v, c + u - v, c + u + v, c - u + v]), np.array([[0, 1, 2], [0, 2, 3]]))


def box_means(imap, boxes: np.ndarray) -> np.ndarray:
    """Mean caustic irradiance (red) of `imap` over chart boxes (n,2,2) [[lo], [hi]]."""
    return imap.mean_over(boxes[:, 0], boxes[:, 1])[:, 0]


def exact_box_means(field, boxes: np.ndarray, samples: int = 200) -> np.ndarray:
    """Means of `field(xy (m,2)) -> (m,)` over each box, on a fine midpoint lattice."""
    t = (np.arange(samples) + 0.5) / samples
    a, b = (g.ravel() for g in np.meshgrid(t, t))
    out = []
    for lo, hi in boxes:
        out.append(field(np.stack([lo[0] + a * (hi[0] - lo[0]), lo[1] + b * (hi[1] - lo[1])], axis=1)).mean())
    return np.array(out)


# A ceiling mirror over a lamp: the floor sees the lamp's image at 2c - h.
CEILING, LAMP_Z, RHO = 3.0, 1.0, 0.7


def ceiling_mirror(glass_slab: bool = False, tint: float = 1.0) -> Scene:
    """A square mirror (2 m, reflectance RHO) at z = CEILING over a point lamp at
    z = LAMP_Z above an 8 m floor. With `glass_slab`, an index-matched (n = 1,
    so F = 0 and no bending) closed glass slab of colour `tint` lies between
    lamp and mirror: light crosses it, reflects, and crosses it again."""
    objects = [Object("Floor", shapes.plane(8.0), Diffuse(albedo=1.0)),
               Object("Mirror", shapes.plane(2.0, (0, 0, CEILING)), Reflector(RHO))]
    if glass_slab:
        slab = shapes.cylinder(2.5, 0.4, (0, 0, 2.0), segments=64)
        objects.append(Object("Slab", slab, Dielectric(1.0, transmission_tint=tint)))
    return Scene(objects, [PointLight((0, 0, LAMP_Z), POWER)], top_camera(2.0, 8))


def mirrored_lamp_irradiance(xy: np.ndarray) -> np.ndarray:
    """E = rho I h' / r'^3 on the floor from the lamp's mirror image at
    height h' = 2c - h (exact while the line to the image crosses the mirror:
    |x|, |y| < h' / (h' - c) m = 2.5 m here)."""
    image = 2 * CEILING - LAMP_Z
    return RHO * INTENSITY * image / ((xy ** 2).sum(axis=1) + image ** 2) ** 1.5


BOXES = np.array([[[-0.2, -0.2], [0.2, 0.2]], [[0.6, -0.2], [1.0, 0.2]], [[-1.8, 1.0], [-1.2, 1.6]],
                  [[1.5, 1.5], [2.2, 2.2]]])


def photon_tolerance(result, exact: np.ndarray) -> np.ndarray:
    """4 standard deviations of a box mean estimated from M photons, 1/sqrt(M),
    with M the box's share of the landed photons; plus the bilinear splat's
    spill over the box edges (half a 20 mm cell against the box's side)."""
    areas = np.prod(BOXES[:, 1] - BOXES[:, 0], axis=1)
    photons = result.stats["landed"] * exact * areas / result.stats["flux_landed_w"][0]
    return 4.0 / np.sqrt(photons) + 0.01 / (BOXES[:, 1, 0] - BOXES[:, 0, 0])


def test_flat_mirror_lights_the_floor_as_the_mirrored_lamp():
    result = render(ceiling_mirror(), quick(lamp_rays=400_000, density="splat", map_scale=20.0))
    exact = exact_box_means(mirrored_lamp_irradiance, BOXES)
    ours = box_means(result.maps["Floor"], BOXES)
    np.testing.assert_array_less(np.abs(ours / exact - 1.0), photon_tolerance(result, exact))


def test_glass_then_mirror_then_glass_multiplies_the_tints():
    """Each photon crosses the slab, reflects, and crosses it again (four
    glass events and one mirror bounce in one path): the floor sees tint^4 of
    the mirrored lamp."""
    tint = 0.9
    result = render(ceiling_mirror(glass_slab=True, tint=tint), quick(lamp_rays=400_000, density="splat",
                                                                       map_scale=20.0))
    exact = tint ** 4 * exact_box_means(mirrored_lamp_irradiance, BOXES)
    ours = box_means(result.maps["Floor"], BOXES)
    np.testing.assert_array_less(np.abs(ours / exact - 1.0), photon_tolerance(result, exact))


def test_beams_off_a_mirror_match_the_mirrored_lamp():
    """Beams have no noise; what is left is their rasterisation, under 3%
    over boxes a few hundred beams wide."""
    result = render(ceiling_mirror(glass_slab=True, tint=0.9), quick(lamp_rays=40_000, density="beam"))
    exact = 0.9 ** 4 * exact_box_means(mirrored_lamp_irradiance, BOXES)
    np.testing.assert_allclose(box_means(result.maps["Floor"], BOXES), exact, rtol=0.03)


def test_reflectors_cast_shadows_and_are_seen_in_the_eye_pass():
    """An orthographic camera between floor and mirror looks up: each pixel
    sees the floor point under it in the mirror. Its direct light (computed
    exactly) is rho * albedo / pi * I h / r^3 of the lamp; the mirror, opaque
    to shadow rays, leaves the floor outside it lit only where the lamp sees it."""
    scene = ceiling_mirror()
    matrix = np.diag([1.0, -1.0, -1.0, 1.0])
    matrix[2, 3] = 2.0
    scene.camera = Camera(matrix, pixx=16, pixy=16, kind="ORTHO", ortho_scale=1.6)
    result = render(scene, quick(lamp_rays=50_000, spp=1))
    step = 1.6 / 16
    ticks = (np.arange(16) + 0.5) * step - 0.8
    x, y = np.meshgrid(ticks, -ticks)  # row 0 at the top is camera +Y, world -y
    r2 = x ** 2 + y ** 2 + LAMP_Z ** 2
    exact = RHO * (1.0 / math.pi) * INTENSITY * LAMP_Z / r2 ** 1.5
    np.testing.assert_allclose(result.passes["direct"][..., 0], exact, rtol=1e-4)

    # the mirror shadows a floor lit by a lamp above it
    above = Scene([Object("Floor", shapes.plane(8.0), Diffuse(albedo=1.0)),
                   Object("Mirror", shapes.plane(1.0, (0, 0, 1.0)), Reflector(RHO))],
                  [PointLight((0, 0, 3.0), POWER)], top_camera(2.0, 16))
    direct = render(above, quick(lamp_rays=1000, spp=1)).passes["direct"][..., 0]
    # columns 5 and 10 see the floor at |x| = 0.625: past the mirror's edge, inside its shadow (0.75)
    assert direct[7:9, [5, 10]].max() == 0.0 and direct[7:9, [3, 12]].min() > 0.0


# The coffee-cup analogue: a point lamp above the rim inside a mirror tube.
R, H, D, HEIGHT, TUBE_RHO = 1.0, 1.0, 0.6, 2.5, 0.8


def mirror_tube() -> Scene:
    return Scene([Object("Floor", shapes.plane(3.0), Diffuse(albedo=1.0)),
                  Object("Tube", shapes.tube(R, H, segments=512), Reflector(TUBE_RHO))],
                 [PointLight((D, 0, HEIGHT), POWER)], top_camera(1.5, 8))


def reflected_lines(phi: np.ndarray):
    """Float64 2D rays in the horizontal plane from the lamp's foot (D, 0) along
    angles `phi (n,)`, reflected off the inside of the circle of radius R:
    (wall points Q (n,2), reflected unit directions (n,2), distances to the wall (n,))."""
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    b = u[:, 0] * D
    dist = -b + np.sqrt(b * b - (D * D - R * R))
    q = np.array([D, 0.0]) + dist[:, None] * u
    n = q / R
    return q, u - 2.0 * (u * n).sum(axis=1)[:, None] * n, dist


def envelope(phi: np.ndarray) -> np.ndarray:
    """(n,2) points of the 2D caustic: where each reflected line meets its neighbour."""
    q1, r1, _ = reflected_lines(phi)
    q2, r2, _ = reflected_lines(phi + 1e-7)
    ab = np.linalg.solve(np.stack([r1, -r2], axis=-1), (q2 - q1)[..., None])[..., 0]
    return q1 + ab[:, :1] * r1


def test_tube_cusp_formula_matches_a_float64_ray_computation():
    """The mirror equation 1/s + 1/s' = 2/R for the far wall, s = R + D, puts
    the paraxial focus (the caustic's cusp) at x = -R + s' = -R D / (2D + R):
    on the axis, beyond the centre along the light's horizontal direction (R/2
    as D goes to infinity: the coffee cup's nephroid). A wall at radius R that
    reflects as a cylinder flips only the horizontal part of each ray, so on
    the floor the caustic is this 2D one of the lamp's foot."""
    cusp = -R * D / (2 * D + R)
    for delta in (1e-3, 1e-4):
        points = envelope(np.array([math.pi + delta]))
        assert points[0] == pytest.approx([cusp, 0.0], abs=10 * delta ** 2)


def assert_cusp_resolved(imap, cusp: float, fold: np.ndarray) -> None:
    """The caustic's two folds meet at the cusp (cusp, 0) and close as
    |y| ~ (cusp - x)^(3/2) toward -x (`fold (n,2)`, float64 points of one
    fold, leaving the cusp). An estimate that resolves a width w sees its
    peak along the axis between the cusp and the point where the folds are
    w apart, here w = 2 map cells; across the axis, on it."""
    w = 2.0 * imap.cell
    merged = fold[np.argmax(np.abs(fold[:, 1]) > 0.5 * w), 0]
    x = np.linspace(-0.6, 0.0, 601)
    along = imap.irradiance_at(np.stack([x, np.zeros_like(x)], axis=1))[:, 0]
    peak = x[along.argmax()]
    assert merged - imap.cell <= peak <= cusp + imap.cell
    y = np.linspace(-0.1, 0.1, 201)
    across = imap.irradiance_at(np.stack([np.full_like(y, peak), y], axis=1))[:, 0]
    assert abs(y[across.argmax()]) <= imap.cell
    assert along.max() > 2.0 * along[x > 0.5 * cusp].max()


@pytest.mark.parametrize("settings", [dict(lamp_rays=1_000_000), dict(lamp_rays=100_000, density="beam")],
                         ids=["photons", "beams"])
def test_mirror_tube_nephroid_cusp_lands_where_geometric_optics_puts_it(settings):
    """Every downward ray from the lamp, at height 2.5 >= 2H, meets the wall
    at most once (a chord's drop exceeds the rim's height); the cusp is at
    x_c = -R D / (2D + R)."""
    result = render(mirror_tube(), quick(**settings))
    assert_cusp_resolved(result.maps["Floor"], -R * D / (2 * D + R), envelope(math.pi + np.linspace(1e-4, 0.3, 3000)))


def test_parallel_light_in_a_mirror_tube_has_its_cusp_at_half_the_radius():
    """A sun whose light travels along -x (and down, 0.4 m per metre) over the
    rim of a tube of height 0.5: the coffee cup's nephroid, cusp at R/2 from
    the centre along the light's horizontal direction. The fold, in float64:
    the line of a ray at height b reflected at (-sqrt(R^2 - b^2), b), met by
    its neighbour."""
    slope = 0.4
    sun = SunLight((-1.0, 0.0, -slope), 10.0)
    scene = Scene([Object("Floor", shapes.plane(3.0), Diffuse(albedo=1.0)),
                   Object("Tube", shapes.tube(R, 0.5, segments=512), Reflector(TUBE_RHO))], [sun], top_camera(1.5, 8))
    result = render(scene, quick(lamp_rays=1_000_000))

    def lines(b):
        q = np.stack([-np.sqrt(R * R - b * b), b], axis=1)
        n = q / R
        u = np.array([-1.0, 0.0])
        return q, u - 2.0 * (n @ u)[:, None] * n

    b = np.linspace(1e-4, 0.3, 3000)
    (q1, r1), (q2, r2) = lines(b), lines(b + 1e-7)
    ab = np.linalg.solve(np.stack([r1, -r2], axis=-1), (q2 - q1)[..., None])[..., 0]
    fold = q1 + ab[:, :1] * r1
    assert fold[0] == pytest.approx([-R / 2, 0.0], abs=1e-6)
    assert_cusp_resolved(result.maps["Floor"], -R / 2, fold)


@pytest.mark.parametrize("density", ["adaptive", "beam"])
def test_flux_off_the_tube_is_the_flux_on_its_wall_times_the_reflectance(density):
    """Flux reaching the wall: I times the solid angle of directions that
    meet it between z = 0 and H, I sum over phi of [cos theta] between
    tan theta = D(phi)/h and D(phi)/(h - H), D(phi) the distance to the wall.
    Every such ray lands on the floor after one reflection. Photons: within
    4/sqrt(landed); beams: each grid triangle cut by the wall's edges is
    shared out approximately, about sqrt(N) of N triangles, so 1/sqrt(N)."""
    phi = (np.arange(400_000) + 0.5) / 400_000 * 2 * math.pi
    _, _, dist = reflected_lines(phi)
    h, low = HEIGHT, HEIGHT - H
    on_wall = INTENSITY * 2 * math.pi * np.mean(h / np.hypot(h, dist) - low / np.hypot(low, dist))
    result = render(mirror_tube(), quick(lamp_rays=200_000, density=density))
    landed = result.stats["flux_landed_w"][0]
    stats = result.stats
    tolerance = (1.0 / math.sqrt(stats["lamp_rays"]) if density == "beam"
                 else 4.0 / math.sqrt(stats["landed"]))
    assert landed == pytest.approx(TUBE_RHO * on_wall, rel=tolerance)


# Two parallel mirrors: a corridor of width W and height CORRIDOR_H with a floor
# between them, lit by a sun whose rays cross the corridor 64 times on the way down.
W, CORRIDOR_H, LENGTH, BOUNCES = 0.2, 2.0, 1.0, 64


def corridor(rho: float) -> tuple[Scene, float]:
    """(scene, flux entering the opening): S cos(theta) W LENGTH."""
    tan = BOUNCES * W / CORRIDOR_H
    theta = math.atan(tan)
    sun = SunLight((math.sin(theta), 0.0, -math.cos(theta)), 10.0)
    walls = [Object(f"Mirror{k}", rectangle((s * W / 2, 0, CORRIDOR_H / 2), (0, LENGTH / 2, 0),
                                            (0, 0, CORRIDOR_H / 2)), Reflector(rho))
             for k, s in enumerate((-1, 1))]
    floor = Object("Floor", rectangle((0, 0, 0), (W / 2, 0, 0), (0, LENGTH / 2, 0)), Diffuse(albedo=1.0))
    return Scene([floor] + walls, [sun], top_camera(1.0, 8)), 10.0 * math.cos(theta) * W * LENGTH


def entering_photons(scene: Scene, photons: int) -> tuple[int, float]:
    """(count, flux) of the emitted photons whose rays cross the corridor's
    opening (z = CORRIDOR_H, |x| < W/2, |y| < LENGTH/2), from the render's own emitters."""
    emitters = make_emitters(scene.lights, *casters_and_bounds(scene), "targeted", 1.0, photons, 0)
    count, flux = 0, 0.0
    for emitter in emitters:
        batch = emitter.emit(0, emitter.count)
        t = (CORRIDOR_H - batch.origins[:, 2]) / batch.dirs[:, 2]
        at = batch.origins + t[:, None] * batch.dirs
        inside = (np.abs(at[:, 0]) < W / 2) & (np.abs(at[:, 1]) < LENGTH / 2)
        count += int(inside.sum())
        flux += float(batch.flux[inside, 0].sum())
    return count, flux


def test_64_bounces_between_parallel_mirrors_lose_and_create_no_photon():
    """Every photon that enters the opening lands, after 64 reflections, with
    the flux it left the sun with; one bounce fewer and none lands. (Each
    bounce restarts its ray epsilon off the wall, so a photon that meets the
    floor within 64 epsilon of a wall's foot takes a 65th bounce there:
    max_depth allows it.)"""
    scene, entering = corridor(1.0)
    result = render(scene, quick(lamp_rays=1_000_000, max_depth=BOUNCES + 1))
    stats = result.stats
    count, flux = entering_photons(scene, 1_000_000)
    assert count > 5000
    assert stats["landed"] == count
    assert stats["flux_landed_w"][0] == pytest.approx(flux, rel=1e-9)
    assert flux == pytest.approx(entering, rel=4.0 / math.sqrt(count))
    assert np.isfinite(result.maps["Floor"].irradiance()).all() and np.isfinite(result.image).all()
    short = render(scene, quick(lamp_rays=1_000_000, max_depth=BOUNCES - 1))
    assert short.stats["landed"] == 0


def test_dim_mirrors_keep_the_expected_flux_through_russian_roulette():
    """rho^64 = 1e-3: photons below 5% of their flux play Russian roulette.
    Survivors carry 5% of their starting flux, with probability
    p = rho^64 / 0.05, so the relative noise is sqrt((1 - p) / (p N))."""
    rho = 0.9
    scene, entering = corridor(rho)
    stats = render(scene, quick(lamp_rays=1_000_000, max_depth=BOUNCES + 1)).stats
    bright = render(corridor(1.0)[0], quick(lamp_rays=1_000_000, max_depth=BOUNCES + 1)).stats
    p = rho ** BOUNCES / 0.05
    noise = math.sqrt((1 - p) / (p * bright["landed"]))
    assert stats["flux_landed_w"][0] == pytest.approx(rho ** BOUNCES * bright["flux_landed_w"][0], rel=4 * noise)
