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
        """This mesh under a (4,4) affine matrix; normals go by its inverse transpose."""
        m = np.asarray(matrix, dtype=np.float64)
        verts = self.vertices @ m[:3, :3].T + m[:3, 3]
        normals = None
        if self.corner_normals is not None:
            nmat = np.linalg.inv(m[:3, :3]).T
            normals = self.corner_normals @ nmat.T
            normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
        tris = self.triangles if np.linalg.det(m[:3, :3]) > 0 else self.triangles[:, ::-1]
        if normals is not None and tris is not self.triangles:
            normals = normals[:, ::-1]
        uvs = None
        if self.corner_uvs is not None:
            uvs = self.corner_uvs if tris is self.triangles else self.corner_uvs[:, ::-1]
        return Mesh(verts, tris, normals, uvs)
