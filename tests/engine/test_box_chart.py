"""Curved receivers without a UV map (maps/box_chart.py): a sphere and a
bowl get their caustic through a box chart the engine makes, against the
closed form, with no line along the chart's seams."""

import math

import numpy as np
import pytest

from caustic_addon import Dielectric, Diffuse, Mesh, Object, RenderSettings, Scene, SunLight, render, shapes
from caustic_addon.maps.box_chart import BoxChart
from caustic_addon.optics.specular import fresnel_dielectric
from caustic_addon.passes.camera_rays import eye_rays
from caustic_addon.tracing.accelerator import Accelerator
from caustic_addon.tracing.topology import open_edge_count, signed_volume
from scenes import top_camera

PIXELS = 64
SUN = 10.0
ALBEDO = 0.8
IOR = 1.5


def sun_through_slab(receiver, elevation: float) -> Scene:
    """`receiver` (a mesh about the origin, within 0.6 m) under a sun
    `elevation` radians from the zenith, whose light comes through a flat
    glass slab 4 m up, off to the side so the top camera sees the receiver
    past it."""
    toward_sun = np.array([math.sin(elevation), 0.0, math.cos(elevation)])
    slab = shapes.cylinder(0.9, 0.1, (4.0 * math.tan(elevation), 0.0, 4.0), segments=64)
    return Scene(objects=[Object("Receiver", receiver, Diffuse(ALBEDO)), Object("Slab", slab, Dielectric(IOR))],
                 lights=[SunLight(-toward_sun, SUN)], camera=top_camera(0.6, PIXELS))


def closed_form(scene: Scene):
    """Per pixel centre: the caustic radiance the slab sends, rho E T
    max(n.s, 0) / pi with T = (1 - F) / (1 + F) (a slab's transmittance
    with its internal reflections, F the unpolarised Fresnel reflectance at
    the sun's incidence), zero where the receiver shadows itself; the
    pixel's box chart island (-1: off the receiver); and whether its 3x3
    neighbourhood is lit throughout, at n.s > 0.3."""
    cam, mesh = scene.camera, scene.objects[0].mesh
    toward_sun = -scene.lights[0].direction
    origins, dirs = eye_rays(cam, np.arange(PIXELS * PIXELS), np.full((PIXELS * PIXELS, 2), 0.5))
    accel = Accelerator(scene.objects[:1], 2.0, threads=1)
    try:
        hits = accel.intersect(origins, dirs)
        normal = accel.face_normals(np.maximum(hits.obj, 0), np.maximum(hits.prim, 0))
        normal = np.where((normal @ dirs[0] > 0.0)[:, None], -normal, normal)
        shadow = accel.intersect(hits.points + 1e-5 * normal, np.tile(toward_sun, (len(dirs), 1)))
    finally:
        accel.close()
    f = fresnel_dielectric(np.array([toward_sun[2]]), 1.0 / IOR)[0]
    cosine = np.where(hits.hit & ~shadow.hit, np.maximum(normal @ toward_sun, 0.0), 0.0).reshape(PIXELS, PIXELS)
    island = np.where(hits.hit, BoxChart(mesh).island[np.maximum(hits.prim, 0)], -1).reshape(PIXELS, PIXELS)
    return ALBEDO * SUN * (1 - f) / (1 + f) * cosine / math.pi, island, _all_around(cosine > 0.3)


def _around(values: np.ndarray) -> np.ndarray:
    """(9,h,w) each pixel's 3x3 neighbourhood (edges repeated)."""
    pad = np.pad(values, 1, mode="edge")
    return np.stack([pad[i:i + values.shape[0], j:j + values.shape[1]] for i in range(3) for j in range(3)])


def _all_around(mask: np.ndarray) -> np.ndarray:
    return _around(mask).all(axis=0)


def seam_and_inside(island: np.ndarray, lit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lit pixels next to a seam of the box chart (their 3x3 meets
    another island), and the other lit pixels."""
    seam = (_around(island) != island).any(axis=0)
    return lit & seam, lit & ~seam


@pytest.mark.parametrize("density", ["beam", "adaptive"])
def test_a_sphere_without_uvs_gets_the_caustic_of_a_slab(density):
    """The sunlit half of a ball under a glass slab: the caustic pass
    against the closed form, no worse along the chart's seams than
    elsewhere; the mesh gets no UV map."""
    ball = shapes.uv_sphere(0.5, (0.0, 0.0, 0.0), 128, 64)
    scene = sun_through_slab(ball, math.radians(30.0))
    result = render(scene, RenderSettings(lamp_rays=40_000, spp=1, density=density))
    expected, island, lit = closed_form(scene)
    caustic = result.passes["caustic"][..., 0]
    error = (caustic - expected) / np.where(lit, expected, 1.0)
    seam, inside = seam_and_inside(island, lit)
    print(f"{density}: relative error mean {error[lit].mean():+.4f}, |error| inside {np.abs(error[inside]).mean():.4f} "
          f"({inside.sum()} pixels), along seams {np.abs(error[seam]).mean():.4f} ({seam.sum()} pixels), "
          f"seam mean {error[seam].mean():+.4f}")
    assert not any("receives no caustics" in w for w in result.warnings)
    assert ball.corner_uvs is None
    assert seam.sum() > 50 and len(np.unique(island[lit])) >= 3
    assert abs(error[lit].mean()) < 0.01
    assert np.abs(error[inside]).mean() < 0.04
    assert abs(error[seam].mean()) < 0.02
    assert np.abs(error[seam]).mean() < np.abs(error[inside]).mean() + 0.015


def test_a_bowl_without_uvs_gets_the_caustic_of_a_slab_inside():
    """Inside a bowl whose rim shadows part of it: the box chart keeps its
    inner and outer walls, which face the same way in turn, apart."""
    bowl = shapes.bowl(0.5, 0.05, (0.0, 0.0, 0.0), 128, 32)
    chart = BoxChart(bowl)
    assert chart.overlaps == []
    scene = sun_through_slab(bowl, math.radians(20.0))
    result = render(scene, RenderSettings(lamp_rays=40_000, spp=1))
    expected, island, lit = closed_form(scene)
    caustic = result.passes["caustic"][..., 0]
    error = (caustic - expected) / np.where(lit, expected, 1.0)
    seam, inside = seam_and_inside(island, lit)
    # the rim's edges are creases, where the light changes anyway
    xy = (np.indices((PIXELS, PIXELS))[::-1] + 0.5) * (1.2 / PIXELS) - 0.6
    rim = np.hypot(*xy) > 0.42
    smooth = seam & ~rim
    print(f"{len(chart.islands)} islands; relative error mean {error[lit].mean():+.4f}, |error| inside "
          f"{np.abs(error[inside]).mean():.4f} ({inside.sum()} pixels), along seams in the wall "
          f"{np.abs(error[smooth]).mean():.4f} ({smooth.sum()} pixels), mean {error[smooth].mean():+.4f}; "
          f"along the rim {np.abs(error[seam & rim]).mean():.4f} ({(seam & rim).sum()} pixels)")
    assert smooth.sum() > 20
    assert abs(error[lit].mean()) < 0.01
    assert np.abs(error[inside]).mean() < 0.04
    assert abs(error[smooth].mean()) < 0.02
    assert np.abs(error[smooth]).mean() < np.abs(error[inside]).mean() + 0.015
    assert np.abs(error[seam & rim]).mean() < 0.1


def test_the_bowl_is_closed_and_holds_its_volume():
    """A hemispherical shell: V = 2 pi (R^3 - r^3) / 3, less its facets'
    shortfall (under 0.3% at 128 x 32)."""
    bowl = shapes.bowl(0.5, 0.05, (0.2, -0.1, 0.3), 128, 32)
    assert open_edge_count(bowl.triangles, bowl.vertices) == 0
    assert signed_volume(bowl.corners) == pytest.approx(2 * math.pi * (0.5 ** 3 - 0.45 ** 3) / 3, rel=3e-3)


def test_a_receiver_whose_box_chart_overlaps_itself_is_named():
    """A spiral ramp of two turns is one piece at overlapping depths whose
    turns lie over each other seen from above: no depth slab separates
    them, and the warning names the object and the face."""
    r, turn = np.linspace(0.3, 1.0, 4), np.linspace(0.0, 4 * math.pi, 97)
    gr, gt = np.meshgrid(r, turn, indexing="ij")
    vertices = np.stack([gr * np.cos(gt), gr * np.sin(gt), 0.05 * gt], -1).reshape(-1, 3)
    idx = np.arange(vertices.shape[0]).reshape(gr.shape)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    ramp = Mesh(vertices, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]))
    scene = sun_through_slab(ramp, 0.0)
    scene.objects[0].name = "Ramp"
    warnings = render(scene, RenderSettings(lamp_rays=2_000, spp=1)).warnings
    print(warnings)
    assert any("'Ramp' has no UV map" in w and "Z overlap" in w for w in warnings)
