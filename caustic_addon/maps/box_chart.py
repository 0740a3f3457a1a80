"""The chart a curved receiver without a UV map gets: a box projection,
made per render, written nowhere.

Each triangle goes to the face of the world's axis box that its normal
points at most (+X, -X, +Y, -Y, +Z or -Z: the largest component, ties
broken toward z, then y, by AXIS_BIAS) and projects along that axis onto
the face's plane: (y, z) for X, (z, x) for Y, (x, y) for Z, in metres. A
projection along the axis keeps chart area = world area * |n_axis| (at
least 1/sqrt(3)), each triangle's area scale.

A face's triangles can overlap in projection: a bowl's outer wall at +x and
its inner wall at -x both face +X. The face's pieces (triangles joined by
edges) are sorted by depth along the axis; pieces whose depth ranges
overlap stay together, and consecutive ones share an island while their
projections do not overlap (tested on a coverage raster, exact-area,
ISLAND_RASTER cells across the face). So each island is a depth slab of
one face, and a shader tells them apart from the true normal and the
position alone (writeback/bake_group.py). Islands are laid out in one
chart in rows, a gutter apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.geometry import Mesh
from ..tracing.topology import mesh_pieces, triangle_normals
from ..util.rows import row_ids
from .charts import Chart, ImageFrame, covered_share
from .raster import rasterise_triangles

# Weights on |n_x|, |n_y|, |n_z| before the largest is taken: a triangle
# whose normal is within 1% of a tie (a cube turned 45 degrees) goes to the
# later axis, here and in a shader whose float32 normal is a little off.
AXIS_BIAS = np.array([1.0, 1.01, 1.02])
# The chart axes (u, v) of each projection axis: (y, z), (z, x), (x, y).
PLANE_AXES = np.array([[1, 2], [2, 0], [0, 1]])
# Cells across a face's coverage raster, and the coverage above which two
# projections overlap (adjacent triangles share cells, summing to 1).
ISLAND_RASTER = 256
_OVERLAP = 1.02


@dataclass
class BoxIsland:
    """One island: the triangles of box face `axis` (0, 1, 2 for X, Y, Z),
    `negative` (facing -axis), whose depth along the axis lies in [depth_lo,
    depth_hi) (-inf and inf at the ends), projected to the world axes
    `plane` (PLANE_AXES[axis]) and moved by `shift (2,)` metres into the
    chart. A triangle's face is the largest of |n| * `bias` (AXIS_BIAS)."""

    axis: int
    negative: bool
    depth_lo: float
    depth_hi: float
    shift: np.ndarray
    plane: tuple = ()
    bias: tuple = ()

    def __post_init__(self):
        self.plane = tuple(int(a) for a in PLANE_AXES[self.axis])
        self.bias = tuple(float(b) for b in AXIS_BIAS)


class BoxChart(Chart):
    """A receiver's box projection. `overlaps`: the faces (names) whose
    islands still overlap themselves, where pieces at one depth cross in
    projection (a spiral ramp): their caustics mix there."""

    def __init__(self, mesh: Mesh):
        normals, _ = triangle_normals(mesh.corners)
        self.axis = np.argmax(np.abs(normals) * AXIS_BIAS, axis=1)
        component = np.take_along_axis(normals, self.axis[:, None], axis=1)[:, 0]
        self.negative = component < 0.0
        self._area_scale = np.abs(component)
        corners = mesh.corners
        self._flat = np.take_along_axis(corners, PLANE_AXES[self.axis][:, None, :], axis=2)
        depth = np.take_along_axis(corners, self.axis[:, None, None], axis=2)[..., 0]
        keys = row_ids(np.round(mesh.vertices, 9))[mesh.triangles]
        pieces = mesh_pieces(mesh.triangles, keys, 2 * self.axis + self.negative)
        self.island = np.zeros(len(corners), dtype=np.int64)
        self.islands: list[BoxIsland] = []
        self.overlaps: list[str] = []
        for face in range(6):
            mine = np.flatnonzero(2 * self.axis + self.negative == face)
            if len(mine):
                self._split_face(face, mine, pieces[mine], depth[mine])
        self.lay_out(0.0)

    def _split_face(self, face: int, tris: np.ndarray, pieces: np.ndarray, depth: np.ndarray) -> None:
        """Islands of the face's triangles `tris (k,)`, of pieces `pieces
        (k,)` and corner depths `depth (k,3)`: runs of pieces that overlap in
        depth, in order, grouped while their projections stay apart."""
        labels, piece = np.unique(pieces, return_inverse=True)
        lo = np.full(len(labels), np.inf)
        hi = np.full(len(labels), -np.inf)
        np.minimum.at(lo, piece, depth.min(axis=1))
        np.maximum.at(hi, piece, depth.max(axis=1))
        order = np.argsort(lo, kind="stable")
        # a new run where a piece starts above every piece before it
        reach = np.maximum.accumulate(hi[order])
        run_of_piece = np.empty(len(labels), dtype=np.int64)
        run_of_piece[order] = np.cumsum(np.r_[True, lo[order][1:] > reach[:-1]]) - 1
        run = run_of_piece[piece]
        flat = self._flat[tris]
        base, span = flat.reshape(-1, 2).min(axis=0), np.ptp(flat.reshape(-1, 2), axis=0)
        cell = max(float(span.max()), 1e-12) / ISLAND_RASTER
        shape = tuple(np.maximum(np.ceil(span / cell).astype(int), 1)[::-1] + 1)
        coverage = [rasterise_triangles(shape, (flat[run == r] - base) / cell, np.ones((int((run == r).sum()), 1)))[0]
                    for r in range(run.max() + 1)]
        if any(c.max() > _OVERLAP for c in coverage):
            self.overlaps.append(("+" if face % 2 == 0 else "-") + "XYZ"[face // 2])
        run_lo = np.array([depth[run == r].min() for r in range(len(coverage))])
        run_hi = np.array([depth[run == r].max() for r in range(len(coverage))])
        start, held = 0, coverage[0].copy()
        for r in range(1, len(coverage) + 1):
            if r < len(coverage) and (held + coverage[r]).max() <= _OVERLAP:
                held += coverage[r]
                continue
            depth_lo = -np.inf if start == 0 else 0.5 * (run_hi[start - 1] + run_lo[start])
            depth_hi = np.inf if r == len(coverage) else 0.5 * (run_hi[r - 1] + run_lo[r])
            self.island[tris[(run >= start) & (run < r)]] = len(self.islands)
            self.islands.append(BoxIsland(face // 2, bool(face % 2), depth_lo, depth_hi, np.zeros(2)))
            if r < len(coverage):
                start, held = r, coverage[r].copy()

    def lay_out(self, gutter: float) -> None:
        """Place the islands in rows, tallest first, `gutter` metres apart
        and from the chart's edge, in rows about as long as the square of
        their total area; sets each island's shift and the chart's origin
        and size."""
        count = len(self.islands)
        lo, hi = np.full((count, 2), np.inf), np.full((count, 2), -np.inf)
        flat = self._flat.reshape(-1, 2)
        owner = np.repeat(self.island, 3)
        for k in range(2):
            np.minimum.at(lo[:, k], owner, flat[:, k])
            np.maximum.at(hi[:, k], owner, flat[:, k])
        size = hi - lo
        row_length = max(np.sqrt(((size[:, 0] + gutter) * (size[:, 1] + gutter)).sum()), size[:, 0].max() + gutter)
        x = y = gutter
        row_height = 0.0
        for k in np.argsort(-size[:, 1], kind="stable"):
            if x > gutter and x + size[k, 0] > row_length:
                x, y, row_height = gutter, y + row_height + gutter, 0.0
            self.islands[k].shift = np.array([x, y]) - lo[k]
            x += size[k, 0] + gutter
            row_height = max(row_height, size[k, 1])
        self._shift = np.array([island.shift for island in self.islands])
        self._island_axis = np.array([island.axis for island in self.islands])
        self.origin = np.zeros(2)
        self.size = (flat + np.take(self._shift, owner, axis=0)).max(axis=0) + gutter

    def coords(self, prim, u, v, points):
        flat = np.take_along_axis(points, PLANE_AXES[self.axis[prim]], axis=1)
        return flat + np.take(self._shift, self.island[prim], axis=0)

    def area_scale(self, prim):
        return self._area_scale[prim]

    def islands_of(self, prim):
        return self.island[prim]

    projects = True

    def project(self, island, points):
        flat = np.take_along_axis(points, PLANE_AXES[self._island_axis[island]][:, None, :], axis=2)
        return flat + np.take(self._shift, island, axis=0)[:, None, :]

    def coverage(self, origin, cell, shape):
        return covered_share(self._flat + np.take(self._shift, self.island, axis=0)[:, None, :], origin, cell, shape)

    def image_frame(self, corner, extent):
        return ImageFrame("BOX", np.array([corner[0], corner[1], 0.0]), np.eye(3),
                          np.array([extent[0], extent[1], 1.0]), tuple(self.islands))
