"""Scene handling: both emission modes agree, all lamp types light the
floor, progress and cancel work, bad scenes are named, odd meshes warned."""

import math
from dataclasses import replace

import numpy as np
import pytest

from caustic_addon import (Camera, Cancelled, Dielectric, Diffuse, MapCache, Mesh, Object, PointLight,
                           RenderSettings, Scene, SceneError, SpotLight, SunLight, render, shapes)
from caustic_addon.maps.cache import lamp_pass_key, scene_digest
from caustic_addon.tracing.topology import open_edge_count, signed_volume, triangle_normals
from benchmarks.references.metrics import annulus_means, annulus_points, relative_l2
from scenes import ball_lens, quick, shadow_radius


def test_targeted_and_sphere_emission_agree():
    """Targeted emission only skips directions that miss the glass: the
    caustic it estimates is the paper's full-sphere one, at a fraction of the photons."""
    scene = ball_lens(pixels=8)
    r_edges = np.linspace(0.0, shadow_radius(), 41)
    xy = annulus_points(r_edges, 200)

    def profile(settings):
        return annulus_means(render(scene, settings).maps["Floor"].irradiance_at(xy)[:, 0], r_edges)

    targeted = profile(quick(lamp_rays=300_000))
    sphere = profile(quick(lamp_rays=300_000 * 20, emission="sphere"))
    assert relative_l2(targeted, sphere, r_edges) < 0.05


@pytest.mark.parametrize("light", [
    SpotLight((0, 0, 6), (0, 0, -1), 1000.0, spot_size=math.radians(60), blend=0.1),
    SunLight((0, 0, -1), 5.0),
])
def test_spot_and_sun_make_a_caustic_too(light):
    scene = ball_lens(pixels=32)
    scene.lights = [light]
    result = render(scene, quick(lamp_rays=200_000))
    floor = result.maps["Floor"].irradiance_at(np.zeros((1, 2)))[0, 0]
    if isinstance(light, SunLight):
        unobstructed = light.strength
    else:
        unobstructed = light.power / (4 * math.pi) / 36.0
    assert floor > 3 * unobstructed
    assert np.isfinite(result.image).all()


def test_sun_direct_light_is_its_strength():
    scene = ball_lens(pixels=16)
    scene.objects = scene.objects[:1]
    scene.lights = [SunLight((0, 0, -1), 2.0)]
    result = render(scene, quick())
    np.testing.assert_allclose(result.image[..., :3], 2.0 / math.pi, rtol=1e-5)


def test_progress_reaches_the_end_and_cancel_stops():
    scene = ball_lens(pixels=32)
    seen = []
    render(scene, quick(lamp_rays=100_000, chunk_size=8192), progress=lambda f, stage: seen.append((f, stage)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert {stage for _, stage in seen} == {"photon pass", "eye pass"}
    with pytest.raises(Cancelled):
        render(scene, quick(lamp_rays=100_000, chunk_size=8192), cancel=lambda: True)


def broken(**changes):
    scene = ball_lens(pixels=8)
    glass = scene.objects[1]
    for key, value in changes.items():
        if key == "ior":
            glass.material = Dielectric(value)
        elif key == "vertices":
            glass.mesh.vertices[3] = value
        elif key == "empty":
            glass.mesh = Mesh(glass.mesh.vertices, np.zeros((0, 3), int))
        elif key == "power":
            scene.lights = [PointLight((0, 0, 6), value, name="Lamp")]
        elif key == "absorption":
            glass.material = Dielectric(1.5, absorption=value)
        elif key == "albedo":
            scene.objects[0].material = Diffuse(albedo=value)
        elif key == "uv":
            scene.objects[0].mesh.corner_uvs[0, 0] = value
    return scene


@pytest.mark.parametrize("changes, message", [
    (dict(ior=0.0), "Glass: IOR must be a positive number"),
    (dict(ior=float("nan")), "Glass: IOR must be a positive number"),
    (dict(vertices=[np.nan, 0, 0]), r"Glass: its vertex 3 is not a finite point \(nan, 0, 0\)"),
    (dict(vertices=[0, 0, np.inf]), r"Glass: its vertex 3 is not a finite point \(0, 0, inf\)"),
    (dict(vertices=[0, 0, 1e30]), r"'Glass' reaches 1e\+30 m from the rest of the scene, which is 23 m across "
                                  r"\(its vertex 3 at \(0, 0, 1e\+30\)\): the tracing's precision follows"),
    (dict(power=1e300), r"light 'Lamp': its power of 1e\+300 W \(times its color\) is past the 1e\+30"),
    (dict(empty=True), "Glass: the mesh has no triangles"),
    (dict(power=-5.0), "light 'Lamp': its power must be"),
    (dict(absorption=[np.nan, 0.0, 0.0]), "Glass: its absorption contains NaN"),
    (dict(albedo=[0.5, np.inf, 0.5]), "Floor: its color contains NaN or infinite"),
    (dict(uv=[np.nan, 0.0]), "Floor: its UV map contains NaN"),
])
def test_bad_scenes_name_the_culprit(changes, message):
    with pytest.raises(SceneError, match=message):
        render(broken(**changes), quick(lamp_rays=1000))


@pytest.mark.parametrize("field, value", [("lamp_rays", -1), ("spp", 0), ("map_scale", -2.0), ("emission", "cone")])
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        render(ball_lens(pixels=8), RenderSettings(**{field: value}))


def test_open_and_inverted_meshes_are_reported():
    scene = ball_lens(pixels=8)
    glass = scene.objects[1].mesh
    scene.objects[1].mesh = Mesh(glass.vertices, glass.triangles[:, ::-1], -glass.corner_normals[:, ::-1])
    assert any("inverted normals" in w for w in render(scene, quick(lamp_rays=10_000)).warnings)
    scene.objects[1].mesh = Mesh(glass.vertices, glass.triangles[10:], glass.corner_normals[10:])
    assert any("not a closed mesh" in w for w in render(scene, quick(lamp_rays=10_000)).warnings)


def test_inverted_normals_render_like_the_right_ones():
    scene = ball_lens(pixels=16)
    right = render(scene, quick()).image
    glass = scene.objects[1].mesh
    scene.objects[1].mesh = Mesh(glass.vertices, glass.triangles[:, ::-1], -glass.corner_normals[:, ::-1])
    flipped = render(scene, quick()).image
    np.testing.assert_allclose(flipped, right, rtol=1e-3)  # Embree's float32 rounding follows the winding


def test_a_curved_receiver_collects_caustics_through_its_uvs():
    """A floor bent into a shallow trough, with UVs: it gets a map through its
    UV chart, and the flux landed equals the flux of the flat floor within noise."""
    flat = ball_lens(pixels=8)
    n = 64
    xs = np.linspace(-4, 4, n + 1)
    gx, gy = np.meshgrid(xs, xs)
    gz = 0.02 * gx ** 2
    verts = np.stack([gx, gy, gz], -1).reshape(-1, 3)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    uv = (np.stack([gx, gy], -1).reshape(-1, 2) + 4) / 8
    trough = Scene([Object("Floor", Mesh(verts, tris, corner_uvs=uv[tris]), Diffuse()), flat.objects[1]],
                   flat.lights, flat.camera)
    curved = render(trough, quick(lamp_rays=200_000))
    assert "Floor" in curved.maps
    landed = curved.maps["Floor"].flux.sum()
    assert landed == pytest.approx(render(flat, quick(lamp_rays=200_000)).maps["Floor"].flux.sum(), rel=0.02)


def test_a_camera_move_reuses_the_illumination_maps():
    """With a cache, a second render that changes only the camera or the eye
    pass skips the photon pass and gives the image a fresh render gives;
    changing the lamp, the glass or the photon settings traces again."""
    cache = MapCache()
    scene = ball_lens(pixels=16)
    first = render(scene, quick(lamp_rays=50_000), cache=cache)
    assert not first.stats["maps_cached"]

    scene.camera.matrix[0, 3] += 0.3
    moved = render(scene, quick(lamp_rays=50_000, spp=4), cache=cache)
    assert moved.stats["maps_cached"] and moved.stats["rays_lamp_pass"] == 0
    np.testing.assert_allclose(moved.image, render(scene, quick(lamp_rays=50_000, spp=4)).image, rtol=1e-6)

    scene.lights = [PointLight((0, 0, 6), 500.0)]
    assert not render(scene, quick(lamp_rays=50_000), cache=cache).stats["maps_cached"]
    scene.objects[1].material = Dielectric(1.33)
    assert not render(scene, quick(lamp_rays=50_000), cache=cache).stats["maps_cached"]
    assert not render(scene, quick(lamp_rays=60_000), cache=cache).stats["maps_cached"]
    # the band count matters only once a material disperses
    assert render(scene, quick(lamp_rays=60_000, bands=3), cache=cache).stats["maps_cached"]
    scene.objects[1].material = Dielectric(1.33, abbe=55.7)
    assert not render(scene, quick(lamp_rays=60_000, bands=3), cache=cache).stats["maps_cached"]
    assert not render(scene, quick(lamp_rays=60_000, bands=4), cache=cache).stats["maps_cached"]


def test_the_cache_holds_one_fewer_scene_while_a_new_one_traces_and_keeps_the_same_ones_after():
    """An animation misses the cache at every frame: the frame being traced
    is held beside one fewer than the cache keeps (65 MB a map set in the
    animated pool), and after `put` the cache holds what it held before."""
    cache = MapCache(capacity=2)
    cache.put("frame 1", "maps 1")
    cache.put("frame 2", "maps 2")
    cache.make_room("frame 3")
    assert cache.get("frame 1") is None and cache.get("frame 2") == "maps 2"
    cache.put("frame 3", "maps 3")
    assert [cache.get(key) for key in ("frame 2", "frame 3")] == ["maps 2", "maps 3"]
    # a kept scene traced again (its beams cannot serve the new camera) drops only its own old maps
    cache.make_room("frame 2")
    assert cache.get("frame 2") is None and cache.get("frame 3") == "maps 3"
    # the add-on's cache keeps the last scene only: none is held while another traces
    last = MapCache()
    last.put("frame 1", "maps 1")
    last.make_room("frame 2")
    assert last.get("frame 1") is None


def test_a_cache_with_a_byte_budget_keeps_the_newest_maps_that_fit():
    """Live's cache keeps many scenes' maps, the least recently used
    dropped first once they hold more than its bytes; the newest always
    stays. A bake of kept maps builds no BVH."""
    scene = ball_lens(pixels=16)
    bake = quick(lamp_rays=20_000, density="beam", eye_pass=False)
    one = render(scene, bake, cache=MapCache()).maps["Floor"].nbytes
    cache = MapCache(capacity=100, max_bytes=int(2.5 * one))
    for height in (2.0, 2.1, 2.2):
        scene.objects[1].mesh = shapes.uv_sphere(0.5, (0.0, 0.0, height), 32, 16)
        assert not render(scene, bake, cache=cache).stats["maps_cached"]
    assert cache.nbytes <= 2.5 * one
    again = render(scene, bake, cache=cache)
    assert again.stats["maps_cached"] and "bvh" not in again.stats["seconds"]
    scene.objects[1].mesh = shapes.uv_sphere(0.5, (0.0, 0.0, 2.1), 32, 16)
    assert render(scene, bake, cache=cache).stats["maps_cached"]
    scene.objects[1].mesh = shapes.uv_sphere(0.5, (0.0, 0.0, 2.0), 32, 16)
    assert not render(scene, bake, cache=cache).stats["maps_cached"]
    # a caller that knows the key (Live, which tries two settings) gives it; one scene digest serves both
    digest = scene_digest(scene)
    assert lamp_pass_key(scene, bake, digest) == lamp_pass_key(scene, bake)
    assert lamp_pass_key(scene, replace(bake, lamp_rays=10_000), digest) != lamp_pass_key(scene, bake)
    assert render(scene, bake, cache=cache, key=lamp_pass_key(scene, bake, digest)).stats["maps_cached"]


def test_the_wavy_slab_is_closed_faces_out_and_holds_its_volume():
    """Its height field over [-1, 1]^2 integrates in closed form: depth plus
    a cos(k.x) integrates to a sin(kx L/2) sin(ky L/2) (2 / kx)(2 / ky)."""
    waves = ((0.02, 0.5, 0.3), (0.015, 0.37, 1.1))
    mesh = shapes.wavy_slab(2.0, 0.3, waves, cells=256)
    assert open_edge_count(mesh.triangles, mesh.vertices) == 0
    exact = 4.0 * 0.3
    for amplitude, wavelength, angle in waves:
        kx, ky = 2 * math.pi / wavelength * math.cos(angle), 2 * math.pi / wavelength * math.sin(angle)
        exact += amplitude * (2 * math.sin(kx) / kx) * (2 * math.sin(ky) / ky)
    assert signed_volume(mesh.corners) == pytest.approx(exact, rel=1e-4)
    normals, _ = triangle_normals(mesh.corners)
    assert np.all(np.einsum("ij,ij->i", normals, mesh.corner_normals.mean(axis=1)) > 0.5)


def test_a_mesh_scaled_to_0_along_an_axis_keeps_the_faces_across_it():
    """The inverse transpose does not exist there: the cofactor matrix gives
    the faces that keep an area their normals, and those flattened to no
    area are dropped."""
    box = shapes.cylinder(1.0, 1.0, segments=16)
    flat = box.transformed(np.diag([2.0, 1.0, 0.0, 1.0]))
    caps = np.abs(box.corner_normals[:, 0, 2]) > 0.5
    assert len(flat.triangles) == caps.sum() > 0  # the walls are flattened to nothing, the caps stay
    assert np.isfinite(flat.corner_normals).all()
    np.testing.assert_allclose(np.abs(flat.corner_normals[..., 2]), 1.0)
    assert len(box.transformed(np.diag([0.0, 0.0, 0.0, 1.0])).triangles) == 0


def test_a_render_that_cannot_fit_in_memory_is_refused_up_front_with_the_number():
    """Memory does not grow with the lamp rays (every pass streams its
    chunks), so 50M of them fit where 100,000 do; a 100,000 x 100,000
    image does not, and is refused before anything is traced."""
    from caustic_addon.memory import needed_bytes, refusal

    scene = ball_lens(pixels=8)
    few, many = (sum(needed_bytes(scene, quick(lamp_rays=n, density="beam")).values()) for n in (100_000, 50_000_000))
    assert few == many < 2e9
    assert refusal(scene, quick(lamp_rays=50_000_000, density="beam"), memory=4e9) is None
    scene.camera = Camera.look_at((0, -6, 4), (0, 0, 0.6), pixx=100_000, pixy=100_000)
    with pytest.raises(SceneError, match=r"this render needs about 2,00\d\.\d GB of memory, more than this machine's "
                                         r"[\d,.]+ GB; 2,000.0 GB of it for the image: lower the resolution"):
        render(scene, quick(lamp_rays=1000))


# --- issue 40: huge values, degenerate casters, lamps on surfaces, a sun of 180 degrees -----------------------


@pytest.mark.parametrize("spoil, culprit", [
    (lambda scene: scene.objects.append(Object("Far", shapes.uv_sphere(0.5, (1e30, 0, 1), 16, 8), Dielectric(1.5))),
     r"'Far' reaches 1e\+30 m from the rest of the scene"),
    (lambda scene: scene.objects[0].mesh.vertices.__imul__(1e20), r"'Floor' reaches 5.66e\+20 m from the rest"),
    (lambda scene: scene.objects[0].mesh.vertices.__imul__(1e5), r"'Floor' reaches 5.66e\+05 m from the rest"),
], ids=["a ball 1e30 m away", "the floor scaled by 1e20", "the floor scaled by 1e5"])
def test_an_object_that_would_black_out_the_rest_is_refused_by_name(spoil, culprit):
    """The tracing's epsilon follows the scene's size: one object far away,
    or huge, made every pixel black, the lit floor included (issue 40)."""
    scene = ball_lens(pixels=8)
    spoil(scene)
    with pytest.raises(SceneError, match=culprit + r".*: the tracing's precision follows the whole scene's size, "
                                                   "so the rest would render black or wrong"):
        render(scene, quick(lamp_rays=1000))


def test_an_object_a_thousand_times_the_rest_renders_with_a_warning():
    scene = ball_lens(pixels=8)
    scene.objects[0].mesh.vertices[:] *= 6000.0  # the rest: the ball, and the camera 20 m above the floor
    warnings = render(scene, quick(lamp_rays=1000)).warnings
    assert [w for w in warnings if w.startswith("'Floor' reaches 3.39e+04 m from the rest of the scene") and
            "3.45e+03 times the rest's, so light on the rest may move by a percent or so" in w]


def test_a_single_object_past_float32_s_arithmetic_names_its_vertex():
    scene = ball_lens(pixels=8)
    scene.objects = scene.objects[:1]
    scene.objects[0].mesh.vertices[2] = [0.0, 0.0, 1e30]
    with pytest.raises(SceneError, match=r"Floor: its vertex 2 lies at \(0, 0, 1e\+30\), past the 1e\+18 m"):
        render(scene, quick(lamp_rays=1000))


def test_glass_with_no_area_is_named():
    scene = ball_lens(pixels=8)
    scene.objects[1] = Object("Glass", Mesh(np.array([[0, 0, 1.0], [1, 0, 1.0], [2, 0, 1.0]]), np.array([[0, 1, 2]])),
                              Dielectric(1.5))
    warnings = render(scene, quick(lamp_rays=1000)).warnings
    assert warnings == ["'Glass' has no area (each of its faces is a line or a point): it casts no caustics and "
                        "shows nothing"]


def test_a_lamp_on_the_receiver_is_named_and_one_just_above_it_casts_its_caustic():
    """A lamp exactly on the floor's plane cast nothing, 0.1 mm above it the
    full caustic: its rays start on the floor and meet it at t = 0."""
    def lamp_at(z):
        scene = ball_lens(pixels=16)
        scene.objects[1] = Object("Glass", shapes.uv_sphere(0.5, (1.0, 0, 0.6), 32, 16), Dielectric(1.5))
        scene.lights = [PointLight((0, 0, z), 100.0, name="Lamp")]
        scene.camera = Camera.look_at((0, -6, 5), (1.5, 0, 0), pixx=16, pixy=16)
        return render(scene, quick(lamp_rays=20_000))

    on, above = lamp_at(0.0), lamp_at(1e-4)
    assert [w for w in on.warnings if w.startswith("light 'Lamp' lies on 'Floor' (within the tracing epsilon")]
    assert not [w for w in above.warnings if "lies on" in w]
    assert above.stats["landed"] > 1000


def test_a_sun_of_180_degrees_renders_as_one_of_179():
    """Blender allows a sun's angle up to 180 degrees (a hemisphere of
    directions); the disc its rays cross would widen without end."""
    def sun(degrees):
        scene = ball_lens(pixels=16, segments=32)
        scene.lights = [SunLight((0, 0, -1), 3.0, angle=math.radians(degrees))]
        return render(scene, quick(lamp_rays=100_000))

    wide, widest = sun(179.0), sun(180.0)
    assert np.isfinite(widest.image).all() and widest.passes["caustic"].mean() > 0
    for name in ("direct", "caustic"):
        assert abs(widest.passes[name].mean() / wide.passes[name].mean() - 1.0) < 0.1, name


def test_open_edges_are_counted_and_placed():
    scene = ball_lens(pixels=8, segments=32)
    glass = scene.objects[1].mesh
    scene.objects[1].mesh = Mesh(glass.vertices, glass.triangles[1:], glass.corner_normals[1:])
    warnings = render(scene, quick(lamp_rays=1000)).warnings
    assert [w for w in warnings if w.startswith("'Glass' is not a closed mesh (3 edges have one face or more than two")]


def test_open_edges_of_a_moved_mesh_and_of_a_changed_one():
    """open_edges keeps its answers by which vertices coincide and the
    triangles: a moved sphere (split at its seam, so vertices coincide) is
    still closed, and the same sphere with a triangle taken out is not."""
    sphere = shapes.uv_sphere(1.0, (0.0, 0.0, 0.0), 16, 8)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    for vertices in (sphere.vertices, sphere.vertices @ turn.T + (3.0, -2.0, 0.5), sphere.vertices * 2.0):
        assert open_edge_count(sphere.triangles, vertices) == 0
    opened = sphere.triangles[1:]
    assert open_edge_count(opened, sphere.vertices) == 3
    assert open_edge_count(opened, sphere.vertices @ turn.T) == 3
    assert open_edge_count(sphere.triangles, sphere.vertices) == 0
