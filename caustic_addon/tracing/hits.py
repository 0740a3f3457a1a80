"""What a batch of rays hit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..util.jit import inline
from ..util.rows import take, true_rows

# The object and triangle index of a ray that hit nothing.
MISS = -1


@inline
def inside1(medium, obj, body):
    """Is a ray in `medium` (an object, or MISS in air) inside the body of
    object `obj`? `body (m,)` per object, the first object of its body.
    Both are looked up whatever `medium` is: read under a branch, `body`
    took an atomic reference count a call, which the two threads' calls
    fought over (util.jit.inline); the bounce's `_oriented` spent 5% of the
    pool's frame there."""
    return (medium != MISS) & (body[max(medium, 0)] == body[obj])


@dataclass
class Hits:
    """Closest hits of a batch of n rays.

    t       (n,) float64 distance travelled to the hit, inf on a miss
    obj     (n,) int64 object index into Accelerator.objects, MISS on a miss
    prim    (n,) int64 global triangle index (over all objects), MISS on a miss
    u, v    (n,) float64 Embree barycentrics: p = (1-u-v) p0 + u p1 + v p2
    points  (n,3) float64 world hit points; the ray's origin on a miss
    """

    t: np.ndarray
    obj: np.ndarray
    prim: np.ndarray
    u: np.ndarray
    v: np.ndarray
    points: np.ndarray

    @staticmethod
    def misses(origins: np.ndarray) -> "Hits":
        """n rays from `origins (n,3)` that hit nothing."""
        n = len(origins)
        return Hits(np.full(n, np.inf), np.full(n, MISS, dtype=np.int64), np.full(n, MISS, dtype=np.int64),
                    np.zeros(n), np.zeros(n), np.array(origins, dtype=np.float64).reshape(n, 3))

    @staticmethod
    def empty(n: int) -> "Hits":
        """n hits to be filled in (tracing.accelerator decodes Embree's into them)."""
        return Hits(np.empty(n), np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64), np.empty(n),
                    np.empty(n), np.empty((n, 3)))

    @property
    def hit(self) -> np.ndarray:
        return self.obj != MISS

    def select(self, mask: np.ndarray) -> "Hits":
        """The hits where `mask (n,)` is True: these very hits where it is
        True throughout."""
        index = true_rows(np.ascontiguousarray(mask, dtype=bool))
        return self if len(index) == len(self.t) else self.take(index)

    def take(self, index: np.ndarray) -> "Hits":
        """The hits `index (k,)` int64, in that order."""
        return Hits(*(take(a, index) for a in (self.t, self.obj, self.prim, self.u, self.v, self.points)))

    def span(self, start: int, stop: int) -> "Hits":
        """The hits start .. stop - 1, views of these."""
        return Hits(*(a[start:stop] for a in (self.t, self.obj, self.prim, self.u, self.v, self.points)))

    def replace(self, index: np.ndarray, other: "Hits") -> None:
        """Overwrite the hits at `index (k,)` with `other`'s k hits."""
        for name in ("t", "obj", "prim", "u", "v", "points"):
            getattr(self, name)[index] = getattr(other, name)


# The numba type of each field, for the kernels that take hit arrays by
# name (util.jit.named_kernel).
HIT_TYPES = {"t": "f8[::1]", "obj": "i8[::1]", "prim": "i8[::1]", "u": "f8[::1]", "v": "f8[::1]",
             "points": "f8[:, ::1]"}
