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

from typing import Optional

import numpy as np

from ..util.rows import take_rows
from ..util.vectors import dot
from .hits import MISS, Hits

# Faces closer than this many epsilons touch.
CONTACT_EPSILONS = 2.0
# The re-cast's half-length along the ray is CONTACT_EPSILONS epsilons
# across the surface: longer for a glancing ray, up to 1 / _MIN_COSINE times.
_MIN_COSINE = 0.05
# Barycentric coordinates of the points each caster face is probed at: its
# centre and three points toward its corners.
_PROBE_BARYCENTRICS = np.array([[1 / 3, 1 / 3, 1 / 3], [0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]])


class _Subscene:
    """An Embree scene of some of the accelerator's objects, `members (k,)`
    object indices, in geomID order."""

    def __init__(self, accel, members: list[int]):
        view = accel.view_of(np.asarray(members, dtype=np.int64))
        self.accel, self.embree, self.members = accel, view.embree, view.objects

    def closest(self, origins: np.ndarray, dirs: np.ndarray, dists: np.ndarray) -> Hits:
        """Closest hits within `dists (n,)` of rays `origins, dirs (n,3)`, in the accelerator's indices."""
        self.accel.count_rays(len(origins))
        if len(origins) == 0:
            return self.accel.as_hits({}, origins, self.members)
        raw = self.embree.run(np.ascontiguousarray(origins, dtype=np.float32),
                              np.ascontiguousarray(dirs, dtype=np.float32),
                              dists=np.ascontiguousarray(dists, dtype=np.float32), output=1)
        return self.accel.as_hits(raw, origins, self.members)


class Contacts:
    """Where the accelerator's objects touch.

    boxes     object index -> (lo (3,), hi (3,)): a box around the region
              where it touches another object, CONTACT_EPSILONS epsilons wider
    partners  object index -> the Embree scene of the objects it touches
    """

    def __init__(self, accel):
        self.accel = accel
        self.boxes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.partners: dict[int, _Subscene] = {}
        touching: dict[int, set[int]] = {}
        reach = CONTACT_EPSILONS * accel.epsilon
        bounds = [(o.mesh.vertices.min(axis=0) - reach, o.mesh.vertices.max(axis=0) + reach) for o in accel.objects]
        for a, obj in enumerate(accel.objects):
            # parts of one body (its materials) meet along edges, not faces
            near = [b for b in range(len(accel.objects))
                    if accel.body[b] != accel.body[a] and _overlap(bounds[a], bounds[b])]
            if not obj.is_caster or not near:
                continue
            for b, prims in self._probe(a, near, bounds).items():
                touching.setdefault(a, set()).add(b)
                touching.setdefault(b, set()).add(a)
                corners = np.take(accel.corners, prims, axis=0).reshape(-1, 3)
                box = (corners.min(axis=0) - reach, corners.max(axis=0) + reach)
                for index in (a, b):
                    self.boxes[index] = _union(self.boxes.get(index), box)
        for index, others in touching.items():
            self.partners[index] = _Subscene(accel, sorted(others))

    def _probe(self, a: int, near: list[int], bounds) -> dict[int, np.ndarray]:
        """{object b: the faces of caster `a` (global indices) that touch it}
        for the objects `near` whose boxes meet a's: probes along each face's
        normal, from CONTACT_EPSILONS epsilons behind to as far in front,
        at the points _PROBE_BARYCENTRICS."""
        accel = self.accel
        first, end = accel.prim_offset[a], accel.prim_offset[a + 1]
        corners = accel.corners[first:end]
        lo, hi = corners.min(axis=1), corners.max(axis=1)
        candidate = np.zeros(len(corners), dtype=bool)
        for b in near:
            candidate |= np.all((lo <= bounds[b][1]) & (hi >= bounds[b][0]), axis=1)
        candidate &= dot(accel.face_normal[first:end], accel.face_normal[first:end]) > 0.0
        prims = first + np.flatnonzero(candidate)
        if len(prims) == 0:
            return {}
        normal = np.repeat(np.take(accel.face_normal, prims, axis=0), len(_PROBE_BARYCENTRICS), axis=0)
        points = np.einsum("kj,ijc->ikc", _PROBE_BARYCENTRICS, np.take(accel.corners, prims, axis=0)).reshape(-1, 3)
        reach = CONTACT_EPSILONS * accel.epsilon
        hits = _Subscene(accel, near).closest(points - reach * normal, normal, np.full(len(points), 2.0 * reach))
        face = np.repeat(prims, len(_PROBE_BARYCENTRICS))
        found = {}
        for b in np.unique(hits.obj[hits.hit]):
            found[int(b)] = np.unique(face[hits.obj == b])
        return found

    def inside_box(self, obj: np.ndarray, points: np.ndarray) -> np.ndarray:
        """(n,) bool: `points (n,3)` lie in the contact box of their object `obj (n,)`."""
        inside = np.zeros(len(obj), dtype=bool)
        for index, (lo, hi) in self.boxes.items():
            mine = obj == index
            inside[mine] = np.all((points[mine] >= lo) & (points[mine] <= hi), axis=1)
        return inside

    def _recast(self, obj: np.ndarray, points: np.ndarray, dirs: np.ndarray, normals: np.ndarray) -> tuple[Hits, np.ndarray]:
        """The surfaces of the objects that `obj (n,)` touches that rays
        `dirs (n,3)` meet within CONTACT_EPSILONS epsilons (across faces of
        normals `normals (n,3)`) before or after `points (n,3)`: (hits, and
        the signed distance (n,) of each past the point along the ray)."""
        accel = self.accel
        half = CONTACT_EPSILONS * accel.epsilon / np.maximum(np.abs(dot(dirs, normals)), _MIN_COSINE)
        start = points - half[:, None] * dirs
        found = Hits(np.full(len(obj), np.inf), np.full(len(obj), MISS), np.full(len(obj), MISS),
                     np.zeros(len(obj)), np.zeros(len(obj)), points.copy())
        for index, scene in self.partners.items():
            mine = obj == index
            if mine.any():
                found.replace(np.flatnonzero(mine), scene.closest(*take_rows(mine, start, dirs, 2.0 * half)))
        return found, found.t - half

    def resolve(self, hits: Hits, origins: np.ndarray, dirs: np.ndarray, medium: np.ndarray,
                leaving: Optional[np.ndarray]) -> None:
        """Apply the two rules (module docstring) to `hits` of rays
        `origins, dirs (n,3)` inside `medium (n,)`, which scattered at the
        faces `leaving (n,)` (MISS: they started at a lamp or the camera).
        Changes `hits` in place."""
        accel = self.accel
        done = np.zeros(len(hits.t), dtype=bool)
        if leaving is not None:
            rows = np.flatnonzero(leaving != MISS)
            face = np.take(leaving, rows)
            normal, d = np.take(accel.face_normal, face, axis=0), np.take(dirs, rows, axis=0)
            side = np.where(dot(d, normal) < 0.0, -1.0, 1.0)
            points = np.take(origins, rows, axis=0) - (accel.epsilon * side)[:, None] * normal
            owner = np.take(accel.owner, face)
            near = self.inside_box(owner, points)
            rows, owner, points, d, normal = (a[near] for a in (rows, owner, points, d, normal))
            found, _ = self._recast(owner, points, d, normal)
            meets = found.hit & self._meets(found, owner, d, normal)
            rows = rows[meets]
            found = found.select(meets)
            found.t[:] = 0.0
            hits.replace(rows, found)
            done[rows] = True
        near = hits.hit & ~done
        near[near] = self.inside_box(hits.obj[near], hits.points[near])
        rows = np.flatnonzero(near)
        if len(rows) == 0:
            return
        mine = hits.select(near)
        d, ray_medium = np.take(dirs, rows, axis=0), np.take(medium, rows)
        found, past = self._recast(mine.obj, mine.points, d, np.take(accel.face_normal, mine.prim, axis=0))
        first = found.hit & self._other_first(mine, found, d, ray_medium)
        found.t = mine.t + past
        hits.replace(rows[first], found.select(first))

    def _meets(self, found: Hits, left: np.ndarray, dirs: np.ndarray, left_normal: np.ndarray) -> np.ndarray:
        """(n,) bool: a ray `dirs (n,3)` that leaves a face of object `left
        (n,)`, of normal `left_normal (n,3)`, meets the coincident surface
        `found`: if that is closed glass, when it enters it; else, if it
        leaves closed glass, when it goes to the side where the other
        surface lies (outside, where the two face each other; inside, where
        the other lies inside the glass, against its wall); else when it
        meets the other's front."""
        closed = self.accel.closed
        found_normal = np.take(self.accel.face_normal, np.maximum(found.prim, 0), axis=0)
        entering = dot(dirs, found_normal) < 0.0
        outward = dot(dirs, left_normal) > 0.0
        toward = outward == (dot(left_normal, found_normal) < 0.0)
        return np.where(closed[np.maximum(found.obj, 0)], entering, np.where(closed[left], toward, entering))

    def _other_first(self, mine: Hits, other: Hits, dirs: np.ndarray, medium: np.ndarray) -> np.ndarray:
        """(n,) bool: of two coincident surfaces, the ray `dirs (n,3)` in
        `medium (n,)` meets `other` before `mine`. Against closed glass, a
        surface facing it (a table under it) comes after the glass for a ray
        inside the glass and before it for one outside; a surface turned as
        its wall lies inside it (a pebble on its bottom) and comes first.
        Between two closed glasses, the one the ray is in comes first;
        between two open surfaces, a specular one before one that is not. A
        closed surface that the ray's medium contradicts is never chosen."""
        accel = self.accel
        o = np.maximum(other.obj, 0)
        other_normal = np.take(accel.face_normal, np.maximum(other.prim, 0), axis=0)
        apart = dot(np.take(accel.face_normal, mine.prim, axis=0), other_normal) < 0.0
        closed_mine, closed_other = accel.closed[mine.obj], accel.closed[o]
        in_mine, in_other = medium == mine.obj, medium == o
        specular = np.array([obj.is_caster for obj in accel.objects])
        choice = np.where(closed_mine & closed_other, in_other & ~in_mine,
                          np.where(closed_mine, ~apart | ~in_mine,
                                   np.where(closed_other, apart & in_other, specular[o] & ~specular[mine.obj])))
        consistent = ~closed_other | ((dot(dirs, other_normal) > 0.0) == in_other)
        return consistent & choice
def _overlap(a, b) -> bool:
    return bool(np.all(a[0] <= b[1]) and np.all(b[0] <= a[1]))


def _union(a, b):
    if a is None:
        return b
    return np.minimum(a[0], b[0]), np.maximum(a[1], b[1])
