"""Ray differentials through specular bounces (passes/differentials.py):
against finite differences of traced rays, and the caustic seen through
glass averaged over the pixel's footprint."""

from dataclasses import replace

import numpy as np

from caustic_addon import Camera, Dielectric, Diffuse, Object, Reflector, RenderSettings, Scene, render, shapes
from caustic_addon.passes.bounce import split, trace
from caustic_addon.passes.camera_rays import eye_rays, ray_differentials
from caustic_addon.passes.paths import Paths, relative_floor
from caustic_addon.scene.material_table import Materials
from caustic_addon.tracing.accelerator import Accelerator
from caustic_addon.tracing.hits import MISS

STEP = 1e-2  # pixels: the central difference (float32 hits limit a smaller one)


class _Arrivals:
    """A tracer that splits at every specular hit, giving eye rays their
    camera differentials at the first, and keeps where each path arrives:
    by (eye sample, family), the point and the ray's differentials there."""

    def __init__(self, accel, materials, camera):
        self.accel, self.materials, self.camera = accel, materials, camera
        self.found = {}

    def escaped(self, paths):
        pass

    def arrived(self, paths, hits):
        for k in np.flatnonzero(paths.specular):
            self.found[(int(paths.ids[k]), int(paths.family[k]))] = (
                hits.points[k], paths.dirs[k], paths.origins[k], paths.d_origins[k], paths.d_dirs[k])

    def scattered(self, paths, hits, surface, depth):
        if paths.d_origins is None:
            d_origins, d_dirs = ray_differentials(self.camera, paths.dirs)
            paths = replace(paths, d_origins=d_origins, d_dirs=d_dirs)
        return split(self.accel, self.materials, paths, hits, surface, carries_light=False)


def _arrivals(scene, pixels, offsets):
    accel = Accelerator(scene.objects, scene.extent(), threads=1)
    materials = Materials.of(scene.objects)
    origins, dirs = eye_rays(scene.camera, pixels, offsets)
    weight = np.ones((len(pixels), 3))
    tracer = _Arrivals(accel, materials, scene.camera)
    paths = Paths.start(origins, dirs, weight, np.arange(len(pixels)), (MISS, MISS), relative_floor(weight),
                        family=True, camera=True)
    trace(accel, materials, paths, 8, tracer)
    return tracer.found


def _floor_change(origin, d, d_origin, d_dir, point):
    """The change of the floor point (plane z = 0) that the ray hits, per
    pixel step, by Igehy's transfer to that plane."""
    s = (point - origin) @ d
    moved = d_origin + s * d_dir
    return moved - (moved[:, 2:] / d[2]) * d


def _check(scene, pixels):
    offsets = np.full((len(pixels), 2), 0.5)
    base = _arrivals(scene, pixels, offsets)
    assert len(base) > 50
    for axis in range(2):
        ahead, behind = offsets.copy(), offsets.copy()
        ahead[:, axis] += STEP
        behind[:, axis] -= STEP
        ahead, behind = _arrivals(scene, pixels, ahead), _arrivals(scene, pixels, behind)
        errors, sizes = [], []
        for key, (point, d, origin, d_origin, d_dir) in base.items():
            if key not in ahead or key not in behind:
                continue
            predicted = _floor_change(origin, d, d_origin, d_dir, point)[axis]
            measured = (ahead[key][0] - behind[key][0]) / (2.0 * STEP)
            errors.append(np.linalg.norm(predicted - measured))
            sizes.append(np.linalg.norm(measured))
        errors, sizes = np.array(errors), np.array(sizes)
        assert len(errors) > 0.5 * len(base)
        assert np.median(errors / sizes) < 1e-3, axis


def _camera(pixx=64, pixy=48):
    return Camera.look_at((0.0, -4.0, 2.5), (0.0, 0.0, 0.6), pixx=pixx, pixy=pixy, fov=np.radians(30.0))


def test_through_a_glass_ball_match_finite_differences():
    """Refraction twice through a smooth sphere (and the internal
    reflections between): the floor point each path reaches moves per
    pixel step as its carried differentials say, to 1e-3 of the move."""
    scene = Scene(objects=[Object("Floor", shapes.plane(20.0), Diffuse(albedo=1.0)),
                           Object("Ball", shapes.uv_sphere(0.6, (0, 0, 0.7), 96, 48), Dielectric(1.5))],
                  lights=[], camera=_camera())
    _check(scene, np.arange(64 * 48)[::7])


def test_in_a_curved_mirror_match_finite_differences():
    """Reflection off a smooth mirror ball, whose curvature spreads the
    footprint: the shading normal's change carries it."""
    scene = Scene(objects=[Object("Floor", shapes.plane(20.0), Diffuse(albedo=1.0)),
                           Object("Mirror", shapes.uv_sphere(0.6, (0, 0, 0.7), 96, 48), Reflector(1.0))],
                  lights=[], camera=_camera())
    _check(scene, np.arange(64 * 48)[::5])


def test_the_caustic_seen_through_a_ball_lens_is_its_footprint_mean_at_one_sample():
    """The ball lens's focus and fold ring seen through the ball: at 1
    sample a pixel, with the default edge samples, the caustic there is
    within 20% (L2) of a 64-sample render. The lens magnifies the
    caustic's sharp lines past the pixel, so the edge pass refines most of
    these pixels; read at one point per sample, as before its rays carried
    differentials, it was 31% off."""
    from benchmarks.scenes import ball_lens

    scene = ball_lens.scene(80, 60)
    accel = Accelerator(scene.objects, scene.extent(), threads=1)
    origins, dirs = eye_rays(scene.camera, np.arange(80 * 60), np.full((80 * 60, 2), 0.5))
    through = (accel.intersect(origins, dirs).obj == 1).reshape(60, 80)
    assert through.sum() > 500
    caustic = {spp: render(scene, RenderSettings(lamp_rays=30_000, spp=spp)).passes["caustic"] for spp in (1, 64)}
    error = np.linalg.norm((caustic[1] - caustic[64])[through]) / np.linalg.norm(caustic[64][through])
    assert error < 0.2
