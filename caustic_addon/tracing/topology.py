"""Mesh topology and measures: face normals and areas, enclosed volume, open edges."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np

from ..util.rows import row_ids
from ..util.vectors import cross_rows, length

# open_edges' answers for the last meshes it was asked about.
_SEEN_KEPT = 16
_SEEN: OrderedDict = OrderedDict()
_SEEN_LOCK = threading.Lock()


def triangle_normals(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit normals (nt,3), areas (nt,)) of triangles `corners (nt,3,3)`,
    oriented by the right-hand rule on their winding. Degenerate triangles get
    a zero normal and zero area."""
    cross = cross_rows(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    double_area = length(cross)
    return cross / np.where(double_area > 0, double_area, 1.0)[:, None], 0.5 * double_area


def signed_volume(corners: np.ndarray) -> float:
    """Volume enclosed by a closed mesh, positive when its normals face out
    (divergence theorem: sum of p0 . (p1 x p2) / 6 over triangles)."""
    return float(np.einsum("ij,ij->i", corners[:, 0], cross_rows(corners[:, 1], corners[:, 2])).sum() / 6.0)


def open_edge_count(triangles: np.ndarray, vertices: np.ndarray) -> int:
    """Number of edges not shared by exactly two triangles (open_edges)."""
    return len(open_edges(triangles, vertices))


def open_edges(triangles: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """(k,2) vertex indices of the edges not shared by exactly two
    triangles. Vertices at the same position count as one, so meshes split
    for UVs or sharp edges still read as closed; triangles that repeat a
    vertex, and copies of a triangle, are left out. The answer depends only
    on which vertices coincide and on the triangles, so the last meshes'
    answers are kept by those: a mesh that only moved (an animation, Live)
    is not analysed again."""
    weld = _weld(vertices)
    digest = hashlib.sha1(weld.tobytes())
    digest.update(np.ascontiguousarray(triangles, dtype=np.int64).tobytes())
    key = digest.digest()
    with _SEEN_LOCK:
        if key in _SEEN:
            _SEEN.move_to_end(key)
            return _SEEN[key]
    edges = _open_edges(triangles, weld)
    with _SEEN_LOCK:
        _SEEN[key] = edges
        while len(_SEEN) > _SEEN_KEPT:
            _SEEN.popitem(last=False)
    return edges


def _weld(vertices: np.ndarray) -> np.ndarray:
    """(nv,) labels of the vertices, equal where their positions are (to
    1e-9), numbered in the order they first appear, so that they stay the
    same when the mesh moves."""
    ids = row_ids(np.round(vertices, 9))
    first = np.full(int(ids.max(initial=-1)) + 1, len(ids), dtype=np.int64)
    np.minimum.at(first, ids, np.arange(len(ids)))
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return rank[ids]


def _open_edges(triangles: np.ndarray, weld: np.ndarray) -> np.ndarray:
    """open_edges of `triangles (nt,3)` whose vertices are welded as `weld (nv,)` says."""
    a, b, c = np.sort(weld[triangles], axis=1).T
    # sorted, a triangle that repeats a vertex repeats it in neighbours
    proper = (a != b) & (b != c)
    a, b, c = a[proper], b[proper], c[proper]
    n = int(weld.max(initial=0)) + 1
    # a triangle's sorted corners as one number, up to 2^21 vertices
    keys = (a * n + b) * n + c if n < 1 << 21 else row_ids(np.stack([a, b, c], axis=1))
    first = np.unique(keys, return_index=True)[1]
    a, b, c = a[first], b[first], c[first]
    # with a <= b <= c each edge is already (low, high)
    edges, counts = np.unique(np.concatenate([a * n + b, b * n + c, a * n + c]), return_counts=True)
    edges = edges[counts != 2]
    vertex_of = np.empty(n, dtype=np.int64)
    vertex_of[weld] = np.arange(len(weld))
    return vertex_of[np.stack([edges // n, edges % n], axis=1)]


def mesh_pieces(triangles: np.ndarray, corner_keys: np.ndarray, group: np.ndarray) -> np.ndarray:
    """(nt,) labels 0..k-1 of the pieces of a mesh: triangles of one
    `group (nt,)` joined through shared edges, an edge being two corners of
    equal keys (`corner_keys (nt,3)` int64: welded positions, or positions
    and UVs for UV islands). Connected components by hooking and pointer
    jumping (Shiloach and Vishkin 1982): each round hooks the larger root
    of every edge whose ends differ onto the smaller, then points every
    triangle at its root; a few rounds, each a numpy pass over the edges
    still between pieces."""
    nt = len(triangles)
    if nt == 0:
        return np.zeros(0, dtype=np.int64)
    a, b = corner_keys, np.roll(corner_keys, -1, axis=1)
    edges = np.stack([np.minimum(a, b).ravel(), np.maximum(a, b).ravel(), np.repeat(group, 3)], axis=1)
    owner = np.repeat(np.arange(nt), 3)
    key = row_ids(edges)
    order = np.argsort(key, kind="stable")
    same = key[order][1:] == key[order][:-1]
    left, right = owner[order][:-1][same], owner[order][1:][same]
    root = np.arange(nt)
    while True:
        low, high = np.minimum(root[left], root[right]), np.maximum(root[left], root[right])
        apart = np.flatnonzero(low != high)
        if len(apart) == 0:
            break
        left, right = left[apart], right[apart]
        np.minimum.at(root, high[apart], low[apart])
        while True:
            up = root[root]
            if np.array_equal(up, root):
                break
            root = up
    return np.unique(root, return_inverse=True)[1].reshape(-1)
