"""What both passes do where a ray meets a specular surface, a dielectric or
a reflector: orient the normals, then refract or reflect. Kept in one place
so the photon pass, the beams and the eye pass cannot disagree about the
physics. A reflector is a surface whose Fresnel reflectance is 1: it always
reflects, and its colour (applied by the caller) is its reflectance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..optics.specular import fresnel_dielectric, reflect, refract
from ..scene.material_table import Materials
from ..tracing.accelerator import Accelerator
from ..tracing.hits import Hits
from ..util.vectors import dot, normalize


@dataclass
class Interface:
    """n rays at specular hits, oriented.

    points      (n,3) world hit points
    facing      (n,3) geometric normal on the side the ray comes from
    shading     (n,3) shading normal on that same side
    entering    (n,) bool: the ray goes from outside the object to inside
    eta         (n,) eta_i / eta_t for this crossing
    fresnel     (n,) unpolarised reflectance; 1 under total internal
                reflection and at reflectors
    """

    points: np.ndarray
    facing: np.ndarray
    shading: np.ndarray
    entering: np.ndarray
    eta: np.ndarray
    fresnel: np.ndarray


def orient(accel: Accelerator, hits: Hits, dirs: np.ndarray, points: np.ndarray,
           materials: Materials, medium: np.ndarray, band=None) -> Interface:
    """Orient the hits' normals against `dirs (n,3)` and evaluate Fresnel
    (1 at reflectors, which reflect everything). Dielectrics refract with
    their IOR in wavelength band `band` (an int, or (n,) per ray), or at
    587.6 nm (n_d) when it is None.

    Entering or leaving: for a closed mesh, the ray's own state `medium (n,)`
    (the object it is inside, or MISS) decides, since a hit at an edge or a
    grazing hit can land on a face whose normal says otherwise; for an open
    mesh, the outward geometric normal does (dot(d, n) < 0 means entering).
    The geometric normal is turned against the ray, and the shading normal
    put on its side; where interpolation tips it past the ray
    (dot(d, n_s) >= 0), the geometric normal is used instead.
    """
    face = np.take(accel.face_normal, hits.prim, axis=0)
    toward = dot(dirs, face) < 0.0
    entering = np.where(accel.closed[hits.obj], medium != hits.obj, toward)
    facing = np.where(toward[:, None], face, -face)
    shading = accel.shading_normal(hits.prim, hits.u, hits.v)
    shading = np.where((dot(shading, facing) < 0.0)[:, None], -shading, shading)
    tipped = dot(dirs, shading) >= 0.0
    shading[tipped] = facing[tipped]
    ior = materials.ior[hits.obj] if band is None else materials.ior_bands[hits.obj, band]
    eta = np.where(entering, 1.0 / ior, ior)
    fresnel = np.where(materials.reflector[hits.obj], 1.0, fresnel_dielectric(-dot(dirs, shading), eta))
    return Interface(points, facing, shading, entering, eta, fresnel)


def scatter(surface: Interface, dirs: np.ndarray, reflect_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """New unit directions (n,3) and which of them crossed the surface (n,) bool:
    mirror reflection where `reflect_mask`, Snell refraction elsewhere (total
    internal reflection reflects).

    A shading normal can send a reflected ray into the surface or a refracted
    one back out; those rays are redone about the geometric normal, which
    cannot.
    """
    reflected = reflect(dirs, surface.shading)
    refracted, tir = refract(dirs, surface.shading, surface.eta)
    mirror = reflect_mask | tir
    out = np.where(mirror[:, None], reflected, refracted)
    side = dot(out, surface.facing)
    wrong = np.where(mirror, side <= 0.0, side >= 0.0)
    if wrong.any():
        d, n = dirs[wrong], surface.facing[wrong]
        redo_refract, redo_tir = refract(d, n, surface.eta[wrong])
        mirror[wrong] |= redo_tir
        out[wrong] = np.where(mirror[wrong][:, None], reflect(d, n), redo_refract)
    return normalize(out), ~mirror
