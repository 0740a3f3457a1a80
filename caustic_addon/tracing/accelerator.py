"""One Embree scene per render, shared by the photon pass and the eye pass.

Embree facts this module absorbs (tracing/embree.py has the rest): tnear is
0, so callers offset secondary origins with `offset()`; Embree's Ng is
unnormalised and its sign follows Embree's winding, so we use our own
outward face normals instead; the casting kernels release the GIL, so
batches are split over worker threads.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import fields

import numpy as np

from ..scene import Mesh, Object
from ..util.jit import inline, kernel, named_kernel
from ..util.parallel import threads_here
from ..util.rows import contiguous
from ..util.vectors import dot1, float_rows, length, normalize, normalize1, row, set_row, sum1
from . import embree
from .contact import Contacts
from .embree import PACKET, intersect1, occluded8, packet_blocked, packet_record, ray_record, set_packet_ray
from .hits import HIT_TYPES, MISS, Hits, inside1
from .joins import Joins
from .prototypes import PROTOTYPES, Prototype
from .topology import open_edges, signed_volume
from .triangles import TRIANGLES_TYPE, corner_points, face_normal1, face_normals, normal_transforms, normals1, \
    surface_point1

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
    """Some of the objects in an Embree scene of their own: `objects (k,)`
    maps its geometry ids to object indices; `scene` is None where there
    are none."""

    def __init__(self, scene: embree.Scene | None, objects: np.ndarray):
        self.scene, self.objects = scene, objects


# The numba type of each of the Accelerator's tables, by the name kernels
# give it (util.jit.named_kernel): `surface_of` is its `surface`.
GEOMETRY_TYPES = {"body": "i8[::1]", "surface_of": "i8[::1]", "closed": "b1[::1]", "triangles": TRIANGLES_TYPE,
                  "epsilon": "f8"}
# The numba type of what a cast takes: the Embree scene's handle, the rays,
# their lengths (none: unbounded), the objects its geometry ids stand for.
CAST_TYPES = {"scene": "u8", "origins": "f8[:, ::1]", "dirs": "f8[:, ::1]", "dists": "f8[::1]",
              "members": "i8[::1]"}


class Accelerator:
    """The scene's triangles in one Embree BVH, with their shading data.

    body (m,) int64 per object: the index of the first object of its body
    (scene.Object.body); surface (m,) int64: the first object of its body
    with an equal material, what paths crossing from one to the other
    cannot tell apart; closed (m,) bool: a dielectric whose body has no
    holes, so that a ray's own state can track its inside.

    triangles: the tables kernels read each triangle's corners and normals
    from (tracing/triangles.py), by global index (all objects' triangles,
    in object order, from prim_offset (m+1,)); an instancer's copies share
    their mesh's rows.

    Each kind of ray (CAMERA, REFLECTED, REFRACTED, SHADOW) sees the objects
    whose scene.Visibility lets it; a kind that does not see them all gets an
    Embree scene of its own.
    """

    def __init__(self, objects: list[Object], extent: float, threads: int = 2, quality: str = "medium"):
        self.objects = objects
        self.quality = quality
        self.epsilon = EPSILON_FRACTION * extent
        self.threads = max(1, threads)
        self.warnings: list[str] = []
        self.rays_cast = 0
        self._count_lock = threading.Lock()
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None

        # the instanced objects' meshes, kept between renders
        self._prototypes: dict[int, Prototype] = {i: PROTOTYPES.of(obj.instances.mesh, quality)
                                                  for i, obj in enumerate(objects) if obj.instances is not None}
        bodies: dict[str, list[int]] = {}
        for index, obj in enumerate(objects):
            bodies.setdefault(obj.body_name, []).append(index)
        self.body = np.empty(len(objects), dtype=np.int64)
        self.surface = np.arange(len(objects), dtype=np.int64)
        self.closed = np.zeros(len(objects), dtype=bool)
        copies = np.array([obj.copies for obj in objects], dtype=np.int64)
        placed = copies > 1
        rows_of = [obj.instances.mesh if placed[i] else obj.mesh for i, obj in enumerate(objects)]
        sizes = np.array([len(mesh.triangles) for mesh in rows_of], dtype=np.int64)
        self.prim_offset = np.concatenate([[0], np.cumsum(sizes * copies)]).astype(np.int64)
        row_offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        corners, face_normal = np.empty((row_offset[-1], 3, 3)), np.empty((row_offset[-1], 3))
        corner_normal, area = np.empty((row_offset[-1], 3, 3)), np.empty(row_offset[-1])
        for index, mesh in enumerate(rows_of):
            rows = slice(row_offset[index], row_offset[index + 1])
            _triangle_tables(mesh.vertices, mesh.triangles,
                             np.zeros((0, 3, 3)) if mesh.corner_normals is None else mesh.corner_normals,
                             corners[rows], face_normal[rows], corner_normal[rows], area[rows])
        has_area = [bool(np.any(area[row_offset[i]:row_offset[i + 1]] > 0)) for i in range(len(objects))]
        for name, members in bodies.items():
            if any(objects[i].is_caster for i in members) and not any(has_area[i] for i in members):
                self.warnings.append(f"'{name}' has no area (each of its faces is a line or a point): it casts "
                                     "no caustics and shows nothing")
        for members in bodies.values():
            self.body[members] = members[0]
            for k, index in enumerate(members[1:], 1):
                self.surface[index] = next(j for j in members[:k + 1]
                                           if _same_material(objects[j].material, objects[index].material))
            glass = [i for i in members if objects[i].is_transparent]
            if glass and any(has_area[i] for i in members):
                closed, sign = self._body_orientation(members)
                self.closed[glass] = closed
                for i in glass if sign < 0 else ():
                    face_normal[row_offset[i]:row_offset[i + 1]] *= -1.0
                    corner_normal[row_offset[i]:row_offset[i + 1]] *= -1.0
        min_barycentric = np.empty((row_offset[-1], 3))
        _min_barycentrics(corners, area, self.epsilon, min_barycentric)
        transforms = np.concatenate([np.eye(4)[None] if obj.instances is None else obj.instances.transforms
                                     for obj in objects] or [np.zeros((0, 4, 4))])
        self.triangles = (corners, face_normal, corner_normal, min_barycentric, self.prim_offset, row_offset[:-1],
                          np.maximum(sizes, 1), np.concatenate([[0], np.cumsum(copies)[:-1]]).astype(np.int64),
                          placed, np.ascontiguousarray(transforms[:, :3, :]), normal_transforms(transforms),
                          np.linalg.det(transforms[:, :3, :3]) < 0.0)
        self._geometries = [embree.Geometry(obj.mesh.vertices, obj.mesh.triangles) if obj.instances is None else
                            embree.Instances(self._prototypes[i].scene, obj.instances.transforms)
                            for i, obj in enumerate(objects)]
        self._built: dict[tuple, _View] = {}
        self._all = self.view_of(np.arange(len(objects)))
        self._views = self._ray_views()
        for body in np.unique(self.body[self.closed]):
            self._warn_if_thin(int(body))
        self.contacts = Contacts(self)
        self.joins = Joins(self)
        self.rays_cast = 0  # counts the passes' rays, not the probes'

    def view_of(self, indices: np.ndarray) -> _View:
        """The objects `indices (k,)` in an Embree scene, built at the
        accelerator's quality, once for each set of objects: the kinds of
        ray, the contacts' probes and partners and the joins' partners
        often ask for the same."""
        indices = np.asarray(indices, dtype=np.int64)
        key = tuple(indices.tolist())
        if key not in self._built:
            scene = embree.Scene([self._geometries[i] for i in indices], self.quality) if len(indices) else None
            self._built[key] = _View(scene, indices)
        return self._built[key]

    def _ray_views(self) -> list[_View]:
        """The _View each kind of ray sees, by kind."""
        return [self.view_of(np.flatnonzero([getattr(o.visibility, flag) for o in self.objects]))
                for flag in _VISIBILITY_FLAGS]

    def _body_orientation(self, members: np.ndarray) -> tuple[bool, float]:
        """(closed, +1 or -1) of the body made of objects `members (k,)`:
        whether its surface has no holes, and whether its winding faces out
        (+1) or in (-1); a warning names it when it is open or inside out.
        A body of one instanced object reads them off its mesh's prototype."""
        meshes = [_first_copy(self.objects[i]) for i in members]
        name = self.objects[members[0]].body_name
        if len(members) == 1 and members[0] in self._prototypes:
            vertices = meshes[0].vertices
            holes, inward = self._prototypes[members[0]].holes, self._prototypes[members[0]].inward
        else:
            vertices = np.concatenate([m.vertices for m in meshes])
            starts = np.cumsum([0] + [len(m.vertices) for m in meshes])
            triangles = np.concatenate([m.triangles + start for m, start in zip(meshes, starts)])
            holes = open_edges(triangles, vertices)
            inward = not len(holes) and signed_volume(np.take(vertices, triangles, axis=0)) < 0.0
        if len(holes):
            where = ", ".join(f"{float(c):.3g}" for c in vertices[holes[0]].mean(axis=0))
            self.warnings.append(
                f"'{name}' is not a closed mesh ({len(holes):,} edges have one face or more than two, as Select "
                f"Non-Manifold shows; the first near ({where})): inside and outside are guessed per hit "
                "from its normals, so light may leak through its holes")
            return False, 1.0
        if inward:
            self.warnings.append(f"'{name}' has inverted normals; they were flipped for tracing")
            return True, -1.0
        return True, 1.0

    def _warn_if_thin(self, body: int) -> None:
        """Warn when closed body `body` has a wall thinner than epsilon: a ray
        offset off one side would start beyond the other (`_thin`). A body
        of one placed mesh asks its prototype first: a glass dragged in Live
        is probed once for each rotation and scale, and each epsilon."""
        glass = np.flatnonzero(self.closed & (self.body == body))
        placed = int(glass[0]) if len(glass) == 1 and self.objects[glass[0]].copies == 1 else None
        prototype = self._prototypes.get(placed)
        key = None if prototype is None else (
            self.objects[placed].instances.transforms[0, :3, :3].tobytes(), self.epsilon)
        thin = None if prototype is None else prototype.thin.get(key)
        if thin is None:
            thin = self._thin(body, glass)
            if prototype is not None:
                prototype.thin[key] = thin
        if thin:
            self.warnings.append(
                f"'{self.objects[body].body_name}' is thinner than the tracing epsilon ({self.epsilon:.2g} m) in "
                "places: light crosses such a wall as if it were one surface")

    def _thin(self, body: int, glass: np.ndarray) -> bool:
        """Whether body `body`, of glass objects `glass (k,)`, has a wall
        thinner than epsilon, as probes from up to _THICKNESS_PROBES face
        centres, evenly spread over its glass, half an epsilon inside, along
        the inward normal, find; on a larger mesh a thin wall of only a few
        faces can go unprobed."""
        ends = np.cumsum(np.diff(self.prim_offset)[glass])
        spread = np.unique(np.linspace(0, ends[-1] - 1, min(ends[-1], _THICKNESS_PROBES)).astype(np.int64))
        which = np.searchsorted(ends, spread, side="right")
        obj = glass[which]
        prim = self.prim_offset[obj] + spread - (ends - np.diff(self.prim_offset)[glass])[which]
        inward = -self.face_normals(obj, prim)
        keep = np.linalg.norm(inward, axis=1) > 0.0
        obj, prim, inward = obj[keep], prim[keep], inward[keep]
        hits = self._closest(self.corner_points(obj, prim).mean(axis=1) + 0.5 * self.epsilon * inward, inward)
        mine = hits.hit & (np.take(self.body, np.maximum(hits.obj, 0)) == body)
        return bool(np.any(mine & (hits.t < 0.5 * self.epsilon)))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()

    def count_rays(self, n: int) -> None:
        with self._count_lock:
            self.rays_cast += n

    def _split(self, n: int, part) -> None:
        """`part(a, b)` over rows 0..n, split across the threads
        util.parallel.threads_here gives, each part on its own thread."""
        self.count_rays(n)
        threads = threads_here(self.threads)
        if threads == 1 or n < _MIN_SPLIT:
            part(0, n)
            return
        bounds = np.linspace(0, n, threads + 1).astype(int)
        for future in [self._pool.submit(part, bounds[i], bounds[i + 1]) for i in range(threads)]:
            future.result()

    def intersect(self, origins: np.ndarray, dirs: np.ndarray, medium: np.ndarray | None = None,
                  outer: np.ndarray | None = None, kind: np.ndarray | None = None,
                  leaving: np.ndarray | None = None) -> Hits:
        """Closest hits of rays `origins (n,3)`, `dirs (n,3)` (unit), world space.

        With `kind (n,)`, CAMERA, REFLECTED, REFRACTED or SHADOW per ray,
        each ray sees only the objects visible to its kind; without, every
        object.

        With `medium (n,)`, the closed object each ray is inside (MISS if
        none), and `outer (n,)` the one it is also inside beneath it (None:
        none; passes/paths.Paths), a face of a closed mesh met from the side
        these rule out (entering a body the ray is in, or leaving one it is
        not in) is passed: the ray goes on from just beyond it, and `t` adds up the legs.
        Such hits are float32 artefacts: the neighbour of the face just
        crossed, met again at t ~ 0 past a shared edge; a face turned away
        from a ray that only touches a vertex; the far side of a crack in
        Embree's non-watertight triangle test. Passing them keeps a ray's
        medium true to the side of the surface it is on. Where objects
        touch, coincident surfaces are met in the order contact.py gives,
        `leaving (n,)` being the face each ray scattered at (MISS if none)."""
        dirs = np.ascontiguousarray(dirs, dtype=np.float64)
        hits = self._closest_by_kind(origins, dirs, kind)
        if medium is None:
            return hits
        medium = np.ascontiguousarray(medium, dtype=np.int64)
        outer = np.full(len(dirs), MISS, dtype=np.int64) if outer is None else np.ascontiguousarray(outer, np.int64)
        for _ in range(_MAX_SKIPS):
            skip = np.flatnonzero(self._contradicts(hits, dirs, medium, outer))
            if len(skip) == 0:
                break
            face = self.face_normals(hits.obj[skip], hits.prim[skip])
            start = self.offset(hits.points[skip], face, dirs[skip])
            again = self._closest_by_kind(start, dirs[skip], None if kind is None else kind[skip])
            again.t += hits.t[skip] + length(start - hits.points[skip])
            hits.replace(skip, again)
        if self.contacts.boxes:
            self.contacts.resolve(hits, origins, dirs, medium, outer, leaving)
        return hits

    def media_at(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(medium, outer) (n,) each: the innermost closed object each of
        `points (n,3)` is inside (medium_at), and the innermost one of
        another body around that (a lamp in a glass ball inside water),
        MISS where none (passes/paths.Paths)."""
        medium, outer = self.medium_at(points), np.full(len(points), MISS, dtype=np.int64)
        for body in np.unique(np.take(self.body, medium[medium != MISS])):
            rows = np.flatnonzero((medium != MISS) & (np.take(self.body, np.maximum(medium, 0)) == body))
            others = self.view_of(np.flatnonzero(self.body != body))
            outer[rows] = self.medium_at(points[rows], others)
        return medium, outer

    def medium_at(self, points: np.ndarray, view: _View | None = None) -> np.ndarray:
        """(n,) the closed object each of `points (n,3)` is inside, MISS if
        none: along each of three fixed directions, the first closed mesh
        met from behind (its inside) holds the point; the three vote by
        body, so a ray through a crack between triangles cannot decide
        alone. Among the objects of `view` (None: all)."""
        if not self.closed.any():
            return np.full(len(points), MISS, dtype=np.int64)
        votes = []
        for direction in _PROBE_DIRS:
            dirs = np.broadcast_to(direction, points.shape)
            origins = np.array(points, dtype=np.float64)
            found = np.full(len(points), MISS, dtype=np.int64)
            open_hit = np.arange(len(points))
            for _ in range(_MAX_SKIPS):
                hits = self._closest(origins[open_hit], dirs[open_hit], view)
                closed = hits.hit.copy()
                closed[closed] = self.closed[hits.obj[closed]]
                normals = np.zeros((len(open_hit), 3))
                normals[hits.hit] = self.face_normals(hits.obj[hits.hit], hits.prim[hits.hit])
                behind = np.einsum("ij,ij->i", dirs[open_hit], normals) > 0.0
                found[open_hit[closed & behind]] = hits.obj[closed & behind]
                through = hits.hit & ~closed
                origins[open_hit[through]] = self.offset(hits.points[through], normals[through],
                                                         dirs[open_hit[through]])
                open_hit = open_hit[through]
                if len(open_hit) == 0:
                    break
            votes.append(found)
        a, b, c = votes
        body_a, body_b, body_c = (np.where(v == MISS, MISS, np.take(self.body, np.maximum(v, 0))) for v in votes)
        return np.where((body_a == body_b) | (body_a == body_c), a, b)

    def surface_at(self, points: np.ndarray) -> np.ndarray:
        """(n,) the object whose surface lies within epsilon of each of
        `points (n,3)` along one of six fixed directions, MISS if none. A ray
        that starts on a surface meets it at t = 0 (Embree's tnear is 0),
        whichever way it goes."""
        dirs = np.concatenate([_PROBE_DIRS, -_PROBE_DIRS])
        hits = self._closest(np.repeat(points, len(dirs), axis=0), np.tile(dirs, (len(points), 1)))
        near = (hits.hit & (hits.t <= self.epsilon)).reshape(len(points), len(dirs))
        first = near.argmax(axis=1)
        objects = hits.obj.reshape(len(points), len(dirs))[np.arange(len(points)), first]
        return np.where(near.any(axis=1), objects, MISS)

    def _contradicts(self, hits: Hits, dirs: np.ndarray, medium: np.ndarray, outer: np.ndarray) -> np.ndarray:
        """(n,) bool: hits on closed meshes from the side the ray's media
        `medium, outer (n,)` rule out, for rays `dirs (n,3)` (contiguous float64)."""
        out = np.empty(len(dirs), dtype=bool)
        _contradicting(hits.obj, hits.prim, dirs, medium, outer, self.closed, self.body, self.triangles, out)
        return out

    def _closest_by_kind(self, origins: np.ndarray, dirs: np.ndarray, kind: np.ndarray | None) -> Hits:
        """Closest hits, each ray among the objects its `kind (n,)` sees (None: all)."""
        if kind is None or all(view is self._all for view in self._views):
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
        return self.closest_in(self._all if view is None else view, origins, dirs)

    def closest_in(self, view: _View, origins: np.ndarray, dirs: np.ndarray, dists: np.ndarray | None = None) -> Hits:
        """Closest hits of rays `origins, dirs (n,3)` among the objects of
        `view`, within `dists (n,)` where given, each thread casting and
        decoding its own part of the batch (see _cast)."""
        if len(origins) == 0 or view.scene is None:
            self.count_rays(len(origins))
            return Hits.misses(origins)
        origins, dirs = float_rows(origins, dirs)
        dists = np.zeros(0) if dists is None else np.ascontiguousarray(dists, dtype=np.float64)
        hits = Hits.empty(len(origins))

        def part(a: int, b: int) -> None:
            _cast(scene=view.scene.handle, origins=origins[a:b], dirs=dirs[a:b], dists=dists[a:b],
                  members=view.objects, triangles=self.triangles, epsilon=self.epsilon,
                  **{f"out_{field}": getattr(hits, field)[a:b] for field in HIT_TYPES})

        self._split(len(origins), part)
        return hits

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, dists: np.ndarray) -> np.ndarray:
        """(n,) bool: is anything that casts shadows between `origins` and
        `origins + dists * dirs`?"""
        scene = self._views[SHADOW].scene
        out = np.zeros(len(origins), dtype=bool)
        if len(origins) == 0 or scene is None:
            self.count_rays(len(origins))
            return out
        origins, dirs = float_rows(origins, dirs)
        dists = np.ascontiguousarray(dists, dtype=np.float64)
        self._split(len(origins), lambda a, b: _occlusions(scene.handle, origins[a:b], dirs[a:b], dists[a:b],
                                                           out[a:b]))
        return out

    def shading_normal(self, obj: np.ndarray, prim: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(n,3) the unit shading normals (triangles.normals1) at triangles `prim (n,)` of objects `obj (n,)`,
        barycentrics `u, v (n,)`."""
        out = np.empty((len(prim), 3))
        _shading_normals(self.triangles, contiguous(obj, np.int64), contiguous(prim, np.int64), *float_rows(u, v), out)
        return out

    def face_normals(self, obj: np.ndarray, prim: np.ndarray) -> np.ndarray:
        """(n,3) the unit geometric normals of triangles `prim (n,)` of objects `obj (n,)`, in world space."""
        out = np.empty((len(prim), 3))
        face_normals(self.triangles, contiguous(obj, np.int64), contiguous(prim, np.int64), out)
        return out

    def corner_points(self, obj: np.ndarray, prim: np.ndarray) -> np.ndarray:
        """(n,3,3) the world corners of triangles `prim (n,)` of objects `obj (n,)`."""
        out = np.empty((len(prim), 3, 3))
        corner_points(self.triangles, contiguous(obj, np.int64), contiguous(prim, np.int64), out)
        return out

    def owners(self, prim: np.ndarray) -> np.ndarray:
        """(n,) the object each of global triangles `prim (n,)` belongs to."""
        return np.searchsorted(self.prim_offset, prim, side="right") - 1

    def offset(self, points: np.ndarray, normals: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """(n,3) offset1 of each row: ray origins off the surface, away from the side `dirs` leave."""
        points, normals, dirs = float_rows(points, normals, dirs)
        out = np.empty_like(points)
        _offsets(points, normals, dirs, self.epsilon, out)
        return out


@kernel("void(f8[:, ::1], i8[:, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, ::1], f8[:, :, ::1], f8[::1])")
def _triangle_tables(vertices, triangles, corner_normals, out_corners, out_face_normal, out_corner_normal, out_area):
    """Per triangle of a mesh: its corners, unit normal by the right-hand
    rule on its winding (0 where it has no area), shading normals at the
    corners (`corner_normals (nt,3,3)`, or none (0,3,3): the face's), and
    area."""
    flat = len(corner_normals) == 0
    for t in range(len(triangles)):
        for c in range(3):
            for axis in range(3):
                out_corners[t, c, axis] = vertices[triangles[t, c], axis]
        e1 = (out_corners[t, 1, 0] - out_corners[t, 0, 0], out_corners[t, 1, 1] - out_corners[t, 0, 1],
              out_corners[t, 1, 2] - out_corners[t, 0, 2])
        e2 = (out_corners[t, 2, 0] - out_corners[t, 0, 0], out_corners[t, 2, 1] - out_corners[t, 0, 1],
              out_corners[t, 2, 2] - out_corners[t, 0, 2])
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        double_area = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        divisor = double_area if double_area > 0.0 else 1.0
        out_area[t] = 0.5 * double_area
        for axis in range(3):
            out_face_normal[t, axis] = n[axis] / divisor
            for c in range(3):
                out_corner_normal[t, c, axis] = out_face_normal[t, axis] if flat else corner_normals[t, c, axis]


@kernel("void(f8[:, :, ::1], f8[::1], f8, f8[:, ::1])")
def _min_barycentrics(corners, area, epsilon, out):
    """(N,3) epsilon / altitude onto each corner's opposite edge, where
    altitude = 2 area / edge length; at most 0.3 (tiny triangles)."""
    for t in range(len(corners)):
        for k in range(3):
            a, b = (k + 1) % 3, (k + 2) % 3
            edge = np.sqrt((corners[t, a, 0] - corners[t, b, 0]) ** 2 + (corners[t, a, 1] - corners[t, b, 1]) ** 2
                           + (corners[t, a, 2] - corners[t, b, 2]) ** 2)
            fraction = epsilon * edge / (2.0 * area[t]) if area[t] > 0.0 else np.inf
            out[t, k] = min(fraction, 0.3) if np.isfinite(fraction) else 0.3


def _first_copy(obj: Object) -> Mesh:
    """`obj`'s mesh, or the first of the copies it is made of (scene.Instances)."""
    if obj.copies == 1:
        return obj.mesh
    return obj.instances.mesh.instanced(obj.instances.transforms[:1], with_normals=False)


@inline
def offset1(point, normal, d, epsilon):
    """A ray origin nudged `epsilon` off the surface at `point` along its
    geometric `normal`, to the side direction `d` leaves toward (the front
    where d is tangent), so the new ray cannot hit the surface again:
    p + epsilon sign(n.d) n."""
    return sum1(1.0, point, -epsilon if dot1(normal, d) < 0.0 else epsilon, normal)


@named_kernel("void", HIT_TYPES, GEOMETRY_TYPES, CAST_TYPES)
def _cast(scene, origins, dirs, dists, members, triangles, epsilon, out_t, out_obj, out_prim, out_u, out_v,
          out_points):
    """Closest hits of rays `origins, dirs (k,3)` in Embree scene `scene`,
    within `dists (k,)` (empty: unbounded): geomID indexes `members`
    (object indices), primID the triangles of the object's copy (global:
    plus the object's first and the copy times its copy size; see
    tracing/triangles.py), the point is surface_point1; a miss has t = inf,
    MISS and the ray's origin. A mirrored copy's triangles run the other
    way round than the mesh Embree holds (Mesh.instanced): its barycentrics
    (u, v) of corners 1 and 2 are (u, 1 - u - v) of the copy's."""
    prim_offset, copy_size, copy_offset, mirrored = triangles[4], triangles[6], triangles[7], triangles[11]
    floats, words, address = ray_record()
    bounded = len(dists) > 0
    for i in range(len(origins)):
        far = dists[i] if bounded else np.inf
        geom, prim, copy, t, u, v = intersect1(scene, floats, words, address, row(origins, i), row(dirs, i), far)
        if geom < 0:
            out_t[i], out_obj[i], out_prim[i], out_u[i], out_v[i] = np.inf, MISS, MISS, u, v
            set_row(out_points, i, row(origins, i))
            continue
        obj = members[geom]
        face = prim + prim_offset[obj] + copy * copy_size[obj]
        if mirrored[copy_offset[obj] + copy]:
            v = 1.0 - u - v
        out_t[i], out_obj[i], out_prim[i], out_u[i], out_v[i] = t, obj, face, u, v
        set_row(out_points, i, surface_point1(triangles, obj, face, u, v, epsilon))


@kernel("void(u8, f8[:, ::1], f8[:, ::1], f8[::1], b1[::1])")
def _occlusions(scene, origins, dirs, dists, out):
    """out (k,): whether anything in Embree scene `scene` lies within
    `dists (k,)` along each ray; in packets of eight, which take half the
    time of single rays on 1920x1080's shadow rays (benchmarks/passes.py)."""
    floats, words, valid, address, valid_address = packet_record()
    n = len(origins)
    for start in range(0, n, PACKET):
        count = min(PACKET, n - start)
        for k in range(count):
            set_packet_ray(floats, words, valid, k, row(origins, start + k), row(dirs, start + k), dists[start + k])
        occluded8(scene, floats, valid, address, valid_address, count)
        for k in range(count):
            out[start + k] = packet_blocked(floats, k)


@kernel(f"void(i8[::1], i8[::1], f8[:, ::1], i8[::1], i8[::1], b1[::1], i8[::1], {TRIANGLES_TYPE}, b1[::1])")
def _contradicting(obj, prim, dirs, medium, outer, closed, body, triangles, out):
    """out (n,): the hit is on a closed mesh, from the side the ray's
    media rule out: toward its front (entering) while inside it, or from
    behind while outside."""
    for i in range(len(obj)):
        if obj[i] == MISS or not closed[obj[i]]:
            out[i] = False
        else:
            toward = dot1(row(dirs, i), face_normal1(triangles, obj[i], prim[i])) < 0.0
            out[i] = toward == (inside1(medium[i], obj[i], body) | inside1(outer[i], obj[i], body))


@kernel(f"void({TRIANGLES_TYPE}, i8[::1], i8[::1], f8[::1], f8[::1], f8[:, ::1])")
def _shading_normals(triangles, obj, prim, u, v, out):
    for i in range(len(prim)):
        set_row(out, i, normals1(triangles, obj[i], prim[i], u[i], v[i])[1])


@kernel("void(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8, f8[:, ::1])")
def _offsets(points, normals, dirs, epsilon, out):
    for i in range(len(points)):
        set_row(out, i, offset1(row(points, i), row(normals, i), row(dirs, i), epsilon))
