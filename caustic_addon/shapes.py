"""Procedural meshes for tests, benchmarks and the paper's experiments: a
round base (sphere), a flat base (cylinder), a pointed base (cone, point
down), the receiver plane, and an open tube (a mirror ring). All but the
tube are closed; all are wound counter-clockwise seen from outside, with
smooth corner normals (flat on caps and the plane).

The paper's scenes (section 4) are laid out here too, so that
benchmarks/paper_scenes.py and the add-on's caustic.add_paper_scene build
the same geometry: a clear object of base PAPER_SHAPES over a diffuse floor
facing +z at z = 0, under one point lamp above, slightly to the side and
behind, so that shadows and caustics fall toward the paper's camera, which
looks down from in front. Lengths in metres:

    round    a sphere, radius 0.5 (the paper's "round base": sphere or droplet)
    flat     a cylinder, radius 0.5, 0.8 tall (a flat-bottomed glass)
    pointed  a cone, radius 0.5, 1.0 tall, point down (a gem's pavilion)
"""

from __future__ import annotations

import math

import numpy as np

from .scene import Mesh


def plane(size: float = 10.0, center=(0.0, 0.0, 0.0)) -> Mesh:
    """A square of side `size` in the z = center_z plane, facing +z, with UVs."""
    h = 0.5 * size
    verts = np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], dtype=np.float64) + center
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)
    return Mesh(verts, tris, np.tile([0.0, 0.0, 1.0], (2, 3, 1)), uv[tris])


def uv_sphere(radius: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 64, rings: int = 32) -> Mesh:
    """A UV sphere with smooth normals: segments around, rings pole to pole."""
    theta = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    unit = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    top, bottom = 0, len(unit) - 1

    def at(r, s):
        return 1 + r * segments + s % segments

    s = np.arange(segments)
    tris = [np.stack([np.full(segments, top), at(0, s), at(0, s + 1)], axis=1)]
    for r in range(rings - 2):
        a, b, c, d = at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s + 1)
        tris += [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]
    tris.append(np.stack([np.full(segments, bottom), at(rings - 2, s + 1), at(rings - 2, s)], axis=1))
    tris = np.concatenate(tris)
    return Mesh(unit * radius + np.asarray(center, dtype=np.float64), tris, unit[tris])


def sphere_for_triangles(triangles: int, radius: float = 1.0, center=(0.0, 0.0, 0.0)) -> Mesh:
    """A UV sphere with about `triangles` triangles (2 segments per ring)."""
    rings = max(3, int(round(math.sqrt(triangles / 4.0))))
    return uv_sphere(radius, center, segments=2 * rings, rings=rings)


def _revolve(profile: np.ndarray, normals: np.ndarray, segments: int, center) -> Mesh:
    """Surface of revolution about z of a closed profile (k,2) of (r, z)
    points from the top axis to the bottom axis, with profile normals (k,2)
    per point as (n_r, n_z). Each profile edge becomes a band of quads; an
    edge ending on the axis becomes a fan."""
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    cos, sin = np.cos(phi), np.sin(phi)
    verts, norms, tris = [], [], []
    for (r0, z0), (r1, z1), (m0, n0) in zip(profile[:-1], profile[1:], normals):
        band = []
        for r, z in ((r0, z0), (r1, z1)):
            band.append(np.stack([r * cos, r * sin, np.full(segments, z)], axis=1))
        normal = np.stack([m0 * cos, m0 * sin, np.full(segments, n0)], axis=1)
        base = sum(len(v) for v in verts)
        verts += band
        norms += [normal, normal]
        s = np.arange(segments)
        a, b = base + s, base + (s + 1) % segments
        c, d = base + segments + (s + 1) % segments, base + segments + s
        tris += [np.stack([a, d, c], axis=1), np.stack([a, c, b], axis=1)]
    verts, norms, tris = np.concatenate(verts), np.concatenate(norms), np.concatenate(tris)
    corners = verts[tris]
    keep = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1) > 0
    tris = tris[keep]
    return Mesh(verts + np.asarray(center, dtype=np.float64), tris, norms[tris])


def cylinder(radius: float = 1.0, height: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 128) -> Mesh:
    """A flat-based cylinder from z = center_z to center_z + height, smooth sides, flat caps."""
    profile = np.array([[0.0, height], [radius, height], [radius, 0.0], [0.0, 0.0]])
    normals = np.array([[0.0, 1.0], [1.0, 0.0], [0.0, -1.0]])
    return _revolve(profile, normals, segments, center)


def cone(radius: float = 1.0, height: float = 1.5, center=(0.0, 0.0, 0.0), segments: int = 128) -> Mesh:
    """A pointed-based cone, point down at center, flat top cap at center_z + height."""
    profile = np.array([[0.0, height], [radius, height], [0.0, 0.0]])
    slant = np.array([height, -radius]) / math.hypot(height, radius)
    normals = np.array([[0.0, 1.0], slant])
    return _revolve(profile, normals, segments, center)


def tube(radius: float = 1.0, height: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 256) -> Mesh:
    """An open tube (no caps) about z from center_z to center_z + height,
    smooth radial normals: a coffee cup's wall, or a ring."""
    return _revolve(np.array([[radius, height], [radius, 0.0]]), np.array([[1.0, 0.0]]), segments, center)


PAPER_SHAPES = ("round", "flat", "pointed")
# The paper's indices of refraction: water, cubic zirconia, diamond.
PAPER_INDICES = {"water": 1.33, "cubic zirconia": 1.9, "diamond": 2.41}
PAPER_RADIUS = 0.5
PAPER_CYLINDER_HEIGHT = 0.8
PAPER_CONE_HEIGHT = 1.0
# m between the floor and the object's lowest point at rest: keeps the glass off the plane.
PAPER_GAP = 1e-3
# m: the height of the paper's raised position
PAPER_RAISED = 1.0
# m: wide enough to catch the fan of light a raised cone throws
PAPER_FLOOR_SIZE = 16.0
PAPER_FLOOR_ALBEDO = 0.8
PAPER_LAMP_POSITION = (0.8, 0.5, 4.0)
# W: the paper's lamp energy 10 makes it 100 W.
PAPER_LAMP_POWER = 10.0
PAPER_EYE = (0.0, -4.0, 6.5)
PAPER_TARGET = (0.0, 0.0, 0.3)
# degrees across the image's width
PAPER_FOV = 40.0


def paper_glass(shape: str, height: float = 0.0) -> Mesh:
    """The paper's object of base `shape` (one of PAPER_SHAPES), centred on
    the z axis, its lowest point PAPER_GAP + `height` m above z = 0."""
    bottom = PAPER_GAP + height
    if shape == "round":
        return uv_sphere(PAPER_RADIUS, (0.0, 0.0, bottom + PAPER_RADIUS), 128, 64)
    if shape == "flat":
        return cylinder(PAPER_RADIUS, PAPER_CYLINDER_HEIGHT, (0.0, 0.0, bottom))
    if shape == "pointed":
        return cone(PAPER_RADIUS, PAPER_CONE_HEIGHT, (0.0, 0.0, bottom))
    raise ValueError(f"shape must be one of {PAPER_SHAPES}, got {shape!r}")
