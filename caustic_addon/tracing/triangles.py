"""The scene's triangles as kernels read them, by global index.

Global triangle g of object o is prim_offset[o] + copy * copy_size[o] + t:
triangle t of copy `copy` of o's mesh (an object that is not instanced is
one copy). An object of one copy keeps its triangles in world space, one
row each. An instancer's copies (scene.Instances, more than one) share the
rows of their mesh in object space, and each copy's transform takes a row to
world space as a kernel reads it: memory grows with the meshes, not with
the copies. A copy whose transform mirrors is wound the other way round
than its mesh, as Mesh.instanced winds it: its corner k is the mesh's
corner 2 - k.

The tables, one tuple that kernels take as `triangles` (TRIANGLES_TYPE):
  corners         (R,3,3) corner positions
  face_normal     (R,3) unit geometric normals, facing out of closed meshes
                  (0 where a triangle has no area)
  corner_normal   (R,3,3) unit shading normals at the corners, same side
  min_barycentric (R,3) surface_point1's floors, read for rows in world
                  space; a copy's are worked out from its world corners
  prim_offset     (m+1,) each object's first global triangle
  row_offset      (m,) each object's first row
  copy_size       (m,) triangles per copy
  copy_offset     (m,) each object's first copy in the per-copy tables
  placed          (m,) bool: the object's rows are in object space, to be
                  placed by its copies' transforms
  to_world        (C,3,4) each copy's affine transform
  normal_to_world (C,3,3) sign(det M) cof(M): a normal's transform,
                  cof(M) = det(M) M^-T, and the winding's turn
  mirrored        (C,) bool: the copy's transform mirrors
"""

from __future__ import annotations

import math

import numpy as np

from ..util.jit import inline, kernel
from ..util.vectors import dot1, normalize1, sum1

TRIANGLES_TYPE = ("Tuple((f8[:, :, ::1], f8[:, ::1], f8[:, :, ::1], f8[:, ::1], i8[::1], i8[::1], i8[::1], "
                  "i8[::1], b1[::1], f8[:, :, ::1], f8[:, :, ::1], b1[::1]))")


def normal_transforms(transforms: np.ndarray) -> np.ndarray:
    """(k,3,3) sign(det M) cof(M) of affine `transforms (k,4,4)`: the
    columns of cof(M) are b x c, c x a and a x b for M's columns a, b, c
    (det(M) M^-T, defined when M is singular)."""
    a, b, c = transforms[:, :3, 0], transforms[:, :3, 1], transforms[:, :3, 2]
    cofactor = np.stack([np.cross(b, c), np.cross(c, a), np.cross(a, b)], axis=2)
    return np.where((np.linalg.det(transforms[:, :3, :3]) < 0.0)[:, None, None], -cofactor, cofactor)


# The tables' places in the tuple. Helpers index the tuple at each use, bind
# no table to a name and read none under a branch: a table taken out of the
# tuple so takes an atomic reference count on each call (util.jit.inline),
# which made the eye pass twice as slow.
(CORNERS, FACE_NORMAL, CORNER_NORMAL, MIN_BARYCENTRIC, PRIM_OFFSET, ROW_OFFSET, COPY_SIZE, COPY_OFFSET, PLACED,
 TO_WORLD, NORMAL_TO_WORLD, MIRRORED) = range(12)


@inline
def owner1(prim_offset, prim):
    """The object global triangle `prim` belongs to: the last whose first
    triangle is at most `prim`, by bisection of `prim_offset (m+1,)`."""
    lo, hi = 0, len(prim_offset) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if prim_offset[mid] <= prim:
            lo = mid
        else:
            hi = mid
    return lo


@inline
def locate1(triangles, obj, prim):
    """(row, copy, placed) of global triangle `prim` of object `obj`: its
    row in the tables, its copy in the per-copy ones, and whether the row
    is in object space (only then is there a copy to divide out)."""
    local = prim - triangles[PRIM_OFFSET][obj]
    size, start, first, placed = (triangles[COPY_SIZE][obj], triangles[ROW_OFFSET][obj], triangles[COPY_OFFSET][obj],
                                  triangles[PLACED][obj])
    copy = local // size if placed else 0
    return start + local - copy * size, first + copy, placed


@inline
def _turned1(triangles, copy, placed, n):
    """The normal `n` of an object-space row in world space, not unit:
    normal_to_world n; `n` itself where the row is in world space."""
    turned = (triangles[NORMAL_TO_WORLD][copy, 0, 0] * n[0] + triangles[NORMAL_TO_WORLD][copy, 0, 1] * n[1]
              + triangles[NORMAL_TO_WORLD][copy, 0, 2] * n[2],
              triangles[NORMAL_TO_WORLD][copy, 1, 0] * n[0] + triangles[NORMAL_TO_WORLD][copy, 1, 1] * n[1]
              + triangles[NORMAL_TO_WORLD][copy, 1, 2] * n[2],
              triangles[NORMAL_TO_WORLD][copy, 2, 0] * n[0] + triangles[NORMAL_TO_WORLD][copy, 2, 1] * n[1]
              + triangles[NORMAL_TO_WORLD][copy, 2, 2] * n[2])
    return turned if placed else n


@inline
def _corner_of1(triangles, copy, placed, k):
    """The row's corner that is corner k of the copy: 2 - k where the copy
    mirrors (Mesh.instanced turns its triangles around) and its row is in
    object space."""
    mirrored = triangles[MIRRORED][copy]
    return 2 - k if placed and mirrored else k


@inline
def corner_at1(triangles, r, copy, placed, k):
    """World position of corner k of row `r` in copy `copy` (locate1)."""
    kk = _corner_of1(triangles, copy, placed, k)
    p = (triangles[CORNERS][r, kk, 0], triangles[CORNERS][r, kk, 1], triangles[CORNERS][r, kk, 2])
    moved = (triangles[TO_WORLD][copy, 0, 0] * p[0] + triangles[TO_WORLD][copy, 0, 1] * p[1]
             + triangles[TO_WORLD][copy, 0, 2] * p[2] + triangles[TO_WORLD][copy, 0, 3],
             triangles[TO_WORLD][copy, 1, 0] * p[0] + triangles[TO_WORLD][copy, 1, 1] * p[1]
             + triangles[TO_WORLD][copy, 1, 2] * p[2] + triangles[TO_WORLD][copy, 1, 3],
             triangles[TO_WORLD][copy, 2, 0] * p[0] + triangles[TO_WORLD][copy, 2, 1] * p[1]
             + triangles[TO_WORLD][copy, 2, 2] * p[2] + triangles[TO_WORLD][copy, 2, 3])
    return moved if placed else p


@inline
def corner_normal_at1(triangles, r, copy, placed, k):
    """Shading normal at corner k of row `r` in copy `copy` (locate1), in
    world space; a copy's is normal_to_world times its mesh's, not unit, so
    that what is interpolated between corners is the mesh's interpolant,
    turned (as Cycles turns an instance's normal)."""
    kk = _corner_of1(triangles, copy, placed, k)
    n = (triangles[CORNER_NORMAL][r, kk, 0], triangles[CORNER_NORMAL][r, kk, 1], triangles[CORNER_NORMAL][r, kk, 2])
    return _turned1(triangles, copy, placed, n)


@inline
def face_normal_at1(triangles, r, copy, placed):
    """Unit geometric normal of row `r` in copy `copy` (locate1), in world
    space (0 where it has no area)."""
    n = (triangles[FACE_NORMAL][r, 0], triangles[FACE_NORMAL][r, 1], triangles[FACE_NORMAL][r, 2])
    turned = _turned1(triangles, copy, placed, n)
    return normalize1(turned) if placed else n


@inline
def face_normal1(triangles, obj, prim):
    """face_normal_at1 of global triangle `prim` of object `obj`."""
    r, copy, placed = locate1(triangles, obj, prim)
    return face_normal_at1(triangles, r, copy, placed)


@inline
def normals1(triangles, obj, prim, u, v):
    """(face, shading): the unit geometric normal of global triangle `prim`
    of object `obj` (face_normal_at1), and its unit shading normal at
    Embree's barycentrics u, v:

        n_s = normalize((1 - u - v) n_0 + u n_1 + v n_2)

    from its corner normals (corner_normal_at1), the face's where they
    cancel out (|n_s| <= 1e-12)."""
    r, copy, placed = locate1(triangles, obj, prim)
    w = 1.0 - u - v
    n0, n1, n2 = (corner_normal_at1(triangles, r, copy, placed, 0), corner_normal_at1(triangles, r, copy, placed, 1),
                  corner_normal_at1(triangles, r, copy, placed, 2))
    n = (w * n0[0] + u * n1[0] + v * n2[0], w * n0[1] + u * n1[1] + v * n2[1], w * n0[2] + u * n1[2] + v * n2[2])
    face = face_normal_at1(triangles, r, copy, placed)
    return face, (normalize1(n) if dot1(n, n) > 1e-24 else face)


@inline
def min_barycentric1(p, k, epsilon):
    """epsilon / the altitude onto the edge opposite corner k of the
    triangle of corners `p` (3 3-tuples), altitude = 2 area / edge length;
    at most 0.3 (tiny triangles)."""
    a, b = p[(k + 1) % 3], p[(k + 2) % 3]
    edge = math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)
    e1, e2 = sum1(1.0, p[1], -1.0, p[0]), sum1(1.0, p[2], -1.0, p[0])
    n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    area = 0.5 * math.sqrt(dot1(n, n))
    fraction = epsilon * edge / (2.0 * area) if area > 0.0 else np.inf
    return min(fraction, 0.3) if np.isfinite(fraction) else 0.3


@inline
def _foot1(p, k):
    """Where the altitude from corner k of the triangle of corners `p`
    meets the line of its opposite edge, as s along that edge from corner
    k+1 to corner k+2: s = (c_k - c_i) . e / e . e, e = c_j - c_i."""
    i, j = (k + 1) % 3, (k + 2) % 3
    along, length2 = 0.0, 0.0
    for a in range(3):
        e = p[j][a] - p[i][a]
        along += (p[k][a] - p[i][a]) * e
        length2 += e * e
    return along / length2 if length2 > 0.0 else 0.5


@inline
def surface_point1(triangles, obj, prim, u, v, epsilon):
    """The float64 point of global triangle `prim` of object `obj` at
    Embree's barycentrics u, v, kept epsilon inside its edges: a float32
    hit can fall just past an edge, and a ray leaving from there would
    already be beyond the neighbouring face's plane and miss it.

    A barycentric b_k below its floor (min_barycentric1: epsilon over the
    altitude onto corner k's opposite edge) is raised to it by moving the
    point along that altitude, straight away from the edge: b_k gains d and
    the edge's corners give it up in the ratio of the altitude's foot, so
    the point moves d * altitude <= epsilon and keeps its place along the
    edge (near a corner, off each edge in turn, twice over, since a move
    off one can bring it nearer the other). Raising b_k and renormalising
    would move it along the edge too, by up to b_k's floor times the
    triangle's length: 0.8 mm on a fan's 0.7 m spokes, which threw the
    light through a slab's bottom off by a third of a pixel."""
    r, copy, placed = locate1(triangles, obj, prim)
    p = (corner_at1(triangles, r, copy, placed, 0), corner_at1(triangles, r, copy, placed, 1),
         corner_at1(triangles, r, copy, placed, 2))
    floor = (triangles[MIN_BARYCENTRIC][r, 0], triangles[MIN_BARYCENTRIC][r, 1], triangles[MIN_BARYCENTRIC][r, 2])
    if placed:
        floor = (min_barycentric1(p, 0, epsilon), min_barycentric1(p, 1, epsilon), min_barycentric1(p, 2, epsilon))
    b0, b1, b2 = 1.0 - u - v, u, v
    for _ in range(2):
        for k in range(3):
            need = floor[k] - (b0 if k == 0 else (b1 if k == 1 else b2))
            if need > 0.0:
                s = _foot1(p, k)
                if k == 0:
                    b0, b1, b2 = b0 + need, b1 - need * (1.0 - s), b2 - need * s
                elif k == 1:
                    b0, b1, b2 = b0 - need * s, b1 + need, b2 - need * (1.0 - s)
                else:
                    b0, b1, b2 = b0 - need * (1.0 - s), b1 - need * s, b2 + need
    return (b0 * p[0][0] + b1 * p[1][0] + b2 * p[2][0],
            b0 * p[0][1] + b1 * p[1][1] + b2 * p[2][1],
            b0 * p[0][2] + b1 * p[1][2] + b2 * p[2][2])


@kernel(f"void({TRIANGLES_TYPE}, i8[::1], i8[::1], f8[:, ::1])")
def face_normals(triangles, obj, prim, out):
    """out (n,3): face_normal1 of each of `prim (n,)` of objects `obj (n,)`."""
    for i in range(len(prim)):
        n = face_normal1(triangles, obj[i], prim[i])
        out[i, 0], out[i, 1], out[i, 2] = n[0], n[1], n[2]


@kernel(f"void({TRIANGLES_TYPE}, i8[::1], i8[::1], f8[:, :, ::1])")
def corner_points(triangles, obj, prim, out):
    """out (n,3,3): the world corners (corner_at1) of each of `prim (n,)` of objects `obj (n,)`."""
    for i in range(len(prim)):
        r, copy, placed = locate1(triangles, obj[i], prim[i])
        for k in range(3):
            p = corner_at1(triangles, r, copy, placed, k)
            out[i, k, 0], out[i, k, 1], out[i, k, 2] = p[0], p[1], p[2]
