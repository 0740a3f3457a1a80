"""An instancer's instances of one mesh as one object (scene.Instances):
the copies' geometry against each copy transformed on its own, Embree's
instance arrays against the same triangles built flat, a render of
instanced glass against the same glass as separate objects, and a mesh's
BVH kept between renders while only its transform changes."""

import numpy as np

from caustic_addon import Dielectric, Diffuse, Mesh, Object, PointLight, Scene, render, shapes
from caustic_addon.tracing.accelerator import Accelerator
from caustic_addon.tracing.prototypes import PROTOTYPES, Prototypes
from scenes import quick, top_camera
from test_stress import box


def transforms(count: int, seed: int = 3) -> np.ndarray:
    """(count,4,4) random invertible affine matrices, every other one mirroring."""
    rng = np.random.default_rng(seed)
    out = np.tile(np.eye(4), (count, 1, 1))
    out[:, :3, :] = rng.normal(size=(count, 3, 4))
    det = np.linalg.det(out[:, :3, :3])
    out[:, :3, 0] *= (np.sign(det) * np.where(np.arange(count) % 2, -1.0, 1.0))[:, None]
    return out


def test_each_copy_is_the_mesh_transformed_on_its_own():
    rng = np.random.default_rng(1)
    local = Mesh(rng.normal(size=(6, 3)), np.array([[0, 1, 2], [2, 3, 4], [4, 5, 0]]), rng.normal(size=(3, 3, 3)),
                 rng.random((3, 3, 2)))
    matrices = transforms(5)
    copies = local.instanced(matrices)
    assert np.any(np.linalg.det(matrices[:, :3, :3]) < 0)
    for i, matrix in enumerate(matrices):
        alone, rows = local.transformed(matrix), slice(3 * i, 3 * i + 3)
        np.testing.assert_allclose(copies.corners[rows], alone.corners, atol=1e-12)
        np.testing.assert_allclose(copies.corner_normals[rows], alone.corner_normals, atol=1e-12)
        np.testing.assert_array_equal(copies.corner_uvs[rows], alone.corner_uvs)
    # the accelerator places each copy's triangles as it reads them, from one set of rows for all copies
    accel = Accelerator([Object.instanced("Copies", local, matrices, Diffuse(0.8))], 10.0, threads=1)
    assert accel.objects[0].mesh.corner_normals is None
    assert len(accel.triangles[0]) == len(local.triangles)
    prim = np.arange(len(copies.triangles))
    obj = np.zeros(len(prim), dtype=np.int64)
    np.testing.assert_allclose(accel.corner_points(obj, prim), copies.corners, atol=1e-12)
    cross = np.cross(copies.corners[:, 1] - copies.corners[:, 0], copies.corners[:, 2] - copies.corners[:, 0])
    np.testing.assert_allclose(accel.face_normals(obj, prim), cross / np.linalg.norm(cross, axis=1)[:, None],
                               atol=1e-12)
    # a copy's shading normal is its mesh's interpolant turned by M^-T, as Cycles turns an instance's
    u, v = rng.random(len(prim)) * 0.5, rng.random(len(prim)) * 0.5
    mirrored = np.repeat(np.linalg.det(matrices[:, :3, :3]) < 0.0, len(local.triangles))
    normals = np.tile(local.corner_normals, (len(matrices), 1, 1))
    normals[mirrored] = normals[mirrored, ::-1]  # a mirrored copy is wound the other way round
    blend = (1.0 - u - v)[:, None] * normals[:, 0] + u[:, None] * normals[:, 1] + v[:, None] * normals[:, 2]
    turned = np.einsum("kji,kj->ki", np.repeat(np.linalg.inv(matrices[:, :3, :3]), len(local.triangles), axis=0),
                       blend)
    np.testing.assert_allclose(accel.shading_normal(obj, prim, u, v),
                               turned / np.linalg.norm(turned, axis=1)[:, None], atol=1e-12)


def grid(count: int, spacing: float, z: float) -> np.ndarray:
    """(count^2,4,4) translations to a count x count grid at height `z`."""
    xs = (np.arange(count) - (count - 1) / 2) * spacing
    out = np.tile(np.eye(4), (count * count, 1, 1))
    out[:, 0, 3], out[:, 1, 3] = np.repeat(xs, count), np.tile(xs, count)
    out[:, 2, 3] = z
    return out


def test_a_ray_meets_the_copy_and_triangle_the_flat_mesh_puts_there():
    """Rays at 8 x 8 balls, every other one mirrored: the instance array's
    hits (object, global triangle, t, barycentrics) are those of the same
    triangles given to Embree flat, to float32's precision."""
    ball, matrices = shapes.uv_sphere(0.2, segments=16, rings=8), grid(8, 0.5, 1.0)
    matrices[::2, :3, 0] *= -1.0
    instanced = Object.instanced("Balls", ball, matrices, Dielectric(1.5))
    flat = Object("Balls", instanced.mesh, Dielectric(1.5))
    floor = Object("Floor", shapes.plane(6.0), Diffuse(0.8))
    rng = np.random.default_rng(5)
    origins = np.column_stack([rng.uniform(-2.0, 2.0, (20_000, 2)), np.full(20_000, 3.0)])
    dirs = rng.normal(size=(20_000, 3)) * [0.2, 0.2, 0.0] + [0.0, 0.0, -1.0]
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    hits = [Accelerator([floor, obj], 6.0, threads=1).intersect(origins, dirs) for obj in (instanced, flat)]
    on_balls = hits[1].obj == 1
    assert on_balls.mean() > 0.2
    np.testing.assert_array_equal(hits[0].obj, hits[1].obj)
    same = hits[0].prim == hits[1].prim
    assert same[on_balls].mean() > 0.999  # rays within float32 of an edge may take either face
    np.testing.assert_allclose(hits[0].t[same], hits[1].t[same], rtol=1e-5)
    np.testing.assert_allclose(hits[0].points[same], hits[1].points[same], atol=1e-5)
    met = same & (hits[1].obj >= 0)
    np.testing.assert_allclose(hits[0].u[met], hits[1].u[met], atol=1e-4)
    np.testing.assert_allclose(hits[0].v[met], hits[1].v[met], atol=1e-4)


def test_an_open_instanced_mesh_is_named_once():
    bowl = shapes.uv_sphere(0.2, segments=16, rings=8)
    bowl = bowl.subset(np.arange(len(bowl.triangles) // 2))
    accel = Accelerator([Object.instanced("Bowls", bowl, grid(3, 0.5, 1.0), Dielectric(1.5))], 6.0, threads=1)
    assert len([w for w in accel.warnings if "'Bowls' is not a closed mesh" in w]) == 1


def test_instanced_glass_renders_as_the_same_glass_in_separate_objects():
    """Four ball lenses as one instanced object and as four objects: the
    same caustics: the beams aim at one caster or at four, and agree to
    0.5%. The copies are never made in world space (geometry.Copies)."""
    ball, matrices = shapes.uv_sphere(0.4, segments=64, rings=32), grid(2, 1.2, 1.0)
    floor = Object("Floor", shapes.plane(8.0), Diffuse(0.8))
    lamp = [PointLight((0.0, 0.0, 4.0), 2000.0)]
    camera = top_camera(1.6, 64)
    together = Scene([floor, Object.instanced("Balls", ball, matrices, Dielectric(1.5))], lamp, camera)
    balls = [Object(f"Ball {i}", ball.transformed(matrix), Dielectric(1.5)) for i, matrix in enumerate(matrices)]
    apart = Scene([floor] + balls, lamp, camera)
    images = [render(scene, quick(lamp_rays=400_000, density="beam")).image for scene in (together, apart)]
    assert np.sqrt(np.mean((images[0] - images[1]) ** 2) / np.mean(images[1] ** 2)) < 0.005
    assert images[0].max() > 3.0 * np.median(images[0])  # the caustics are there
    # the render read the copies through the one mesh and the transforms, and never made them in world space
    assert "_made" not in vars(together.objects[1].mesh)


def moved(x: float, mirror: bool = False) -> np.ndarray:
    """(1,4,4) a translation by x along the x axis, mirrored in y if `mirror`."""
    out = np.eye(4)[None].copy()
    out[0, 0, 3], out[0, 1, 1] = x, -1.0 if mirror else 1.0
    return out


def test_a_mesh_that_only_moves_keeps_its_bvh_and_renders_as_if_built_anew():
    """The ball lens placed over one kept prototype at three places, one of
    them mirrored: one BVH built, the body found closed and facing out each
    time, and each render within float32's rounding of the ball built flat
    there."""
    PROTOTYPES.clear()
    built = PROTOTYPES.built
    ball = shapes.uv_sphere(1.0, (0.0, 0.0, 1.5), 64, 32)
    floor = Object("Floor", shapes.plane(8.0), Diffuse(0.8))
    lamp = [PointLight((0.3, 0.0, 6.0), 1000.0)]
    for x, mirror in ((0.0, False), (0.4, False), (0.4, True)):
        instanced = Object.instanced("Ball", ball, moved(x, mirror), Dielectric(1.5))
        flat = Object("Ball", ball.transformed(moved(x, mirror)[0]), Dielectric(1.5))
        images = [render(Scene([floor, obj], lamp, top_camera(2.0, 48)), quick(lamp_rays=40_000, density="beam"))
                  for obj in (instanced, flat)]
        assert not images[0].warnings
        error = np.sqrt(np.mean((images[0].image - images[1].image) ** 2) / np.mean(images[1].image ** 2))
        assert error < 1e-3, (x, mirror, error)
    assert PROTOTYPES.built == built + 1


def test_the_kept_prototypes_stay_within_their_triangles():
    kept = Prototypes(capacity_triangles=1_200)
    small, large = shapes.uv_sphere(1.0, segments=16, rings=8), shapes.uv_sphere(1.0, segments=32, rings=16)
    first = kept.of(small, "medium")
    assert kept.of(small, "medium") is first and kept.of(small, "high") is not first
    kept.of(large, "medium")
    assert kept.of(small, "medium") is not first and kept.built == 4


def test_a_thin_glass_that_only_moves_is_named_at_every_render_and_probed_once():
    """A slab thinner than the tracing epsilon, placed as an instance, is
    named wherever it moves; its prototype keeps the probes' answer by the
    placement's rotation and scale and the epsilon, so that moving it
    probes nothing again and turning it probes afresh; a slab thicker
    than the epsilon is named nowhere."""
    floor = Object("Floor", shapes.plane(10.0), Diffuse(0.8))
    epsilon = Accelerator([floor], 15.0).epsilon
    for thickness, named in ((0.5 * epsilon, True), (3.0 * epsilon, False)):
        PROTOTYPES.clear()
        slab = box((-1.0, -1.0, 1.0), (1.0, 1.0, 1.0 + thickness))
        turned = moved(0.0)
        turned[0, :3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        for placement in (moved(0.0), moved(0.5), moved(1.0), turned):
            accel = Accelerator([floor, Object.instanced("Slab", slab, placement, Dielectric(1.5))], 15.0)
            assert any("'Slab' is thinner than the tracing epsilon" in w for w in accel.warnings) == named
            assert accel.epsilon == epsilon
        assert len(PROTOTYPES.of(slab, accel.quality).thin) == 2
