"""Triangle meshes in world space, and an instancer's copies of one mesh."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Optional

import numpy as np

from ..util.jit import inline, kernel


@dataclass
class Mesh:
    """A triangle mesh in world space.

    vertices       (nv,3) float64, world space
    triangles      (nt,3) int64, indices into vertices; counter-clockwise seen
                   from outside, as Blender stores them
    corner_normals (nt,3,3) float64 unit normals per triangle corner (smooth or
                   custom shading), or None for flat shading
    corner_uvs     (nt,3,2) float64 texture coordinates per corner, or None
    """

    vertices: np.ndarray
    triangles: np.ndarray
    corner_normals: Optional[np.ndarray] = None
    corner_uvs: Optional[np.ndarray] = None

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        if self.corner_normals is not None:
            self.corner_normals = np.ascontiguousarray(self.corner_normals, dtype=np.float64).reshape(-1, 3, 3)
        if self.corner_uvs is not None:
            self.corner_uvs = np.ascontiguousarray(self.corner_uvs, dtype=np.float64).reshape(-1, 3, 2)

    @cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (3,), hi (3,)) of the vertices, NaN where a vertex has a NaN;
        +inf and -inf for a mesh with no vertices."""
        if len(self.vertices) == 0:
            return np.full(3, np.inf), np.full(3, -np.inf)
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    @property
    def triangle_count(self) -> int:
        return len(self.triangles)

    def farthest_from(self, point: np.ndarray) -> float:
        """The largest distance of a vertex from `point (3,)`."""
        return float(np.sqrt(np.add.reduce(np.square(self.vertices - point), axis=1).max()))

    @property
    def corners(self) -> np.ndarray:
        """(nt,3,3) world positions of each triangle's corners."""
        return np.take(self.vertices, self.triangles, axis=0)

    def subset(self, rows: np.ndarray) -> "Mesh":
        """The triangles `rows (k,)` of this mesh, with only the vertices they use."""
        triangles = np.take(self.triangles, rows, axis=0)
        used, local = np.unique(triangles, return_inverse=True)
        return Mesh(np.take(self.vertices, used, axis=0), local.reshape(-1, 3),
                    None if self.corner_normals is None else np.take(self.corner_normals, rows, axis=0),
                    None if self.corner_uvs is None else np.take(self.corner_uvs, rows, axis=0))

    def transformed(self, matrix: np.ndarray) -> "Mesh":
        """This mesh under a (4,4) affine matrix. Normals go by its cofactor
        matrix, det(M) M^-T, signed as det(M) (the inverse transpose, up to
        scale, and defined when M is singular: a mesh scaled to 0 along an
        axis keeps the normals of the faces across that axis); the
        triangles such a matrix flattens to no area are dropped."""
        m = np.asarray(matrix, dtype=np.float64).reshape(1, 4, 4)
        moved = self.instanced(m)
        if np.linalg.det(m[0, :3, :3]) != 0.0:
            return moved
        keep = with_area(moved.vertices, moved.triangles)
        return Mesh(moved.vertices, moved.triangles[keep],
                    None if moved.corner_normals is None else moved.corner_normals[keep],
                    None if moved.corner_uvs is None else moved.corner_uvs[keep])

    def instanced(self, transforms: np.ndarray, with_normals: bool = True) -> "Mesh":
        """This mesh once under each of `transforms (k,4,4)`, affine, as one
        mesh whose copy i follows copy i-1: copy i's vertices under
        transforms[i], its triangles turned around where it mirrors, and,
        only `with_normals`, its corner normals by the cofactor matrix
        (`transformed`, which also drops what a singular one flattens). All
        copies in one kernel, so that an instancer's thousands of instances
        cost no Python loop."""
        m = np.ascontiguousarray(transforms, dtype=np.float64).reshape(-1, 4, 4)
        k, nv, nt = len(m), len(self.vertices), len(self.triangles)
        verts, tris = np.empty((k * nv, 3)), np.empty((k * nt, 3), dtype=np.int64)
        _copy_points(self.vertices, self.triangles, m, verts, tris)
        normals = None
        if with_normals and self.corner_normals is not None:
            normals = np.empty((k * nt, 3, 3))
            _copy_normals(self.corner_normals, m, normals)
        uvs = None
        if self.corner_uvs is not None:
            flip = np.linalg.det(m[:, :3, :3]) < 0.0
            uvs = np.empty((k, nt, 3, 2))
            uvs[:] = self.corner_uvs
            uvs[flip] = uvs[flip, :, ::-1]
            uvs = uvs.reshape(-1, 3, 2)
        return Mesh(verts, tris, normals, uvs)


class Copies(Mesh):
    """Mesh.instanced(transforms, with_normals=False) of `local`, made only
    where something reads its vertices, triangles or UVs. A render reads an
    instancer's copies through their one mesh and their transforms
    (tracing/triangles.py), and their bounds, size and reach without making
    them, so that its memory grows with the meshes, not with the copies."""

    def __init__(self, local: Mesh, transforms: np.ndarray):
        self.local, self.transforms = local, np.ascontiguousarray(transforms, dtype=np.float64).reshape(-1, 4, 4)

    @cached_property
    def _made(self) -> Mesh:
        return self.local.instanced(self.transforms, with_normals=False)

    @property
    def vertices(self) -> np.ndarray:
        return self._made.vertices

    @property
    def triangles(self) -> np.ndarray:
        return self._made.triangles

    @property
    def corner_uvs(self) -> Optional[np.ndarray]:
        return self._made.corner_uvs

    @property
    def triangle_count(self) -> int:
        return len(self.local.triangles) * len(self.transforms)

    @cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        out = np.array([np.full(3, np.inf), np.full(3, -np.inf)])
        if len(self.local.vertices):
            _copies_bounds(self.local.vertices, self.transforms, out)
        return out[0], out[1]

    def farthest_from(self, point: np.ndarray) -> float:
        return float(np.sqrt(_copies_farthest(self.local.vertices, self.transforms,
                                              np.asarray(point, dtype=np.float64))))


@inline
def _placed1(m, vertices, v, row):
    """Coordinate `row` of vertex v of `vertices (nv,3)` under the affine matrix `m (4,4)`."""
    return m[row, 0] * vertices[v, 0] + m[row, 1] * vertices[v, 1] + m[row, 2] * vertices[v, 2] + m[row, 3]


@kernel("void(f8[:, ::1], f8[:, :, ::1], f8[:, ::1])")
def _copies_bounds(vertices, transforms, out):
    """out (2,3): the lowest and highest coordinates of `vertices (nv,3)`
    under each of `transforms (k,4,4)`, NaN where one is NaN."""
    for i in range(len(transforms)):
        for v in range(len(vertices)):
            for row in range(3):
                x = _placed1(transforms[i], vertices, v, row)
                if x != x:
                    out[0, row] = out[1, row] = x
                elif out[0, row] == out[0, row]:
                    out[0, row], out[1, row] = min(out[0, row], x), max(out[1, row], x)


@kernel("f8(f8[:, ::1], f8[:, :, ::1], f8[::1])")
def _copies_farthest(vertices, transforms, point):
    """The largest squared distance from `point (3,)` of `vertices (nv,3)`
    under any of `transforms (k,4,4)`."""
    farthest = 0.0
    for i in range(len(transforms)):
        for v in range(len(vertices)):
            d2 = 0.0
            for row in range(3):
                d2 += (_placed1(transforms[i], vertices, v, row) - point[row]) ** 2
            farthest = max(farthest, d2)
    return farthest


@inline
def _mirrors(m) -> bool:
    """Whether the affine matrix `m (4,4)` mirrors: its 3x3 part's determinant is negative."""
    return (m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]) - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
            + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0])) < 0.0


@kernel("void(f8[:, ::1], i8[:, ::1], f8[:, :, ::1], f8[:, ::1], i8[:, ::1])")
def _copy_points(vertices, triangles, transforms, out_vertices, out_triangles):
    """Mesh.instanced's vertices and triangles: copy i of the vertices under
    transforms[i], its triangles turned around where the transform mirrors."""
    nv, nt = len(vertices), len(triangles)
    for i in range(len(transforms)):
        m = transforms[i]
        for v in range(nv):
            for row in range(3):
                out_vertices[i * nv + v, row] = _placed1(m, vertices, v, row)
        mirrored = _mirrors(m)
        for t in range(nt):
            for corner in range(3):
                out_triangles[i * nt + t, corner] = triangles[t, 2 - corner if mirrored else corner] + i * nv


@kernel("void(f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1])")
def _copy_normals(corner_normals, transforms, out):
    """Mesh.instanced's corner normals: `corner_normals (nt,3,3)` of copy i
    by transforms[i]'s cofactor matrix, signed by its determinant, as
    Mesh.transformed, in its triangles' corner order, into `out (k*nt,3,3)`."""
    nt = len(corner_normals)
    cofactor = np.empty((3, 3))
    for i in range(len(transforms)):
        m = transforms[i]
        mirrored = _mirrors(m)
        sign = -1.0 if mirrored else 1.0
        # cofactor[r, c] = (-1)^(r+c) times the minor of m[r, c]
        for r in range(3):
            for c in range(3):
                r1, r2, c1, c2 = (r + 1) % 3, (r + 2) % 3, (c + 1) % 3, (c + 2) % 3
                cofactor[r, c] = m[r1, c1] * m[r2, c2] - m[r1, c2] * m[r2, c1]
        for t in range(nt):
            for corner in range(3):
                source = 2 - corner if mirrored else corner
                x, y, z = corner_normals[t, source, 0], corner_normals[t, source, 1], corner_normals[t, source, 2]
                n = out[i * nt + t, corner]
                for row in range(3):
                    n[row] = sign * (cofactor[row, 0] * x + cofactor[row, 1] * y + cofactor[row, 2] * z)
                size = max(np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1e-300)
                for row in range(3):
                    n[row] /= size


def with_area(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(nt,) bool: the triangles `triangles (nt,3)` of `vertices (nv,3)`
    whose area is not 0."""
    corners = np.take(vertices, triangles, axis=0)
    return np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1) > 0.0
