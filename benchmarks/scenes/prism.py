"""A dispersive glass prism in a sun, its spectrum on a floor, and the closed
form of where each colour lands: shared by tests/engine/test_dispersion.py
and benchmarks/cycles_dispersion.py.

The prism runs along y; its cross-section in the x-z plane is an isosceles
triangle of apex angle APEX and base 2 HALF_BASE. The sun meets the entry
face at INCIDENCE; light refracts in, crosses the glass and refracts out of
the exit face. The whole is turned so that light of the d line (587.6 nm,
where the IOR is given) leaves straight down, towards a floor 2 m below the
prism's lowest point. The sun lights only the entry face, so every path
that reaches the floor in two specular events is entry face, exit face;
light that meets the base inside is turned back (total internal
reflection) and has had two events by then, so with max_depth 2 it is lost,
as the sun's reflection off the entry face goes up, never to the floor.

The closed form traces the cross-section in 2D with Snell's law and Fresnel's
equations at both faces, n(lambda) by Cauchy through IOR at the d line with
the Abbe number (optics/dispersion.py), over a fine midpoint grid of entry
points (the sun's light is uniform along the entry face). A colour channel's
centroid on the floor is its band weights times each band's landed light
and mean landing x."""

from __future__ import annotations

import math

import numpy as np

from caustic_addon import Camera, Dielectric, Diffuse, Mesh, Object, Scene, SunLight, shapes
from caustic_addon.optics.dispersion import cauchy_ior

APEX, INCIDENCE, IOR = math.radians(45.0), math.radians(20.0), 1.5
HALF_BASE, LENGTH, DROP = 0.5, 4.0, 2.0
SUN = 1000.0


def _rotate(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], axis=-1)


def _refract(d: np.ndarray, normal: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(direction, transmittance) of rays `d (m,2)` refracted at a face of
    unit `normal (2,)` facing them, `eta` = n_from / n_to; transmittance 0
    where light is totally reflected (Fresnel, unpolarised)."""
    cos_i = -(d @ normal)
    sin_t2 = eta ** 2 * (1.0 - cos_i ** 2)
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    transmit = np.where(sin_t2 < 1.0, 1.0 - 0.5 * (rs ** 2 + rp ** 2), 0.0)
    out = eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * normal
    return out / np.linalg.norm(out, axis=1)[:, None], transmit


def _cross_section() -> tuple[np.ndarray, float]:
    """((3,2) corners in the prism's own x-z frame: base left, base right,
    apex; the angle that turns that frame so the d line leaves straight
    down)."""
    corners = np.array([[-HALF_BASE, 0.0], [HALF_BASE, 0.0], [0.0, HALF_BASE / math.tan(APEX / 2)]])
    inside = -APEX / 2 + math.asin(math.sin(INCIDENCE) / IOR)  # the d line inside, from the entry face
    leaving = math.asin(IOR * math.sin(APEX / 2 - inside))  # from the exit face's normal, below it
    return corners, -math.pi / 2 - (APEX / 2 - leaving)


def outline() -> np.ndarray:
    """(3,2) x, z of the corners in the scene: base left, base right, apex
    (entry face base left to apex, exit face apex to base right)."""
    corners, turn = _cross_section()
    turned = _rotate(corners, turn)
    return turned + np.array([0.0, DROP - turned[:, 1].min()])


def sun_direction() -> np.ndarray:
    """(2,) x, z the sun's light travels along."""
    _, turn = _cross_section()
    entry_inward = np.array([math.cos(-APEX / 2), math.sin(-APEX / 2)])  # in the prism's frame
    return _rotate(_rotate(entry_inward, INCIDENCE), turn)


def prism_mesh() -> Mesh:
    """The prism, LENGTH along y, centred on y = 0, its faces outward."""
    xz = outline()
    vertices = np.concatenate([np.c_[xz[:, 0], np.full(3, y), xz[:, 1]] for y in (-LENGTH / 2, LENGTH / 2)])
    # corners 0-2 at -y, 3-5 at +y
    faces = np.array([(0, 1, 2), (3, 4, 5), (0, 3, 4), (0, 4, 1), (1, 4, 5), (1, 5, 2), (2, 5, 3), (2, 3, 0)])
    corners = vertices[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    inward = np.einsum("ij,ij->i", normals, vertices.mean(axis=0) - corners[:, 0]) > 0
    faces[inward] = faces[inward][:, ::-1]
    return Mesh(vertices, faces)


def scene(abbe: float) -> Scene:
    """The prism (IOR, `abbe`) over a white floor at z = 0, in a sun of SUN
    W/m^2."""
    d = sun_direction()
    camera = np.eye(4)
    camera[2, 3] = 20.0
    return Scene(objects=[Object("Floor", shapes.plane(4.5), Diffuse(albedo=1.0)),
                          Object("Prism", prism_mesh(), Dielectric(IOR, abbe=abbe))],
                 lights=[SunLight((d[0], 0.0, d[1]), SUN)],
                 camera=Camera(camera, pixx=8, pixy=8, kind="ORTHO", ortho_scale=2.0))


def _outward(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Unit normal of the outline's edge p - q, away from the prism."""
    edge = (q - p) / np.linalg.norm(q - p)
    normal = np.array([-edge[1], edge[0]])
    return normal if normal @ (p - outline().mean(axis=0)) > 0 else -normal


def landings(ior: float, entries: int = 200_000) -> tuple[np.ndarray, np.ndarray]:
    """((m,) x where light of index `ior` lands on the floor, (m,) its share
    of the light on the entry face that lands there) for `entries` points
    evenly along the entry face."""
    left, right, apex = outline()
    entry_normal, exit_normal = _outward(left, apex), _outward(apex, right)
    t = (np.arange(entries) + 0.5) / entries
    points = left + t[:, None] * (apex - left)
    sun = np.broadcast_to(sun_direction(), (entries, 2))
    inside, t_in = _refract(sun, entry_normal, np.full(entries, 1.0 / ior))
    # where the ray inside meets the exit face's line, and whether it is on the face
    edge = right - apex
    det = inside[:, 0] * (-edge[1]) - inside[:, 1] * (-edge[0])
    rel = apex - points
    dist = (rel[:, 0] * (-edge[1]) - rel[:, 1] * (-edge[0])) / det
    along = (inside[:, 0] * rel[:, 1] - inside[:, 1] * rel[:, 0]) / det
    reaches = (dist > 0) & (along >= 0) & (along <= 1)
    out, t_out = _refract(inside[reaches], -exit_normal, np.full(reaches.sum(), ior))
    at = points[reaches] + dist[reaches, None] * inside[reaches]
    x = at[:, 0] - at[:, 1] * out[:, 0] / out[:, 1]
    return x, (t_in[reaches] * t_out) / entries


def centroids(abbe: float, wavelengths: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(3,) x of each channel's centroid on the floor, for light of
    `wavelengths (K,)` nm carrying `weights (K,3)` of each channel."""
    moments = np.zeros((len(wavelengths), 2))
    for k, ior in enumerate(cauchy_ior(IOR, abbe, wavelengths)):
        x, share = landings(float(ior))
        moments[k] = share.sum(), (share * x).sum()
    return (weights * moments[:, 1:2]).sum(axis=0) / (weights * moments[:, 0:1]).sum(axis=0)


def landed_power(abbe: float, wavelengths: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(3,) W of each channel that lands on the floor per metre of the
    prism's length, for light of `wavelengths (K,)` nm carrying `weights
    (K,3)`: the sun's power on a metre of the entry face times each band's
    landed share."""
    left, _, apex = outline()
    on_face = SUN * float(np.linalg.norm(apex - left)) * math.cos(INCIDENCE)
    shares = np.array([landings(float(ior))[1].sum() for ior in cauchy_ior(IOR, abbe, wavelengths)])
    return on_face * shares @ weights


def exit_angle(ior: float) -> float:
    """Radians from straight down (positive towards +x) at which the sun's
    light of index `ior` leaves the exit face (0 for IOR)."""
    left, right, apex = outline()
    inside, _ = _refract(sun_direction()[None], _outward(left, apex), np.array([1.0 / ior]))
    out, _ = _refract(inside, -_outward(apex, right), np.array([ior]))
    return math.atan2(float(out[0, 0]), -float(out[0, 1]))
