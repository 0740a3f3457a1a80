"""Procedural meshes for tests, benchmarks, the gallery and the paper's
experiments: a sphere, a cylinder, a cone (point down), a plane, an open
tube (a mirror ring), a bowl, a slab of water with a wavy top and an open
wavy sheet (a subdivided plane under a Wave modifier). All but the tube and
the sheet are closed; all are wound counter-clockwise seen from outside, with smooth
corner normals (flat on caps, walls and the plane)."""

from __future__ import annotations

import math

import numpy as np

from .geometry import Mesh


def plane(size: float = 10.0, center=(0.0, 0.0, 0.0)) -> Mesh:
    """A square of side `size` in the z = center_z plane, facing +z, with UVs."""
    h = 0.5 * size
    verts = np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], dtype=np.float64) + center
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)
    return Mesh(verts, tris, np.tile([0.0, 0.0, 1.0], (2, 3, 1)), uv[tris])


def uv_sphere(radius: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 64, rings: int = 32,
              uvs: bool = False) -> Mesh:
    """A UV sphere with smooth normals: segments around, rings pole to pole;
    with `uvs`, Blender's UV map of it (u around from +x, v up from the
    bottom pole, a seam at u = 0 and 1)."""
    theta = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    unit = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    top, bottom = 0, len(unit) - 1

    s = np.arange(segments)
    # each corner as (ring line 0..rings from the top pole, segment 0..segments, unwrapped)
    grid = [np.stack([np.stack([np.zeros(segments), s + 0.5], -1), np.stack([np.ones(segments), s], -1),
                      np.stack([np.ones(segments), s + 1], -1)], axis=1)]
    for r in range(1, rings - 1):
        a, b = np.stack([np.full(segments, r), s], -1), np.stack([np.full(segments, r + 1), s], -1)
        c, d = np.stack([np.full(segments, r + 1), s + 1], -1), np.stack([np.full(segments, r), s + 1], -1)
        grid += [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]
    grid.append(np.stack([np.stack([np.full(segments, rings), s + 0.5], -1),
                          np.stack([np.full(segments, rings - 1), s + 1], -1),
                          np.stack([np.full(segments, rings - 1), s], -1)], axis=1))
    grid = np.concatenate(grid)
    line, seg = grid[..., 0].astype(np.int64), grid[..., 1]
    tris = np.where(line == 0, top, np.where(line == rings, bottom,
                                             1 + (line - 1) * segments + np.floor(seg).astype(np.int64) % segments))
    corner_uvs = np.stack([seg / segments, 1.0 - line / rings], axis=-1) if uvs else None
    return Mesh(unit * radius + np.asarray(center, dtype=np.float64), tris, unit[tris], corner_uvs)


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


def bowl(radius: float = 1.0, thickness: float = 0.1, center=(0.0, 0.0, 0.0), segments: int = 128,
         steps: int = 32) -> Mesh:
    """A hemispherical bowl, open at the top: a shell between spheres of
    `radius` and radius - thickness about center + (0, 0, radius), from its
    outer bottom at `center` to a flat rim at center_z + radius; each wall
    in `steps` bands, smooth around, flat along them."""
    inner = radius - thickness
    a = np.linspace(0.0, 0.5 * math.pi, steps + 1)
    inside = np.stack([inner * np.sin(a), radius - inner * np.cos(a)], axis=1)
    outside = np.stack([radius * np.sin(a), radius - radius * np.cos(a)], axis=1)[::-1]
    profile = np.concatenate([inside, outside])
    mid = 0.5 * (a[1:] + a[:-1])
    normals = np.concatenate([np.stack([-np.sin(mid), np.cos(mid)], axis=1), [[0.0, 1.0]],
                              np.stack([np.sin(mid), -np.cos(mid)], axis=1)[::-1]])
    return _revolve(profile, normals, segments, center)


def tube(radius: float = 1.0, height: float = 1.0, center=(0.0, 0.0, 0.0), segments: int = 256) -> Mesh:
    """An open tube (no caps) about z from center_z to center_z + height,
    smooth radial normals: a coffee cup's wall, or a ring."""
    return _revolve(np.array([[radius, height], [radius, 0.0]]), np.array([[1.0, 0.0]]), segments, center)


def _height_field(size: float, depth: float, waves, cells: int):
    """The top of `wavy_slab` (its docstring gives the field): (vertices
    ((cells+1)^2, 3), unit normals of the field alike, triangles (2 cells^2,
    3) counter-clockwise seen from above)."""
    ticks = np.linspace(-0.5 * size, 0.5 * size, cells + 1)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    h, dx, dy = np.full_like(x, depth), np.zeros_like(x), np.zeros_like(x)
    for amplitude, wavelength, angle in waves:
        k = 2.0 * math.pi / wavelength * np.array([math.cos(angle), math.sin(angle)])
        phase = k[0] * x + k[1] * y
        h += amplitude * np.cos(phase)
        dx -= amplitude * k[0] * np.sin(phase)
        dy -= amplitude * k[1] * np.sin(phase)
    n = cells + 1
    top = np.stack([x, y, h], axis=-1).reshape(-1, 3)
    top_normals = np.stack([-dx, -dy, np.ones_like(x)], axis=-1).reshape(-1, 3)
    top_normals /= np.linalg.norm(top_normals, axis=1, keepdims=True)
    i, j = np.meshgrid(np.arange(cells), np.arange(cells), indexing="ij")
    a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1
    top_tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return top, top_normals, top_tris


def wavy_sheet(size: float = 2.0, waves=((0.02, 0.5, 0.0), (0.015, 0.37, 1.1)), cuts: int = 100,
               center=(0.0, 0.0, 0.0)) -> Mesh:
    """An open square sheet `size` across, a plane subdivided with `cuts`
    cuts ((cuts + 1)^2 quads) displaced by waves as Blender's Wave and
    Ocean modifiers do: the height field sum of a cos(k . (x, y)) over
    `waves` (amplitude a m, wavelength m, direction radians) about
    `center`, with the field's own smooth normals, facing up."""
    top, normals, tris = _height_field(size, 0.0, waves, cuts + 1)
    return Mesh(top + np.asarray(center, dtype=np.float64), tris, normals[tris])


def wavy_slab(size: float = 2.0, depth: float = 0.3, waves=((0.02, 0.5, 0.0), (0.015, 0.37, 1.1)),
              cells: int = 128, center=(0.0, 0.0, 0.0)) -> Mesh:
    """A closed square slab of water, `size` across and `depth` deep, its
    top the height field depth + sum of a cos(k . (x, y)) over `waves`
    (amplitude a m, wavelength m, direction radians), sampled on `cells` x
    `cells` quads with the field's own normals (-dh/dx, -dh/dy, 1), smooth;
    flat bottom and sides. `center` is the middle of its bottom face."""
    top, top_normals, top_tris = _height_field(size, depth, waves, cells)
    n = cells + 1
    # the rim walked counter-clockwise seen from above: y = -half, x = +half, y = +half, x = -half
    grid = np.arange(n * n).reshape(n, n)
    rim = np.concatenate([grid[:-1, 0], grid[-1, :-1], grid[:0:-1, -1], grid[0, :0:-1]])
    rim_top = top[rim]
    rim_bottom = rim_top * np.array([1.0, 1.0, 0.0])
    m = len(rim)
    # the walls: a quad (top k, bottom k, bottom k+1, top k+1) per rim step,
    # facing out along the side's axis; the bottom: a fan from its centre
    side = np.repeat(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]), cells, axis=0)
    k, k1 = np.arange(m), (np.arange(m) + 1) % m
    t, b, centre = len(top) + k, len(top) + m + k, len(top) + 2 * m
    t1, b1 = len(top) + k1, len(top) + m + k1
    walls = np.concatenate([np.stack([t, b, b1], 1), np.stack([t, b1, t1], 1)])
    bottom = np.stack([np.full(m, centre), b1, b], 1)
    verts = np.concatenate([top, rim_top, rim_bottom, [[0.0, 0.0, 0.0]]])
    tris = np.concatenate([top_tris, walls, bottom])
    normals = np.concatenate([top_normals[top_tris], np.repeat(np.tile(side, (2, 1))[:, None], 3, axis=1),
                              np.tile([0.0, 0.0, -1.0], (m, 3, 1))])
    return Mesh(verts + np.asarray(center, dtype=np.float64), tris, normals)
