"""One Embree scene per render, shared by the photon pass and the eye pass.

embreex facts this module absorbs (see shared notes): tnear is always 0, so
callers offset secondary origins with `offset()`; Embree's Ng is unnormalised
and its sign follows Embree's winding, so we use our own outward face normals
instead; `run` releases the GIL, so batches are split over worker threads.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import fields

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from ..scene import Object
from ..util.vectors import length, normalize
from .contact import Contacts
from .hits import MISS, Hits
from .topology import open_edge_count, signed_volume, triangle_normals

_MIN_SPLIT = 8192
# Origins move this fraction of the scene's diagonal off a surface: well above
# float32 hit-distance error (~1e-7 relative), well below features we resolve.
EPSILON_FRACTION = 2e-6
# Faces of closed meshes met from the side the ray's medium rules out are
# passed, at most this many times per ray and call (see Accelerator.intersect).
_MAX_SKIPS = 4
# Triangles per closed dielectric probed for walls thinner than epsilon.
_THICKNESS_PROBES = 1 << 13
# Directions that `medium_at` looks along, and vote over: fixed, and unlikely
# to line up with a mesh's edges.
_PROBE_DIRS = normalize(np.array([[0.2672, 0.5345, 0.8018], [-0.7071, 0.1104, -0.6984], [0.5774, -0.8083, 0.1155]]))
# Kinds of ray, for the objects' ray visibility: eye rays before any
# specular event, after a reflection, after a refraction; shadow rays.
CAMERA, REFLECTED, REFRACTED, SHADOW = 0, 1, 2, 3
# The scene.Visibility flag each kind of ray obeys.
_VISIBILITY_FLAGS = ("camera", "glossy", "transmission", "shadow")


def _same_material(a, b) -> bool:
    """Whether materials `a` and `b` are equal field by field (arrays by
    value, anything else, such as a texture's nodes, by identity)."""

    def equal(x, y) -> bool:
        numeric = (np.ndarray, np.generic, float, int)
        if isinstance(x, numeric) and isinstance(y, numeric):
            return bool(np.array_equal(x, y))
        return x is y

    return type(a) is type(b) and all(equal(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))


class _View:
    """The objects one kind of ray sees, in an Embree scene of their own:
    `objects (k,)` maps its geometry ids to object indices; `embree` is None
    where that kind of ray sees nothing."""

    def __init__(self, embree, objects: np.ndarray):
        self.embree, self.objects = embree, objects


class Accelerator:
    """The scene's triangles in one Embree BVH, with per-triangle shading data.

    body (m,) int64 per object: the index of the first object of its body
    (scene.Object.body); surface (m,) int64: the first object of its body
    with an equal material, what paths crossing from one to the other
    cannot tell apart; closed (m,) bool: a dielectric whose body has no
    holes, so that a ray's own state can track its inside.

    Per global triangle index (all objects' triangles, in object order):
      corners        (N,3,3) world positions of the corners
      face_normal    (N,3) unit geometric normal, facing out of closed meshes
      corner_normal  (N,3,3) unit shading normals at the corners, same side
      min_barycentric (N,3) the barycentric coordinate, per corner, of a point
                     epsilon from the opposite edge (at most 0.3)
      owner          (N,) index of the object the triangle belongs to

    Each kind of ray (CAMERA, REFLECTED, REFRACTED, SHADOW) sees the objects
    whose scene.Visibility lets it; a kind that does not see them all gets an
    Embree scene of its own.
    """

    def __init__(self, objects: list[Object], extent: float, threads: int = 2):
        self.objects = objects
        self.epsilon = EPSILON_FRACTION * extent
        self.threads = max(1, threads)
        self.warnings: list[str] = []
        self.rays_cast = 0
        self._count_lock = threading.Lock()
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None

        bodies: dict[str, list[int]] = {}
        for index, obj in enumerate(objects):
            bodies.setdefault(obj.body_name, []).append(index)
        self.body = np.empty(len(objects), dtype=np.int64)
        self.surface = np.arange(len(objects), dtype=np.int64)
        self.closed = np.zeros(len(objects), dtype=bool)
        sign = np.ones(len(objects))
        for members in bodies.values():
            self.body[members] = members[0]
            for k, index in enumerate(members[1:], 1):
                self.surface[index] = next(j for j in members[:k + 1]
                                           if _same_material(objects[j].material, objects[index].material))
            glass = [i for i in members if objects[i].is_transparent]
            if glass:
                self.closed[glass], sign[glass] = self._body_orientation(members)
        all_corners, face_normals, corner_normals, areas, owners, offsets = [], [], [], [], [], [0]
        for index, obj in enumerate(objects):
            mesh = obj.mesh
            corners = mesh.corners
            normals, area = triangle_normals(corners)
            normals *= sign[index]
            if mesh.corner_normals is None:
                shading = np.repeat(normals[:, None, :], 3, axis=1)
            else:
                shading = mesh.corner_normals * sign[index]
            all_corners.append(corners)
            face_normals.append(normals)
            areas.append(area)
            corner_normals.append(shading)
            owners.append(np.full(len(normals), index, dtype=np.int64))
            offsets.append(offsets[-1] + len(normals))

        self.corners = np.concatenate(all_corners) if all_corners else np.zeros((0, 3, 3))
        self.min_barycentric = self._min_barycentric(self.corners, np.concatenate(areas) if areas else np.zeros(0))
        self.face_normal = np.concatenate(face_normals) if face_normals else np.zeros((0, 3))
        self.corner_normal = np.concatenate(corner_normals) if corner_normals else np.zeros((0, 3, 3))
        self.owner = np.concatenate(owners) if owners else np.zeros(0, dtype=np.int64)
        self.prim_offset = np.asarray(offsets, dtype=np.int64)
        self._all = self.view_of(np.arange(len(objects)))
        self._views = self._ray_views()
        for body in np.unique(self.body[self.closed]):
            self._warn_if_thin(int(body))
        self.contacts = Contacts(self)
        self.rays_cast = 0  # counts the passes' rays, not the probes'

    def view_of(self, indices: np.ndarray) -> _View:
        """The objects `indices (k,)` in an Embree scene."""
        if len(indices) == 0:
            return _View(None, indices)
        embree = rtcore_scene.EmbreeScene()
        for index in indices:
            mesh = self.objects[index].mesh
            TriangleMesh(embree, mesh.vertices.astype(np.float32), mesh.triangles.astype(np.int32))
        return _View(embree, np.asarray(indices, dtype=np.int64))

    def _ray_views(self) -> list[_View]:
        """The _View each kind of ray sees, by kind; kinds that see the same
        objects share one."""
        views, built = [], {}
        for flag in _VISIBILITY_FLAGS:
            seen = np.flatnonzero([getattr(o.visibility, flag) for o in self.objects])
            if len(seen) == len(self.objects):
                views.append(self._all)
            else:
                if tuple(seen) not in built:
                    built[tuple(seen)] = self.view_of(seen)
                views.append(built[tuple(seen)])
        return views

    def _body_orientation(self, members: np.ndarray) -> tuple[bool, float]:
        """(closed, +1 or -1) of the body made of objects `members (k,)`:
        whether its surface has no holes, and whether its winding faces out
        (+1) or in (-1); a warning names it when it is open or inside out."""
        meshes = [self.objects[i].mesh for i in members]
        starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
        triangles = np.concatenate([m.triangles + start for m, start in zip(meshes, starts)])
        vertices = np.concatenate([m.vertices for m in meshes])
        name = self.objects[members[0]].body_name
        if open_edge_count(triangles, vertices) != 0:
            self.warnings.append(
                f"'{name}' is not a closed mesh: inside and outside are guessed per hit "
                "from its normals, so light may leak through its holes")
            return False, 1.0
        if signed_volume(np.take(vertices, triangles, axis=0)) < 0.0:
            self.warnings.append(f"'{name}' has inverted normals; they were flipped for tracing")
            return True, -1.0
        return True, 1.0

    def _min_barycentric(self, corners: np.ndarray, area: np.ndarray) -> np.ndarray:
        """(N,3) epsilon / altitude onto each corner's opposite edge, where
        altitude = 2 area / edge length; at most 0.3 (tiny triangles).
        `area (N,)` of each triangle."""
        opposite = np.stack([length(corners[:, (k + 1) % 3] - corners[:, (k + 2) % 3]) for k in range(3)], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            fraction = self.epsilon * opposite / (2.0 * area[:, None])
        return np.where(np.isfinite(fraction), np.minimum(fraction, 0.3), 0.3)

    def _warn_if_thin(self, body: int) -> None:
        """Warn when closed body `body` has a wall thinner than epsilon: a ray
        offset off one side would start beyond the other. Probes from up to
        _THICKNESS_PROBES face centres, evenly spread over the body's glass,
        half an epsilon inside, along the inward normal; on a larger mesh a
        thin wall of only a few faces can go unprobed."""
        prim = np.flatnonzero(np.isin(self.owner, np.flatnonzero(self.closed & (self.body == body))))
        prim = prim[np.unique(np.linspace(0, len(prim) - 1, min(len(prim), _THICKNESS_PROBES)).astype(np.int64))]
        prim = prim[np.linalg.norm(self.face_normal[prim], axis=1) > 0.0]
        inward = -self.face_normal[prim]
        hits = self._closest(self.corners[prim].mean(axis=1) + 0.5 * self.epsilon * inward, inward)
        mine = hits.hit & (np.take(self.body, np.maximum(hits.obj, 0)) == body)
        if np.any(mine & (hits.t < 0.5 * self.epsilon)):
            self.warnings.append(
                f"'{self.objects[body].body_name}' is thinner than the tracing epsilon ({self.epsilon:.2g} m) in "
                "places: light crosses such a wall as if it were one surface")

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()

    def count_rays(self, n: int) -> None:
        with self._count_lock:
            self.rays_cast += n

    def _run(self, embree, origins: np.ndarray, dirs: np.ndarray, **kwargs) -> list[dict]:
        """Embree scene `embree` over the batch, split across threads; one result dict per part."""
        n = len(origins)
        self.count_rays(n)
        o32 = np.ascontiguousarray(origins, dtype=np.float32)
        d32 = np.ascontiguousarray(dirs, dtype=np.float32)
        dists = kwargs.pop("dists", None)
        if self._pool is None or n < _MIN_SPLIT:
            return [embree.run(o32, d32, dists=dists, **kwargs)]
        bounds = np.linspace(0, n, self.threads + 1).astype(int)
        parts = [(bounds[i], bounds[i + 1]) for i in range(self.threads)]
        futures = [self._pool.submit(embree.run, o32[a:b], d32[a:b],
                                     dists=None if dists is None else dists[a:b], **kwargs)
                   for a, b in parts]
        return [f.result() for f in futures]

    def intersect(self, origins: np.ndarray, dirs: np.ndarray, medium: np.ndarray | None = None,
                  kind: np.ndarray | None = None, leaving: np.ndarray | None = None) -> Hits:
        """Closest hits of rays `origins (n,3)`, `dirs (n,3)` (unit), world space.

        With `kind (n,)`, CAMERA, REFLECTED or REFRACTED per ray, each ray
        sees only the objects visible to its kind; without, every object.

        With `medium (n,)`, the closed object each ray is inside (MISS if
        none), a face of a closed mesh met from the side the medium rules out
        (entering the body the ray is in, or leaving one it is not in) is
        passed: the ray goes on from just beyond it, and `t` adds up the legs.
        Such hits are float32 artefacts: the neighbour of the face just
        crossed, met again at t ~ 0 past a shared edge; a face turned away
        from a ray that only touches a vertex; the far side of a crack in
        Embree's non-watertight triangle test. Passing them keeps a ray's
        medium true to the side of the surface it is on. Where objects
        touch, coincident surfaces are met in the order contact.py gives,
        `leaving (n,)` being the face each ray scattered at (MISS if none)."""
        hits = self._closest_by_kind(origins, dirs, kind)
        if medium is None:
            return hits
        for _ in range(_MAX_SKIPS):
            skip = np.flatnonzero(self._contradicts(hits, dirs, medium))
            if len(skip) == 0:
                break
            face = np.take(self.face_normal, hits.prim[skip], axis=0)
            start = self.offset(hits.points[skip], face, dirs[skip])
            again = self._closest_by_kind(start, dirs[skip], None if kind is None else kind[skip])
            again.t += hits.t[skip] + length(start - hits.points[skip])
            hits.replace(skip, again)
        if self.contacts.boxes:
            self.contacts.resolve(hits, origins, dirs, medium, leaving)
        return hits

    def inside(self, medium: np.ndarray, obj: np.ndarray) -> np.ndarray:
        """(n,) bool: is a ray in `medium (n,)` (an object, or MISS in air)
        inside the body of `obj (n,)`?"""
        return (medium != MISS) & (np.take(self.body, np.maximum(medium, 0)) == np.take(self.body, obj))

    def medium_at(self, points: np.ndarray) -> np.ndarray:
        """(n,) the closed object each of `points (n,3)` is inside, MISS if
        none: along each of three fixed directions, the first closed mesh
        met from behind (its inside) holds the point; the three vote by
        body, so a ray through a crack between triangles cannot decide alone."""
        if not self.closed.any():
            return np.full(len(points), MISS, dtype=np.int64)
        votes = []
        for direction in _PROBE_DIRS:
            dirs = np.broadcast_to(direction, points.shape)
            origins = np.array(points, dtype=np.float64)
            found = np.full(len(points), MISS, dtype=np.int64)
            open_hit = np.arange(len(points))
            for _ in range(_MAX_SKIPS):
                hits = self._closest(origins[open_hit], dirs[open_hit])
                closed = hits.hit.copy()
                closed[closed] = self.closed[hits.obj[closed]]
                behind = np.einsum("ij,ij->i", dirs[open_hit], self.face_normal[np.maximum(hits.prim, 0)]) > 0.0
                found[open_hit[closed & behind]] = hits.obj[closed & behind]
                through = hits.hit & ~closed
                origins[open_hit[through]] = self.offset(hits.points[through], np.take(self.face_normal, hits.prim[through], axis=0),
                                                         dirs[open_hit[through]])
                open_hit = open_hit[through]
                if len(open_hit) == 0:
                    break
            votes.append(found)
        a, b, c = votes
        body_a, body_b, body_c = (np.where(v == MISS, MISS, np.take(self.body, np.maximum(v, 0))) for v in votes)
        return np.where((body_a == body_b) | (body_a == body_c), a, b)

    def _contradicts(self, hits: Hits, dirs: np.ndarray, medium: np.ndarray) -> np.ndarray:
        """(n,) bool: hits on closed meshes from the side the ray's medium rules out."""
        closed = hits.hit.copy()
        closed[closed] = self.closed[hits.obj[closed]]
        index = np.flatnonzero(closed)
        toward = np.einsum("ij,ij->i", dirs[index], np.take(self.face_normal, hits.prim[index], axis=0)) < 0.0
        closed[index] = toward == self.inside(medium[index], hits.obj[index])
        return closed

    def _closest_by_kind(self, origins: np.ndarray, dirs: np.ndarray, kind: np.ndarray | None) -> Hits:
        """Closest hits, each ray among the objects its `kind (n,)` sees (None: all)."""
        if kind is None or all(view is self._all for view in self._views[:SHADOW]):
            return self._closest(origins, dirs)
        kinds = np.unique(kind)
        if len(kinds) == 1:
            return self._closest(origins, dirs, self._views[kinds[0]])
        hits = Hits.misses(origins)
        for k in kinds:
            rows = np.flatnonzero(kind == k)
            hits.replace(rows, self._closest(np.take(origins, rows, axis=0), np.take(dirs, rows, axis=0),
                                             self._views[k]))
        return hits

    def _closest(self, origins: np.ndarray, dirs: np.ndarray, view: _View | None = None) -> Hits:
        """Closest hits among the objects of `view` (None: all of them)."""
        view = self._all if view is None else view
        if len(origins) == 0 or view.embree is None:
            return self.as_hits({}, origins, view.objects)
        parts = self._run(view.embree, origins, dirs, output=1)
        raw = {key: np.concatenate([p[key] for p in parts]) for key in ("geomID", "primID", "tfar", "u", "v")}
        return self.as_hits(raw, origins, view.objects)

    def as_hits(self, raw: dict, origins: np.ndarray, members: np.ndarray) -> Hits:
        """Hits from embreex's output `raw` for rays from `origins (n,3)`,
        cast in an Embree scene whose geomIDs are the objects `members`;
        every ray a miss where `raw` is empty."""
        if not raw:
            return Hits.misses(origins)
        geom = raw["geomID"].astype(np.int64)
        miss = geom < 0
        # a miss takes the MISS appended to `members`, which may be empty
        obj = np.take(np.append(np.asarray(members, dtype=np.int64), MISS), np.where(miss, len(members), geom))
        t = np.where(miss, np.inf, raw["tfar"].astype(np.float64))
        u, v = raw["u"].astype(np.float64), raw["v"].astype(np.float64)
        prim = np.where(miss, MISS, raw["primID"].astype(np.int64) + self.prim_offset[np.maximum(obj, 0)])
        points = origins.astype(np.float64, copy=True)
        hit = np.flatnonzero(~miss)
        points[hit] = self.surface_points(prim[hit], u[hit], v[hit])
        return Hits(t, obj, prim, u, v, points)

    def surface_points(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(n,3) float64 points of triangles `prim` at Embree's barycentrics,
        each kept epsilon inside its triangle's edges. A float32 hit can fall
        just past an edge; a ray leaving from there would already be beyond
        the neighbouring face's plane and miss it."""
        bary = np.stack([1.0 - u - v, u, v], axis=1)
        bary = np.maximum(bary, np.take(self.min_barycentric, prim, axis=0))
        bary /= (bary[:, 0] + bary[:, 1] + bary[:, 2])[:, None]
        return np.einsum("ij,ijk->ik", bary, np.take(self.corners, prim, axis=0))

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, dists: np.ndarray) -> np.ndarray:
        """(n,) bool: is anything that casts shadows between `origins` and
        `origins + dists * dirs`?"""
        embree = self._views[SHADOW].embree
        if len(origins) == 0 or embree is None:
            return np.zeros(len(origins), dtype=bool)
        parts = self._run(embree, origins, dirs, query="OCCLUDED",
                          dists=np.ascontiguousarray(dists, dtype=np.float32))
        return np.concatenate(parts) != MISS

    def shading_normal(self, prim: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(n,3) unit shading normals, interpolated from the corner normals
        with Embree's barycentrics; the face normal where they cancel out."""
        w = 1.0 - u - v
        c = np.take(self.corner_normal, prim, axis=0)
        n = w[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        size = length(n)
        bad = ~(size > 1e-12)
        n[bad] = self.face_normal[prim[bad]]
        size[bad] = 1.0
        return n / size[:, None]

    def offset(self, points: np.ndarray, normals: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """Ray origins (n,3) nudged off the surface along the geometric normal
        to the side `dirs` leave toward, so the new ray cannot hit it again."""
        side = np.sign(np.einsum("ij,ij->i", normals, dirs))
        side[side == 0] = 1.0
        return points + (self.epsilon * side)[:, None] * normals
