"""The beam grid's bookkeeping, in compiled kernels: which cells' paths
diverge (refinement), the leaf cells' crack-free triangles, which of them
bound beams in one family, and the fallback photons' shares.

Vertices are keys on a grid 2^levels times finer than a source's, key =
base + row * width + col. A vertex's landings are found by a search in the
landings sorted by key (`LandingIndex`), galloping from where the last
element's were (neighbouring elements come one after the other), and an
element's (a cell's or a triangle's) corners share a family group when
each of them has a landing of that group. A vertex has at most one landing
of a group: a family is a whole path."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..maps.illumination_map import IlluminationMap
from ..maps.raster import signed_area1
from ..util.jit import inline, kernel
from ..util.rows import row_ids
from .bounce import SCATTERED

# A cell whose two triangles' landed areas differ by more than this factor is
# split (measured on the ball lens: lower factors spend paths for no gain).
REFINE_RATIO = 8.0
# Families whose throughput is below this (reflections off the outside, weak
# internal reflections) never split a cell: too little flux for the paths.
REFINE_THROUGHPUT = 0.2
# A cell's two triangles as corners (r, c), (r+s, c), (r, c+s), (r+s, c+s):
# cut along the main diagonal, and along the other one.
_MAIN_HALVES = np.array([[0, 1, 3], [0, 3, 2]])
_ANTI_HALVES = np.array([[0, 1, 2], [1, 3, 2]])


class LandingIndex:
    """Landings indexed by grid vertex, each with its family group: one
    (family, receiver, island of its chart, unless the chart `projects`
    beams into any island).

    vertex (n,) the landings' vertex keys, ascending; order (n,) the
    landing at each (stable: landings of one vertex in their order);
    group (n,) by landing."""

    def __init__(self, landings, maps: dict[int, IlluminationMap]):
        self.landings = landings
        projects = np.zeros(max(maps, default=-1) + 1, dtype=bool)
        for index, imap in maps.items():
            projects[index] = imap.chart.projects
        piece = np.where(projects[landings.obj], 0, landings.island)
        self.group = row_ids(np.stack([landings.family, landings.obj.astype(np.uint64),
                                       piece.astype(np.uint64)], axis=1))
        self.order = np.argsort(landings.vertex, kind="stable")
        self.vertex = np.ascontiguousarray(landings.vertex[self.order])


@inline
def _search_from(keys, key, hint):
    """The first index of `keys` (ascending) whose key is at least `key`,
    galloping from index `hint` (steps 1, 2, 4, ... toward it, then a
    binary search between the last two): O(log distance), so a run of
    look-ups of nearby keys, as neighbouring cells make, costs a few steps
    each."""
    n = len(keys)
    hint = min(max(hint, 0), n)
    step = 1
    if hint < n and keys[hint] < key:
        lo = hi = hint + 1
        while hi < n and keys[hi] < key:
            lo = hi + 1
            hi += step
            step *= 2
        hi = min(hi, n)
    else:
        lo = hi = hint
        while lo > 0 and keys[lo - 1] >= key:
            hi = lo - 1
            lo -= step
            step *= 2
        lo = max(lo, 0)
    while lo < hi:
        mid = (lo + hi) >> 1
        if keys[mid] < key:
            lo = mid + 1
        else:
            hi = mid
    return lo


@inline
def _ranges(vertex, corners, start, end):
    """The landings at each vertex of `corners (k,)`: at `order[start[k]:
    end[k]]` of the index (both (k,), filled in; `start` holds where the
    last element's corners were, where each search starts)."""
    for k in range(len(corners)):
        start[k] = end[k] = _search_from(vertex, corners[k], start[k])
        while end[k] < len(vertex) and vertex[end[k]] == corners[k]:
            end[k] += 1


@inline
def _all_landed(order, group, start, end, wanted, found):
    """Whether every corner, its landings at `order[start[k]:end[k]]`, has
    a landing of group `wanted`; their landings go to `found (k,)`."""
    for k in range(len(start)):
        found[k] = -1
        for p in range(start[k], end[k]):
            if group[order[p]] == wanted:
                found[k] = order[p]
                break
        if found[k] < 0:
            return False
    return True


@inline
def _toward_centre(row, col, size, width):
    """Whether a cell's main diagonal, (r, c) to (r+s, c+s), points at the
    grid's centre. The concentric map that lays the grid over an aim bends
    along the square's two diagonals, so a triangle across one lands
    distorted: its beam comes out too bright and its neighbour too dim, a
    dotted seam. Cut along the diagonal toward the centre, no triangle
    crosses them."""
    half = 0.5 * (width - 1)
    return (row + 0.5 * size - half) * (col + 0.5 * size - half) >= 0.0


@dataclass
class Cells:
    """Square cells of stacked grids: the corner `row, col (n,)` nearest
    each grid's origin and the edge `size (n,)`, in fine grid steps, on the
    grid whose vertex keys start at `base (n,)` (key = base + row * width +
    col)."""

    row: np.ndarray
    col: np.ndarray
    size: np.ndarray
    base: np.ndarray

    def corners(self, width: int) -> np.ndarray:
        """(n,4) vertex keys: (r, c), (r+s, c), (r, c+s), (r+s, c+s)."""
        row, col, size = self.row, self.col, self.size
        return self.base[:, None] + np.stack([row * width + col, (row + size) * width + col,
                                              row * width + col + size, (row + size) * width + col + size], axis=1)

    def take(self, rows) -> "Cells":
        return Cells(self.row[rows], self.col[rows], self.size[rows], self.base[rows])

    def split(self, rows: np.ndarray) -> "Cells":
        """These cells with those at `rows` (bool) cut in four."""
        cut = self.take(rows)
        half = cut.size // 2
        kept = self.take(~rows)
        return Cells(np.concatenate([kept.row, cut.row, cut.row + half, cut.row, cut.row + half]),
                     np.concatenate([kept.col, cut.col, cut.col, cut.col + half, cut.col + half]),
                     np.concatenate([kept.size] + [half] * 4),
                     np.concatenate([kept.base] + [cut.base] * 4))


def diverging(lookup: LandingIndex, cells: Cells, width: int) -> np.ndarray:
    """(n,) bool: the cells whose paths diverge (`_diverging`)."""
    land = lookup.landings
    return _diverging(lookup.vertex, lookup.order, lookup.group, land.throughput, (land.family & SCATTERED) != 0,
                      np.ascontiguousarray(land.xy), land.island, np.ascontiguousarray(cells.corners(width)),
                      cells.row, cells.col, cells.size, width)


@kernel("b1[::1](i8[::1], i8[::1], i8[::1], f8[::1], b1[::1], f8[:, ::1], i8[::1], i8[:, ::1], i8[::1], i8[::1], "
        "i8[::1], i8)")
def _diverging(vertex, order, group, throughput, scattered, xy, island, corners, row, col, size, width):
    """(n,) bool by cell `corners (n,4)` (of `row, col, size (n,)` on a
    grid `width` steps wide), whether its paths diverge: some but not all
    of its corners land in a family group of throughput at least
    REFINE_THROUGHPUT (a silhouette, total internal reflection), or, in a
    group all four land in, its two triangles (`_toward_centre`) land with
    opposite orientation (a fold of the caustic crosses it) or areas more
    than REFINE_RATIO apart, unless its corners land on different islands
    (across a box chart's seam chart areas do not compare). Paths a rough
    surface scattered (`scattered (landings,)`) part from every neighbour,
    and splitting would not bring them together: they split no cell. A
    cell one fine step across is never split."""
    split = np.zeros(len(corners), dtype=np.bool_)
    start, end, found = np.zeros(4, dtype=np.int64), np.empty(4, dtype=np.int64), np.empty(4, dtype=np.int64)
    for c in range(len(corners)):
        if size[c] <= 1:
            continue
        _ranges(vertex, corners[c], start, end)
        for k in range(4):
            for p in range(start[k], end[k]):
                landing = order[p]
                if (throughput[landing] >= REFINE_THROUGHPUT and not scattered[landing]
                        and not _all_landed(order, group, start, end, group[landing], found)):
                    split[c] = True
        halves = _MAIN_HALVES if _toward_centre(row[c], col[c], size[c], width) else _ANTI_HALVES
        for p in range(start[0], end[0]):
            if split[c] or not _all_landed(order, group, start, end, group[order[p]], found):
                continue
            a = signed_area1(xy[found[halves[0, 0]]], xy[found[halves[0, 1]]], xy[found[halves[0, 2]]])
            b = signed_area1(xy[found[halves[1, 0]]], xy[found[halves[1, 1]]], xy[found[halves[1, 2]]])
            small, large = min(abs(a), abs(b)), max(abs(a), abs(b))
            seam = (island[found[1]] != island[found[0]] or island[found[2]] != island[found[0]]
                    or island[found[3]] != island[found[0]])
            split[c] = not seam and (a * b <= 0.0 or large > REFINE_RATIO * small)
    return split


@inline
def _boundary_point(row, col, size, j):
    """(row, col) of point j, 0 <= j < 4 size, of the boundary of the cell
    at (row, col) of edge `size`, walked counter-clockwise in (col, row)
    from that corner: bottom, right, top, left."""
    side, along = j // size, j % size
    if side == 0:
        return row, col + along
    if side == 1:
        return row + along, col + size
    if side == 2:
        return row + size, col + size - along
    return row + size - along, col


@inline
def _is_traced(traced, key, hint):
    """(whether vertex `key` is in `traced (n,)`, ascending, which holds
    at least the cells' corners, so is not empty; where it is or would be),
    searched from index `hint`."""
    at = _search_from(traced, key, hint)
    return (at < len(traced)) & (traced[min(at, len(traced) - 1)] == key), at


def crack_free_triangles(cells: Cells, width: int, traced: np.ndarray):
    """Triangles over the leaf cells that share every traced vertex with
    their neighbours, so that beams of a split cell and of its unsplit
    neighbour meet without cracks. A cell with no traced point inside its
    edges is two triangles (`_toward_centre`); one with such points (a
    split neighbour's) is a fan from its centre through its boundary points
    in order.

    Returns (triangles (n,3) vertex keys, area (n,) in fine grid units
    squared, centres (k,) vertex keys of the fan centres, still to trace):
    the plain cells' first triangles, their second ones, then the fans."""
    return _crack_free_triangles(cells.row, cells.col, cells.size, cells.base, width, traced)


@kernel("Tuple((i8[:, ::1], f8[::1], i8[::1]))(i8[::1], i8[::1], i8[::1], i8[::1], i8, i8[::1])")
def _crack_free_triangles(row, col, size, base, width, traced):
    """`crack_free_triangles` of cells `row, col, size, base (n,)`."""
    kept = np.zeros(len(row), dtype=np.int64)
    at = 0
    for c in range(len(row)):
        for j in range(4 * size[c]):
            r, q = _boundary_point(row[c], col[c], size[c], j)
            found, at = _is_traced(traced, base[c] + r * width + q, at)
            if j % size[c] == 0 or found:
                kept[c] += 1
    fans = np.count_nonzero(kept > 4)
    plain = len(row) - fans
    triangles = np.empty((2 * plain + kept[kept > 4].sum(), 3), dtype=np.int64)
    area = np.empty(len(triangles))
    centres = np.empty(fans, dtype=np.int64)
    corners = np.empty(4, dtype=np.int64)
    done_plain, done_fans, t = 0, 0, 2 * plain
    for c in range(len(row)):
        r0, c0, s, b = row[c], col[c], size[c], base[c]
        if kept[c] <= 4:
            corners[0], corners[1] = b + r0 * width + c0, b + (r0 + s) * width + c0
            corners[2], corners[3] = b + r0 * width + c0 + s, b + (r0 + s) * width + c0 + s
            halves = _MAIN_HALVES if _toward_centre(r0, c0, s, width) else _ANTI_HALVES
            for h in range(2):
                for k in range(3):
                    triangles[done_plain + h * plain, k] = corners[halves[h, k]]
                area[done_plain + h * plain] = 0.5 * float(s * s)
            done_plain += 1
            continue
        cr, cc = r0 + s // 2, c0 + s // 2
        centre = b + cr * width + cc
        centres[done_fans] = centre
        done_fans += 1
        first = t
        for j in range(4 * s):
            r, q = _boundary_point(r0, c0, s, j)
            key = b + r * width + q
            found, at = _is_traced(traced, key, at)
            if j % s != 0 and not found:
                continue
            triangles[t, 0], triangles[t, 1] = centre, key
            if t > first:
                triangles[t - 1, 2] = key
            t += 1
        triangles[t - 1, 2] = triangles[first, 1]
        for f in range(first, t):
            ar, ac = (triangles[f, 1] - b) // width, (triangles[f, 1] - b) % width
            br, bc = (triangles[f, 2] - b) // width, (triangles[f, 2] - b) % width
            area[f] = 0.5 * abs((ac - cc) * (br - cr) - (ar - cr) * (bc - cc))
    return triangles, area, centres


def coherent_triangles(lookup: LandingIndex, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(triangle (b,), landings (b,3)): for every triangle of `triangles
    (n,3)` vertex keys, every family group all three corners landed in,
    with those landings; by triangle, then group."""
    return _coherent(lookup.vertex, lookup.order, lookup.group, np.ascontiguousarray(triangles))


@kernel("Tuple((i8[::1], i8[:, ::1]))(i8[::1], i8[::1], i8[::1], i8[:, ::1])")
def _coherent(vertex, order, group, elements):
    """`coherent_triangles` of `elements (n,k)`: their count first, then
    the sets themselves, each element's in order of group."""
    k = elements.shape[1]
    start, end, found = np.zeros(k, dtype=np.int64), np.empty(k, dtype=np.int64), np.empty(k, dtype=np.int64)
    count = 0
    for e in range(len(elements)):
        _ranges(vertex, elements[e], start, end)
        for p in range(start[0], end[0]):
            count += _all_landed(order, group, start, end, group[order[p]], found)
    element, landings = np.empty(count, dtype=np.int64), np.empty((count, k), dtype=np.int64)
    at = 0
    for e in range(len(elements)):
        _ranges(vertex, elements[e], start, end)
        first = at
        for p in range(start[0], end[0]):
            if not _all_landed(order, group, start, end, group[order[p]], found):
                continue
            i = at
            while i > first and group[landings[i - 1, 0]] > group[order[p]]:
                landings[i] = landings[i - 1]
                i -= 1
            element[at], landings[i] = e, found
            at += 1
    return element, landings


def fallback_shares(lookup: LandingIndex, triangles: np.ndarray, measure: np.ndarray, beam_triangle: np.ndarray,
                    beam_landings: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """(landings,) the emission measure each landing carries as a photon: a
    third of that of every triangle of `triangles (n,3)` (measure `measure
    (n,)`) at whose corner it landed, unless its group is one of the
    triangle's beams (`coherent_triangles`' `beam_triangle (b,)`,
    `beam_landings (b,3)`) that is `kept (b,)`."""
    return _fallback_shares(lookup.vertex, lookup.order, lookup.group, np.ascontiguousarray(triangles), measure,
                            beam_triangle, np.take(lookup.group, beam_landings[:, 0]), kept)


@kernel("f8[::1](i8[::1], i8[::1], i8[::1], i8[:, ::1], f8[::1], i8[::1], i8[::1], b1[::1])")
def _fallback_shares(vertex, order, group, triangles, measure, beam_triangle, beam_group, kept):
    """`fallback_shares`, the beams given by triangle and group
    `beam_group (b,)`, in that order; sums in the order of triangles,
    corners and landings."""
    share = np.zeros(len(order))
    start, end = np.zeros(3, dtype=np.int64), np.empty(3, dtype=np.int64)
    first = 0
    for t in range(len(triangles)):
        while first < len(beam_triangle) and beam_triangle[first] < t:
            first += 1
        _ranges(vertex, triangles[t], start, end)
        for k in range(3):
            for p in range(start[k], end[k]):
                landing = order[p]
                loose = True
                b = first
                while b < len(beam_triangle) and beam_triangle[b] == t:
                    if beam_group[b] == group[landing]:
                        loose = not kept[b]
                        break
                    b += 1
                if loose:
                    share[landing] += measure[t] / 3.0
    return share
