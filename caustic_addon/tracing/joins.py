"""Closed glass and water that lie against each other: a liquid in its glass,
a glass block on another. Light that leaves one enters the other through a
single interface of the ratio of their indices, as it does where a liquid
wets the glass; two interfaces with air between would reflect twice and
totally reflect where the single one lets light through.

Artists model such a pair with the two surfaces coincident, a hair apart,
or overlapping as Cycles users do. An overlap needs nothing here: the ray
enters the second while still inside the first, and the nested media of
passes/bounce.crossing1 carry it. Where the surfaces coincide or a gap
lies between them, a ray that leaves the first for the air probes along
its way, from CONTACT_EPSILONS epsilons behind its point to JOIN_SHARE of
the smaller object's size ahead, for a surface of the other that it enters.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..util.rows import take
from .contact import CONTACT_EPSILONS, _recast_rays, _Subscene
from .hits import MISS

# The widest gap between two closed dielectrics that counts as none: this
# share of the smaller one's box diagonal (0.8 mm for a 10 cm tumbler's
# 8 cm liquid).
JOIN_SHARE = 0.01


class Joins:
    """Which closed dielectrics lie against which.

    has_partners  (m,) bool per object: some closed dielectric of another body
                  lies within its gap
    gap           (m,) the widest gap each object's probe spans
    partners      object index -> the Embree scene of those objects
    """

    def __init__(self, accel):
        self.accel = weakref.proxy(accel)
        m = len(accel.objects)
        self.has_partners, self.gap = np.zeros(m, dtype=bool), np.zeros(m)
        self.partners: dict[int, _Subscene] = {}
        closed = np.flatnonzero(accel.closed)
        if len(closed) < 2:
            return
        lo = np.array([accel.objects[i].mesh.bounds[0] for i in closed])
        hi = np.array([accel.objects[i].mesh.bounds[1] for i in closed])
        size = np.linalg.norm(hi - lo, axis=1)
        for k, a in enumerate(closed):
            gap = JOIN_SHARE * np.minimum(size, size[k])
            near = ((accel.body[closed] != accel.body[a]) & np.all(lo - gap[:, None] <= hi[k], axis=1)
                    & np.all(lo[k] <= hi + gap[:, None], axis=1))
            if near.any():
                self.has_partners[a], self.gap[a] = True, gap[near].max()
                self.partners[int(a)] = _Subscene(self.accel, closed[near].tolist())

    def entered(self, obj: np.ndarray, prim: np.ndarray, points: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,) the partner of `obj (n,)` whose surface rays that leave it
        through faces `prim (n,)` at `points (n,3)` along `dirs (n,3)` enter
        within its gap, MISS if none: the first such surface met from
        CONTACT_EPSILONS epsilons back across the face."""
        accel, found = self.accel, np.full(len(obj), MISS, dtype=np.int64)
        for index, scene in self.partners.items():
            rows = np.flatnonzero(obj == index)
            if len(rows) == 0:
                continue
            d, back, start = take(dirs, rows), np.empty(len(rows)), np.empty((len(rows), 3))
            _recast_rays(take(points, rows), d, accel.face_normals(take(obj, rows), take(prim, rows)),
                         CONTACT_EPSILONS * accel.epsilon, back, start)
            hits = scene.closest(start, d, back + self.gap[index])
            front = hits.hit.copy()
            front[front] = np.einsum("ij,ij->i", d[front], accel.face_normals(hits.obj[front], hits.prim[front])) < 0.0
            found[rows[front]] = hits.obj[front]
        return found
