"""Surfaces of different objects that touch: a glass standing on a table or
on a mirror, a pebble lying on the bottom of a glass of water.

Where two surfaces coincide (coplanar faces, or faces closer than
CONTACT_EPSILONS epsilons), a ray meets both at one distance and Embree
returns either; and a ray that leaves one starts epsilon off it
(`Accelerator.offset`), already past the other. A ray leaving a glass
through its base started below the table and missed it, and rays through
the base hit the glass or the table at random: salt-and-pepper noise
through the base, which a 1 mm gap removed.

Within the boxes around the regions where objects touch, found once per
render by short probes from each caster's faces, two rules order the
coincident surfaces by the ray's own side of them, as two solids in contact
would (Cycles gets the same by excluding the face a ray leaves):

- a ray that meets two coincident surfaces meets first the closed glass it
  is inside (it leaves it before it meets the table), or, outside, the
  other surface (the table, or a mirror, before the glass behind it);
- a ray that leaves a surface there toward the other meets it at once: out
  of a glass's base onto the table, off a mirror into the glass standing
  on it.

Each rule casts the ray again, epsilon before and after the point, against
an Embree scene of the touching objects only, so it can find the other
surface without meeting the first.
"""

from __future__ import annotations

import weakref
from typing import Optional

import numpy as np

from ..util.jit import inline, kernel
from ..util.rows import contiguous, take, take_rows, true_rows
from ..util.vectors import dot, dot1, row, set_row, sum1
from .hits import MISS, Hits, inside1
from .triangles import TRIANGLES_TYPE, face_normal1, owner1

# Faces closer than this many epsilons touch.
CONTACT_EPSILONS = 2.0
# The re-cast's half-length along the ray is CONTACT_EPSILONS epsilons
# across the surface: longer for a glancing ray, up to 1 / _MIN_COSINE times.
_MIN_COSINE = 0.05
# Triangles of one object probed at a time, which bounds the probes' memory.
_BATCH = 1 << 20
# Barycentric coordinates of the points each caster face is probed at: its
# centre and three points toward its corners.
_PROBE_BARYCENTRICS = np.array([[1 / 3, 1 / 3, 1 / 3], [0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]])


class _Subscene:
    """An Embree scene of some of the accelerator's objects, `members (k,)`
    object indices, in geomID order."""

    def __init__(self, accel, members: list[int]):
        self.accel, self.view = accel, accel.view_of(np.asarray(members, dtype=np.int64))

    def closest(self, origins: np.ndarray, dirs: np.ndarray, dists: np.ndarray) -> Hits:
        """Closest hits within `dists (n,)` of rays `origins, dirs (n,3)`, in the accelerator's indices."""
        return self.accel.closest_in(self.view, origins, dirs, dists)


class Contacts:
    """Where the accelerator's objects touch.

    boxes     object index -> (lo (3,), hi (3,)): a box around the region
              where it touches another object, CONTACT_EPSILONS epsilons wider
    partners  object index -> the Embree scene of the objects it touches
    """

    def __init__(self, accel):
        # weak, as the accelerator owns its contacts: a cycle would keep its
        # Embree scenes and tables alive until Python's cyclic collector runs
        self.accel = weakref.proxy(accel)
        self.boxes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.partners: dict[int, _Subscene] = {}
        touching: dict[int, set[int]] = {}
        reach = CONTACT_EPSILONS * accel.epsilon
        # each object's box, (objects,3) corners
        lo = np.array([o.mesh.bounds[0] - reach for o in accel.objects]).reshape(-1, 3)
        hi = np.array([o.mesh.bounds[1] + reach for o in accel.objects]).reshape(-1, 3)
        for a, obj in enumerate(accel.objects):
            if not obj.is_caster:
                continue
            # parts of one body (its materials) meet along edges, not faces
            near = np.flatnonzero((accel.body != accel.body[a]) & np.all(lo[a] <= hi, axis=1)
                                  & np.all(lo <= hi[a], axis=1)).tolist()
            if not near:
                continue
            for b, prims in self._probe(a, near, lo, hi).items():
                touching.setdefault(a, set()).add(b)
                touching.setdefault(b, set()).add(a)
                corners = accel.corner_points(np.full(len(prims), a), prims).reshape(-1, 3)
                box = (corners.min(axis=0) - reach, corners.max(axis=0) + reach)
                for index in (a, b):
                    self.boxes[index] = _union(self.boxes.get(index), box)
        for index, others in touching.items():
            self.partners[index] = _Subscene(self.accel, sorted(others))
        # the boxes as (objects,3) corners, empty (inf, -inf) where an object has none
        self.lo, self.hi = np.full((len(accel.objects), 3), np.inf), np.full((len(accel.objects), 3), -np.inf)
        for index, (lo, hi) in self.boxes.items():
            self.lo[index], self.hi[index] = lo, hi
        self.caster = np.array([o.is_caster for o in accel.objects], dtype=bool)

    def _probe(self, a: int, near: list[int], box_lo: np.ndarray, box_hi: np.ndarray) -> dict[int, np.ndarray]:
        """{object b: the faces of caster `a` (global indices) that touch it}
        for the objects `near` whose boxes (`box_lo`, `box_hi` (objects,3)
        corners) meet a's: probes along each face's
        normal, from CONTACT_EPSILONS epsilons behind to as far in front,
        at the points _PROBE_BARYCENTRICS."""
        accel = self.accel
        prims, corners, normals = [], [], []
        for first in range(accel.prim_offset[a], accel.prim_offset[a + 1], _BATCH):
            prim = np.arange(first, min(first + _BATCH, accel.prim_offset[a + 1]))
            owner = np.full(len(prim), a)
            corner, normal = accel.corner_points(owner, prim), accel.face_normals(owner, prim)
            lo, hi = corner.min(axis=1), corner.max(axis=1)
            candidate = np.zeros(len(prim), dtype=bool)
            for b in near:
                candidate |= np.all((lo <= box_hi[b]) & (hi >= box_lo[b]), axis=1)
            candidate &= dot(normal, normal) > 0.0
            prims.append(prim[candidate])
            corners.append(corner[candidate])
            normals.append(normal[candidate])
        prims = np.concatenate(prims)
        if len(prims) == 0:
            return {}
        normal = np.repeat(np.concatenate(normals), len(_PROBE_BARYCENTRICS), axis=0)
        points = np.einsum("kj,ijc->ikc", _PROBE_BARYCENTRICS, np.concatenate(corners)).reshape(-1, 3)
        reach = CONTACT_EPSILONS * accel.epsilon
        hits = _Subscene(accel, near).closest(points - reach * normal, normal, np.full(len(points), 2.0 * reach))
        face = np.repeat(prims, len(_PROBE_BARYCENTRICS))
        found = {}
        for b in np.unique(hits.obj[hits.hit]):
            found[int(b)] = np.unique(face[hits.obj == b])
        return found

    def _recast(self, obj: np.ndarray, points: np.ndarray, dirs: np.ndarray, normals: np.ndarray) -> tuple[Hits, np.ndarray]:
        """The surfaces of the objects that `obj (n,)` touches that rays
        `dirs (n,3)` meet within CONTACT_EPSILONS epsilons (across faces of
        normals `normals (n,3)`) before or after `points (n,3)`: (hits, and
        the signed distance (n,) of each past the point along the ray)."""
        n = len(obj)
        half, start = np.empty(n), np.empty((n, 3))
        _recast_rays(points, dirs, normals, CONTACT_EPSILONS * self.accel.epsilon, half, start)
        found = Hits(np.full(n, np.inf), np.full(n, MISS), np.full(n, MISS), np.zeros(n), np.zeros(n), points.copy())
        for index, scene in self.partners.items():
            mine = obj == index
            if mine.any():
                found.replace(true_rows(mine), scene.closest(*take_rows(mine, start, dirs, 2.0 * half)))
        return found, found.t - half

    def resolve(self, hits: Hits, origins: np.ndarray, dirs: np.ndarray, medium: np.ndarray, outer: np.ndarray,
                leaving: Optional[np.ndarray]) -> None:
        """Apply the two rules (module docstring) to `hits` of rays
        `origins, dirs (n,3)` inside `medium` over `outer (n,)`, which scattered at the
        faces `leaving (n,)` (MISS: they started at a lamp or the camera).
        Changes `hits` in place."""
        accel, n, f8, i8 = self.accel, len(hits.t), np.float64, np.int64
        dirs, medium = contiguous(dirs, f8), contiguous(medium, i8)
        done = np.zeros(n, dtype=bool)
        if leaving is not None:
            rows, owner, points, normal = np.empty(n, dtype=i8), np.empty(n, dtype=i8), np.empty((n, 3)), np.empty((n, 3))
            count = _left_in_boxes(contiguous(leaving, i8), contiguous(origins, f8), dirs, accel.triangles,
                                   accel.prim_offset, accel.epsilon, self.lo, self.hi, rows, owner, points, normal)
            rows, owner, points, normal = rows[:count], owner[:count], points[:count], normal[:count]
            d = take(dirs, rows)
            found, _ = self._recast(owner, points, d, normal)
            meets = true_rows(_meeting(found.obj, found.prim, owner, d, take(medium, rows), take(outer, rows), normal,
                                       accel.triangles, accel.closed, accel.body))
            rows, found = take(rows, meets), found.take(meets)
            found.t[:] = 0.0
            hits.replace(rows, found)
            done[rows] = True
        rows = np.empty(n, dtype=i8)
        rows = rows[:_hits_in_boxes(contiguous(hits.obj, i8), contiguous(hits.points, f8), done, self.lo, self.hi, rows)]
        if len(rows) == 0:
            return
        mine = hits.take(rows)
        d = take(dirs, rows)
        found, past = self._recast(mine.obj, mine.points, d, accel.face_normals(mine.obj, mine.prim))
        first = true_rows(_other_first(mine.obj, mine.prim, found.obj, found.prim, d, take(medium, rows),
                                       accel.triangles, accel.closed, self.caster))
        found.t = mine.t + past
        hits.replace(take(rows, first), found.take(first))


@inline
def in_box1(lo, hi, o, p):
    """The point `p` lies in the box `lo[o]`..`hi[o]` ((objects,3)) of object `o`."""
    return ((lo[o, 0] <= p[0]) & (p[0] <= hi[o, 0]) & (lo[o, 1] <= p[1]) & (p[1] <= hi[o, 1])
            & (lo[o, 2] <= p[2]) & (p[2] <= hi[o, 2]))


@kernel(f"i8(i8[::1], f8[:, ::1], f8[:, ::1], {TRIANGLES_TYPE}, i8[::1], f8, f8[:, ::1], f8[:, ::1], "
        "i8[::1], i8[::1], f8[:, ::1], f8[:, ::1])")
def _left_in_boxes(leaving, origins, dirs, triangles, prim_offset, epsilon, lo, hi, rows, owners, points, normals):
    """The rays that scattered at a face `leaving[i]` (not MISS) whose
    point on it, `origins[i]` less the epsilon offset1 put it off, lies in
    the contact box of the face's object: into `rows`, `owners`, `points`
    and `normals` (the face's); returns how many."""
    count = 0
    for i in range(len(leaving)):
        face = leaving[i]
        if face == MISS:
            continue
        owner = owner1(prim_offset, face)
        normal = face_normal1(triangles, owner, face)
        side = -1.0 if dot1(row(dirs, i), normal) < 0.0 else 1.0
        point = sum1(1.0, row(origins, i), -(epsilon * side), normal)
        if in_box1(lo, hi, owner, point):
            rows[count], owners[count] = i, owner
            set_row(points, count, point)
            set_row(normals, count, normal)
            count += 1
    return count


@kernel("i8(i8[::1], f8[:, ::1], b1[::1], f8[:, ::1], f8[:, ::1], i8[::1])")
def _hits_in_boxes(obj, points, done, lo, hi, rows):
    """The hits not `done` that lie in their object's contact box, into `rows`; returns how many."""
    count = 0
    for i in range(len(obj)):
        if obj[i] != MISS and not done[i] and in_box1(lo, hi, obj[i], row(points, i)):
            rows[count] = i
            count += 1
    return count


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8, f8[::1], f8[:, ::1])")
def _recast_rays(points, dirs, normals, reach, half, start):
    """The re-cast of each ray: `half (n,)` its half-length, `reach` (the
    CONTACT_EPSILONS epsilons) over |d.n|, at least _MIN_COSINE, and
    `start (n,3)` that far back along the ray from its point."""
    for i in range(len(points)):
        half[i] = reach / max(abs(dot1(row(dirs, i), row(normals, i))), _MIN_COSINE)
        set_row(start, i, sum1(1.0, row(points, i), -half[i], row(dirs, i)))


@inline
def meets1(d, found_normal, left_normal, found_closed, left_closed):
    """A ray `d` that leaves a face of normal `left_normal` meets the
    coincident surface of normal `found_normal`: if that is closed glass,
    when it enters it; else, if it leaves closed glass, when it goes to the
    side where the other surface lies (outside, where the two face each
    other; inside, where the other lies inside the glass, against its wall);
    else when it meets the other's front."""
    entering = dot1(d, found_normal) < 0.0
    if found_closed or not left_closed:
        return entering
    return (dot1(d, left_normal) > 0.0) == (dot1(left_normal, found_normal) < 0.0)


@kernel(f"b1[::1](i8[::1], i8[::1], i8[::1], f8[:, ::1], i8[::1], i8[::1], f8[:, ::1], {TRIANGLES_TYPE}, b1[::1], "
        "i8[::1])")
def _meeting(found_obj, found_prim, left, dirs, medium, outer, left_normal, triangles, closed, body):
    """(n,) bool: the re-cast found a surface that the ray leaving object
    `left (n,)` meets (meets1), and not closed glass that its media
    `medium, outer (n,)` say it is in already (glass it crossed into
    through a joined surface, tracing/joins.py)."""
    out = np.zeros(len(left), dtype=np.bool_)
    for i in range(len(left)):
        o = found_obj[i]
        if o != MISS:
            inside = inside1(medium[i], o, body) | inside1(outer[i], o, body)
            out[i] = meets1(row(dirs, i), face_normal1(triangles, o, found_prim[i]), row(left_normal, i), closed[o],
                            closed[left[i]]) and not (closed[o] and inside)
    return out


@inline
def other_first1(d, medium, mine, other, mine_normal, other_normal, closed_mine, closed_other, caster_mine,
                 caster_other):
    """Of two coincident surfaces of objects `mine` and `other`, the ray
    `d` in `medium` meets `other` before `mine`. Against closed glass, a
    surface facing it (a table under it) comes after the glass for a ray
    inside the glass and before it for one outside; a surface turned as
    its wall lies inside it (a pebble on its bottom) and comes first.
    Between two closed glasses, the one the ray is in comes first; between
    two open surfaces, a specular one (a caster) before one that is not. A
    closed surface that the ray's medium contradicts is never chosen."""
    apart = dot1(mine_normal, other_normal) < 0.0
    in_mine, in_other = medium == mine, medium == other
    if closed_mine and closed_other:
        choice = in_other and not in_mine
    elif closed_mine:
        choice = (not apart) or (not in_mine)
    elif closed_other:
        choice = apart and in_other
    else:
        choice = caster_other and not caster_mine
    consistent = (not closed_other) or ((dot1(d, other_normal) > 0.0) == in_other)
    return consistent and choice


@kernel(f"b1[::1](i8[::1], i8[::1], i8[::1], i8[::1], f8[:, ::1], i8[::1], {TRIANGLES_TYPE}, b1[::1], b1[::1])")
def _other_first(mine_obj, mine_prim, other_obj, other_prim, dirs, medium, triangles, closed, caster):
    """(n,) bool: the re-cast found another surface that the ray meets first (other_first1)."""
    out = np.zeros(len(mine_obj), dtype=np.bool_)
    for i in range(len(mine_obj)):
        m, o = mine_obj[i], other_obj[i]
        if o != MISS:
            out[i] = other_first1(row(dirs, i), medium[i], m, o, face_normal1(triangles, m, mine_prim[i]),
                                  face_normal1(triangles, o, other_prim[i]), closed[m], closed[o], caster[m], caster[o])
    return out


def _union(a, b):
    if a is None:
        return b
    return np.minimum(a[0], b[0]), np.maximum(a[1], b[1])
