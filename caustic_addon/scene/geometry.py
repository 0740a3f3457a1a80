"""Triangle meshes in world space."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np


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
        m = np.asarray(matrix, dtype=np.float64)
        verts = self.vertices @ m[:3, :3].T + m[:3, 3]
        det = float(np.linalg.det(m[:3, :3]))
        tris, normals, uvs = self.triangles, self.corner_normals, self.corner_uvs
        if det < 0.0:
            tris = tris[:, ::-1]
            normals = None if normals is None else normals[:, ::-1]
            uvs = None if uvs is None else uvs[:, ::-1]
        if normals is not None:
            normals = normals @ cofactor_matrix(m[:3, :3]).T * (-1.0 if det < 0.0 else 1.0)
            length = np.linalg.norm(normals, axis=-1, keepdims=True)
            normals = normals / np.maximum(length, 1e-300)
        if det == 0.0:
            keep = with_area(verts, tris)
            tris = tris[keep]
            normals = None if normals is None else normals[keep]
            uvs = None if uvs is None else uvs[keep]
        return Mesh(verts, tris, normals, uvs)

    def instanced(self, transforms: np.ndarray) -> "Mesh":
        """This mesh once under each of `transforms (k,4,4)`, affine and
        invertible, as one mesh whose copy i is `transformed(transforms[i])`:
        its vertices and triangles follow copy i-1's. All copies at once, so
        that an instancer's thousands of instances cost no Python loop."""
        m = np.asarray(transforms, dtype=np.float64).reshape(-1, 4, 4)
        k, nv, nt = len(m), len(self.vertices), len(self.triangles)
        linear = m[:, :3, :3]
        verts = self.vertices @ linear.transpose(0, 2, 1) + m[:, None, :3, 3]
        flip = np.flatnonzero(np.linalg.det(linear) < 0.0)
        tris = np.empty((k, nt, 3), dtype=np.int64)
        tris[:] = self.triangles
        tris[flip] = tris[flip, :, ::-1]
        tris += (np.arange(k, dtype=np.int64) * nv)[:, None, None]
        normals = uvs = None
        if self.corner_normals is not None:
            columns = [linear[:, :, axis] for axis in range(3)]
            cofactor = np.stack([np.cross(columns[1], columns[2]), np.cross(columns[2], columns[0]),
                                 np.cross(columns[0], columns[1])], axis=2)
            cofactor[flip] *= -1.0
            normals = (self.corner_normals.reshape(-1, 3) @ cofactor.transpose(0, 2, 1)).reshape(k, nt, 3, 3)
            normals[flip] = normals[flip, :, ::-1]
            normals /= np.maximum(np.sqrt(np.einsum("...i,...i->...", normals, normals))[..., None], 1e-300)
        if self.corner_uvs is not None:
            uvs = np.empty((k, nt, 3, 2), dtype=np.float64)
            uvs[:] = self.corner_uvs
            uvs[flip] = uvs[flip, :, ::-1]
        return Mesh(verts.reshape(-1, 3), tris.reshape(-1, 3), None if normals is None else normals.reshape(-1, 3, 3),
                    None if uvs is None else uvs.reshape(-1, 3, 2))


def cofactor_matrix(m: np.ndarray) -> np.ndarray:
    """(3,3) cofactor matrix of `m (3,3)`: its columns are the cross
    products of m's columns in turn, m1 x m2, m2 x m0, m0 x m1; it equals
    det(m) m^-T where m is invertible."""
    c = m.T
    return np.stack([np.cross(c[1], c[2]), np.cross(c[2], c[0]), np.cross(c[0], c[1])], axis=1)


def with_area(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(nt,) bool: the triangles `triangles (nt,3)` of `vertices (nv,3)`
    whose area is not 0."""
    corners = np.take(vertices, triangles, axis=0)
    return np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1) > 0.0
