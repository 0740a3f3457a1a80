"""Embree called from the kernels (tracing/embree.py): hits against the
closed form of a ray and a triangle, occlusion within a ray's length, and
kernels that call Embree cached on disk like any other."""

import numpy as np
import pytest
from test_kernels import compile_in_a_new_process

from caustic_addon import Diffuse, Mesh, Object
from caustic_addon.tracing import embree
from caustic_addon.tracing.accelerator import Accelerator

# A right triangle in the plane z = 1: corners (0,0), (2,0), (0,2).
TRIANGLE = Mesh(np.array([[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]]), np.array([[0, 1, 2]]))


def accelerator(*meshes: Mesh) -> Accelerator:
    return Accelerator([Object(f"Part {i}", mesh, Diffuse(0.8)) for i, mesh in enumerate(meshes)], 4.0, threads=1)


def test_a_ray_meets_the_triangle_where_the_closed_form_puts_it():
    """From (x, y, 3) straight down, the ray meets z = 1 at t = 2, with
    Embree's barycentrics u = x / 2, v = y / 2 (p = (1-u-v) p0 + u p1 + v p2)."""
    rng = np.random.default_rng(7)
    xy = rng.random((1000, 2)) * 2.0
    inside = xy.sum(axis=1) < 2.0
    origins = np.column_stack([xy, np.full(len(xy), 3.0)])
    dirs = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
    hits = accelerator(TRIANGLE).intersect(origins, dirs)
    margin = np.abs(xy.sum(axis=1) - 2.0) > 1e-5  # rays within float32 of the hypotenuse go either way
    assert np.array_equal(hits.hit[margin], inside[margin])
    np.testing.assert_allclose(hits.t[inside], 2.0, rtol=1e-6)
    np.testing.assert_allclose(hits.u[inside], xy[inside, 0] / 2.0, atol=1e-6)
    np.testing.assert_allclose(hits.v[inside], xy[inside, 1] / 2.0, atol=1e-6)
    np.testing.assert_allclose(hits.points[inside, :2], xy[inside], atol=1e-5)
    assert np.all(np.isinf(hits.t[~inside & margin]))
    np.testing.assert_array_equal(hits.points[~inside & margin], origins[~inside & margin])


def test_the_nearer_of_two_meshes_is_hit_and_named_by_its_object():
    below = Mesh(TRIANGLE.vertices - [0.0, 0.0, 0.5], TRIANGLE.triangles)
    accel = accelerator(below, TRIANGLE)
    hits = accel.intersect(np.array([[0.5, 0.5, 3.0], [0.5, 0.5, -3.0]]), np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]))
    np.testing.assert_array_equal(hits.obj, [1, 0])
    np.testing.assert_array_equal(hits.prim, [1, 0])  # global triangle indices: object 1's first is 1
    np.testing.assert_allclose(hits.t, [2.0, 3.5], rtol=1e-6)


@pytest.mark.parametrize("length, blocked", [(1.9, False), (2.1, True)])
def test_a_shadow_ray_is_blocked_only_by_what_lies_within_its_length(length, blocked):
    origins = np.tile([0.5, 0.5, 3.0], (20_000, 1))  # enough rows to be split across threads
    dirs = np.tile([0.0, 0.0, -1.0], (20_000, 1))
    accel = Accelerator([Object("Triangle", TRIANGLE, Diffuse(0.8))], 4.0, threads=2)
    try:
        assert np.all(accel.occluded(origins, dirs, np.full(len(origins), length)) == blocked)
    finally:
        accel.close()


def test_an_error_embree_reports_is_raised_with_what_was_being_done():
    """Embree reports errors through its device, not by return values:
    each build asks, so an error surfaces where it happened (here a build
    quality Embree does not know)."""
    scene = embree.Scene([embree.Geometry(TRIANGLE.vertices, TRIANGLE.triangles)])
    embree._lib.rtcSetSceneBuildQuality(scene.handle, 7)
    with pytest.raises(RuntimeError, match="Embree could not set the build quality: unknown error"):
        embree._check("set the build quality")


CAST = """
import json, sys
import numpy as np
from caustic_addon.tracing import accelerator
from caustic_addon.util import jit
jit.use_kernel_cache(sys.argv[1])
stats = accelerator._cast.compiled().stats
print(json.dumps({"hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values())}))
"""


def test_a_kernel_that_calls_embree_is_loaded_from_the_cache_by_the_next_process(tmp_path):
    """numba would not cache a kernel that calls a ctypes function (its
    address is baked in); the kernels call Embree by a symbol name that
    each process registers."""
    first = compile_in_a_new_process(tmp_path, CAST)
    second = compile_in_a_new_process(tmp_path, CAST)
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1)
