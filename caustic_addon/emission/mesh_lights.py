"""Emissive meshes as lamps (scene.MeshLight): one of each object whose
material emits, sampled by area for shadow rays, and cut into pieces of
about equal area for the pass from the lamps, where each piece is a small
area lamp on each side whose light leaves the mesh. Shadow rays sample it
in lamp_samples.py."""

from __future__ import annotations

import math

import numpy as np

from ..scene import AreaLight, MeshLight, Object, Scene
from ..tracing.topology import open_edge_count, signed_volume, triangle_normals
from ..util.vectors import DIVISION_FLOOR

# Pieces a mesh light is cut into where photons leave it, each side.
PHOTON_PIECES = 64


def mesh_lights(scene: Scene) -> list[MeshLight]:
    """A MeshLight of each object whose material emits (Scene.emitting) and
    that has an area."""
    lights = [MeshLight(obj.mesh.corners, obj.material.emission, name=obj.name, sides=_leaving_sides(obj, scene))
              for obj in scene.emitting]
    return [light for light in lights if light.areas.sum() > 0.0]


def _leaving_sides(emitter: Object, scene: Scene) -> tuple[bool, bool]:
    """The sides of `emitter`'s faces whose light can reach another object:
    both of an open mesh; of a closed one its outer side (by the sign of its
    volume), unless another object's centre lies within its bounds. (A
    glowing ball sent half its lamp rays inward, where its own faces stop
    them.)"""
    mesh = emitter.mesh
    if open_edge_count(mesh.triangles, mesh.vertices) > 0:
        return True, True
    lo, hi = mesh.bounds
    for other in scene.objects:
        centre = 0.5 * (other.mesh.bounds[0] + other.mesh.bounds[1])
        if other is not emitter and np.all(centre > lo) and np.all(centre < hi):
            return True, True
    outward = signed_volume(mesh.corners) > 0.0
    return outward, not outward


def _subdivision(n: int) -> np.ndarray:
    """(n^2,3,3) barycentric corners of the n^2 equal triangles that cut a
    triangle's edges into n parts."""
    up = [((i, j), (i + 1, j), (i, j + 1)) for i in range(n) for j in range(n - i)]
    down = [((i + 1, j), (i + 1, j + 1), (i, j + 1)) for i in range(n) for j in range(n - i - 1)]
    steps = np.array(up + down, dtype=np.float64) / n
    return np.stack([1.0 - steps.sum(axis=2), steps[..., 0], steps[..., 1]], axis=2)


def pieces(light: MeshLight, count: int) -> tuple[np.ndarray, np.ndarray]:
    """(triangles (k,3,3), areas (k,)): the light's faces in about `count`
    pieces of area A / count or more, A the light's. A face of area a is cut
    in n^2 equal triangles, n = floor(sqrt(a count / A)), so large faces
    tile exactly; where small faces leave more than `count` pieces, `count`
    are drawn by area (systematic resampling, stratified along the faces'
    order), each standing for A / count: its triangle grown or shrunk about
    its centroid to that area."""
    triangles, areas = light.triangles, light.areas
    keep = areas > 0.0
    triangles, areas = triangles[keep], areas[keep]
    total = float(areas.sum())
    splits = np.maximum(np.floor(np.sqrt(areas * count / total)), 1).astype(np.int64)
    done = [np.einsum("pkc,tcx->tpkx", _subdivision(n), triangles[splits == n]).reshape(-1, 3, 3)
            for n in np.unique(splits)]
    cut = np.concatenate(done)
    if len(cut) <= count:
        return cut, _area_of(cut)
    cdf = np.cumsum(_area_of(cut)) / total
    chosen = cut[np.minimum(np.searchsorted(cdf, (np.arange(count) + 0.5) / count), len(cut) - 1)]
    centroid = chosen.mean(axis=1, keepdims=True)
    scale = np.sqrt(total / count / np.maximum(_area_of(chosen), DIVISION_FLOOR))
    return centroid + (chosen - centroid) * scale[:, None, None], np.full(count, total / count)


def _area_of(triangles: np.ndarray) -> np.ndarray:
    return triangle_normals(triangles)[1]


def _sides(triangles: np.ndarray) -> np.ndarray:
    """(k,2,3) unit normals of each triangle's two sides, along its winding's normal and against it."""
    normal = triangle_normals(triangles)[0]
    return np.stack([normal, -normal], axis=1)


def _kites(triangles: np.ndarray) -> np.ndarray:
    """(3k,4,3): each of `triangles (k,3,3)` as three quadrilaterals of a
    third of its area each, a corner, the midpoints of its two edges and the
    centroid between them."""
    g = triangles.mean(axis=1)
    mid = 0.5 * (triangles + np.roll(triangles, -1, axis=1))
    quads = [np.stack([triangles[:, k], mid[:, k], g, mid[:, k - 1]], axis=1) for k in range(3)]
    return np.stack(quads, axis=1).reshape(-1, 4, 3)


def point_lamps(light: MeshLight, count: int, lift: float) -> tuple[list[AreaLight], list[np.ndarray]]:
    """(lamps, cells) for beam mode (lamp_points.beam_lamps): the light's
    `pieces`, about count / 3, each as three quadrilateral cells (`_kites`:
    beams spread over a cell's image as over a lamp's cells, in its
    quadrilateral's parts), each cell on each side whose light leaves the
    mesh (MeshLight.sides) an area lamp of size 0 at its centroid, `lift` m
    off the face, sending pi a L; its cell (4,3) the corners less the
    centroid."""
    triangles, areas = pieces(light, max(1, count // 3))
    quads = _kites(triangles)
    # the quadrilateral as triangles (0, 1, 2) and (0, 2, 3): its centroid by area
    halves = [_area_of(quads[:, [0, a, b]]) for a, b in ((1, 2), (2, 3))]
    centroids = ((halves[0][:, None] * quads[:, :3].sum(axis=1) + halves[1][:, None] * quads[:, [0, 2, 3]].sum(axis=1))
                 / (3.0 * np.maximum(halves[0] + halves[1], DIVISION_FLOOR)[:, None]))
    cells = quads - centroids[:, None, :]
    lamps, corners = [], []
    zero = np.zeros(3)
    for centroid, area, cell, sides in zip(centroids, np.repeat(areas / 3.0, 3), cells,
                                           np.repeat(_sides(triangles), 3, axis=0)):
        for normal in sides[list(light.sides)]:
            lamps.append(AreaLight(centroid + lift * normal, zero, zero, normal, math.pi * float(area),
                                   color=light.radiance, name=light.name))
            corners.append(cell)
    return lamps, corners


def area_lamps(light: MeshLight, count: int, lift: float) -> list[AreaLight]:
    """The light for photons: each of its `pieces`, on each side whose
    light leaves the mesh, as the parallelogram area lamp of the piece's
    area about its centroid, spanned by its edges (half-extents (b - a) / 2
    and (c - a) / 4), `lift` m off the face, sending pi a L."""
    triangles, areas = pieces(light, count)
    centroids = triangles.mean(axis=1)
    axis_x = 0.5 * (triangles[:, 1] - triangles[:, 0])
    axis_y = 0.25 * (triangles[:, 2] - triangles[:, 0])
    return [AreaLight(c + lift * normal, x, y, normal, math.pi * float(a), color=light.radiance, name=light.name)
            for c, x, y, a, sides in zip(centroids, axis_x, axis_y, areas, _sides(triangles))
            for normal in sides[list(light.sides)]]


def lift_off(light: MeshLight) -> float:
    """How far a piece's lamp sits off its face, m: a millionth of the
    light's reach, so its rays leave the face."""
    return 1e-6 * max(light.radius, 1.0)
