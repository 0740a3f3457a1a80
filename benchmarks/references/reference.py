"""Exact float64 reference: the irradiance a glass ball lens throws onto a plane.

Scene, rotationally symmetric about the z axis: an isotropic point lamp of
radiant intensity I (W/sr) at (0, 0, lamp_z); a solid, non-absorbing sphere
of radius R and relative index n centred at (0, 0, centre_z), entirely above
the diffuse plane z = 0 and entirely below the lamp.

Caustic irradiance is the light that reaches the plane after at least one
specular event at the sphere. Light is traced in one meridional half-plane,
coordinates (x, z) relative to the sphere's centre. The cone of directions
from the lamp tangent to the sphere is cut into `rays` strata of equal width
in the angle of incidence at the sphere (dense where the landing point moves
fast, near grazing incidence). Each stratum carries the flux I times the
solid angle of its annulus of directions and is traced as a ray tube: its
two edge rays are followed through every interface event, where the exact
unpolarised Fresnel reflectance splits them into a reflected and a
refracted branch. A branch that leaves the sphere never meets it again (the
sphere is convex), so it goes straight to the plane or up; the branch that
stays inside is followed for up to `max_events` events in all. A tube's
flux in a branch is the stratum's flux times the mean Fresnel weight of its
edge rays, spread uniformly between their signed landing points x and folded
onto r = |x|; annulus j then gets E_j = flux_j / (pi (r_{j+1}^2 - r_j^2)).

The tube is the stratum's landing map linearised, so the binned flux
converges at second order in 1/rays, except in the few tubes that straddle a
fold of the map (a caustic); `self_error` measures it by doubling `rays`.
For the benchmark scene (R = 1, n = 1.5, centre_z = 1.5, lamp_z = 6, 200
annuli over the shadow disc) DEFAULT_RAYS gives a relative L2 self-error
near 1e-8 and under 1e-5 in every annulus, in well under a second. Rays are
traced CHUNK tubes at a time, the loop running over interface events.

The direct irradiance is averaged over each annulus exactly: the lit part
of the annulus subtends a known solid angle at the lamp.

The reference shares no code with caustic_addon on purpose: it is what the
renderer is checked against.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

DEFAULT_RAYS = 1 << 16
CHUNK = 1 << 14
MAX_EVENTS = 64
MIN_WEIGHT = 1e-12


@dataclass(frozen=True)
class FluxBudget:
    """Where the flux the lamp sends into the sphere's tangent cone ends up (W).

    `horizon` is the flux of tubes with one edge ray descending and one not:
    it lands beyond the descending edge's (far) landing point or never.
    `lost` is flux still inside the sphere when tracing stopped.
    """

    emitted: float
    binned: float
    outside_bins: float
    upward: float
    horizon: float
    lost: float

    @property
    def accounted(self) -> float:
        """Sum of all the places the emitted flux went to."""
        return self.binned + self.outside_bins + self.upward + self.horizon + self.lost


@dataclass(frozen=True)
class BallLensIrradiance:
    """Annulus-averaged irradiance on the plane (W/m^2), one value per annulus of `r_edges (m+1,)`."""

    r_edges: np.ndarray
    caustic: np.ndarray
    direct: np.ndarray
    budget: FluxBudget


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product over the last axis of `a (...,2)` and `b (...,2)` -> (...)."""
    return np.einsum("...i,...i->...", a, b)


def reflect(dirs: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Mirror reflection r = d - 2 (d.n) n of `dirs (...,2)` about unit `normals (...,2)`.

    Source: B. de Greve, "Reflections and Refractions in Ray Tracing" (2006), eq. 10.
    """
    return dirs - 2.0 * dot(dirs, normals)[..., None] * normals


def refract(dirs: np.ndarray, normals: np.ndarray, eta: float) -> np.ndarray:
    """Snell's law in vector form, t = eta d + (eta cos_i - cos_t) n.

    cos_i = -d.n with unit `normals (...,2)` facing the incoming `dirs (...,2)`,
    cos_t = sqrt(1 - eta^2 (1 - cos_i^2)), eta = n_incident / n_transmitted.
    Source: B. de Greve, "Reflections and Refractions in Ray Tracing" (2006), eq. 22.
    Rows past the critical angle are meaningless (cos_t is clamped to 0);
    their Fresnel reflectance is 1, so they carry no flux.
    """
    cos_i = -dot(dirs, normals)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)))
    return eta * dirs + (eta * cos_i - cos_t)[..., None] * normals


def fresnel_unpolarised(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance F = (r_s^2 + r_p^2) / 2 of a dielectric interface.

        r_s = (eta cos_i - cos_t) / (eta cos_i + cos_t)
        r_p = (cos_i - eta cos_t) / (cos_i + eta cos_t)

    with eta = n_incident / n_transmitted, cos_i >= 0 and cos_t from Snell's
    law; F = 1 under total internal reflection and at grazing incidence
    (where eta = 1 gives 0/0). Source: E. Hecht, Optics (4th ed.), sec. 4.6,
    the Fresnel equations for r_perp and r_par divided by n_t.
    """
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    with np.errstate(invalid="ignore"):
        r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
        r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (r_s * r_s + r_p * r_p))


def ball_lens_focal_length(R: float, n: float) -> tuple[float, float]:
    """Effective focal length f = n R / (2 (n - 1)), measured from the centre, and BFD = f - R.

    Source: Edmund Optics, "Understanding Ball Lenses" (EFL = n D / (4 (n - 1)),
    BFL = EFL - D / 2 for diameter D = 2 R); both principal planes of a ball
    lens pass through its centre.
    """
    f = n * R / (2.0 * (n - 1.0))
    return f, f - R


def single_surface_image_distance(s: float, n1: float, n2: float, radius: float) -> float:
    """Paraxial image distance s' from n1 / s + n2 / s' = (n2 - n1) / radius.

    Signs: s > 0 for an object before the surface, s' > 0 for an image after
    it, radius > 0 when the centre of curvature lies after the surface.
    Source: E. Hecht, Optics (4th ed.), sec. 5.2.2, refraction at spherical surfaces.
    """
    return n2 / ((n2 - n1) / radius - n1 / s)


def paraxial_image_z(R: float, n: float, centre_z: float, lamp_z: float) -> float:
    """z of the paraxial image of the lamp, refracting at the top surface and then the bottom one."""
    top_z, bottom_z = centre_z + R, centre_z - R
    first_image_z = top_z - single_surface_image_distance(lamp_z - top_z, 1.0, n, R)
    return bottom_z - single_surface_image_distance(first_image_z - bottom_z, n, 1.0, -R)


def tangent_half_angle(R: float, centre_z: float, lamp_z: float) -> float:
    """Half-angle alpha of the cone from the lamp tangent to the sphere: sin alpha = R / (lamp_z - centre_z)."""
    return float(np.arcsin(R / (lamp_z - centre_z)))


def shadow_radius(R: float, centre_z: float, lamp_z: float) -> float:
    """Radius lamp_z tan(alpha) of the disc on the plane that the sphere hides from the lamp."""
    return lamp_z * float(np.tan(tangent_half_angle(R, centre_z, lamp_z)))


def check_scene(R: float, n: float, centre_z: float, lamp_z: float) -> None:
    """Raise ValueError unless the sphere lies between the plane and the lamp."""
    if not (R > 0.0 and n > 0.0 and centre_z >= R and lamp_z > centre_z + R):
        raise ValueError(f"need R > 0, n > 0, R <= centre_z < lamp_z - R; got {R=}, {n=}, {centre_z=}, {lamp_z=}")


def polar_angle(incidence: np.ndarray, R: float, lamp_height: float) -> np.ndarray:
    """Polar angle theta of the lamp ray that meets the sphere at angle of incidence i.

    Its impact parameter is both lamp_height sin(theta) and R sin(i).
    """
    return np.arcsin(R / lamp_height * np.sin(incidence))


def lamp_strata(rays: int, R: float, lamp_height: float, I: float) -> tuple[np.ndarray, np.ndarray]:
    """Edge incidence angles `(rays+1,)` of equal strata of [0, pi/2] and each stratum's flux `(rays,)`.

    The flux of the polar-angle stratum [a, b] is I times its solid angle,
    I 2 pi (cos a - cos b) = I 4 pi sin((a + b) / 2) sin((b - a) / 2).
    """
    incidence = np.linspace(0.0, 0.5 * np.pi, rays + 1)
    theta = polar_angle(incidence, R, lamp_height)
    a, b = theta[:-1], theta[1:]
    return incidence, 4.0 * np.pi * I * np.sin(0.5 * (a + b)) * np.sin(0.5 * (b - a))


def first_hits(incidence: np.ndarray, R: float, lamp_height: float) -> tuple[np.ndarray, np.ndarray]:
    """Points `pos (...,2)` where lamp rays meet the sphere at angles of incidence `(...)`, and their `dirs (...,2)`.

    Frame centred on the sphere, lamp at (0, lamp_height), d = (sin theta, -cos theta).
    The ray-sphere distance t = lamp_height cos(theta) - R cos(i) is the
    distance to the foot of the perpendicular from the centre minus half the chord.
    """
    theta = polar_angle(incidence, R, lamp_height)
    sin, cos = np.sin(theta), np.cos(theta)
    t = lamp_height * cos - R * np.cos(incidence)
    pos = np.stack([t * sin, lamp_height - t * cos], axis=-1)
    return pos, np.stack([sin, -cos], axis=-1)


def chord_end(pos: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Where rays leaving the sphere's surface at `pos (...,2)` inward along `dirs (...,2)` meet it again.

    The chord of a ray p + t d through a sphere centred at the origin has length t = -2 p.d.
    """
    return pos - 2.0 * dot(pos, dirs)[..., None] * dirs


def split(
    pos: np.ndarray, dirs: np.ndarray, eta: float, normal_sign: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reflected and refracted `dirs (...,2)` and Fresnel reflectance `(...)` at sphere points `pos (...,2)`.

    normal_sign is +1 for light arriving from outside and -1 from inside, so
    that the unit normal faces the incoming `dirs (...,2)`. The normal is
    normalised from pos itself: dividing by R instead lets rounding errors
    in |pos| and |dirs| feed each other and grow about sevenfold per event.
    """
    normals = pos / (normal_sign * np.sqrt(dot(pos, pos)))[..., None]
    cos_i = np.maximum(-dot(dirs, normals), 0.0)
    return reflect(dirs, normals), refract(dirs, normals, eta), fresnel_unpolarised(cos_i, eta)


def landing_x(pos: np.ndarray, dirs: np.ndarray, plane_z: float) -> np.ndarray:
    """Signed x `(...)` where rays from `pos (...,2)` along `dirs (...,2)` cross z = plane_z.

    NaN for rays that never descend.
    """
    down = dirs[..., 1] < 0.0
    step = (plane_z - pos[..., 1]) / np.where(down, dirs[..., 1], -1.0)
    return np.where(down, pos[..., 0] + step * dirs[..., 0], np.nan)


def annulus_areas(r_edges: np.ndarray) -> np.ndarray:
    """Areas pi (r_out^2 - r_in^2) `(m,)` of the annuli between `r_edges (m+1,)`."""
    return np.pi * (r_edges[1:] ** 2 - r_edges[:-1] ** 2)


def fold_segments(x_lo: np.ndarray, x_hi: np.ndarray, flux: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fold flux spread uniformly over signed [x_lo, x_hi] `(k,)` onto r = |x|.

    Returns the r-segments [a, b] `(2k,)` of the positive then the negative
    part of each x-segment and the flux on each.
    """
    length = x_hi - x_lo
    positive = np.maximum(x_hi, 0.0) - np.maximum(x_lo, 0.0)
    positive_share = np.where(length > 0.0, positive / np.where(length > 0.0, length, 1.0), x_lo >= 0.0)
    a = np.concatenate([np.maximum(x_lo, 0.0), np.maximum(-x_hi, 0.0)])
    b = np.concatenate([np.maximum(x_hi, 0.0), np.maximum(-x_lo, 0.0)])
    return a, b, np.concatenate([flux * positive_share, flux * (1.0 - positive_share)])


def bin_segments(a: np.ndarray, b: np.ndarray, flux: np.ndarray, r_edges: np.ndarray) -> np.ndarray:
    """Flux `(k,)` spread uniformly over [a, b] `(k,)`, summed per annulus [r_edges[j], r_edges[j+1]) -> (m,).

    A segment inside one annulus is a point; a longer one adds its density
    times the overlap to its first and last annulus, and to the annuli it
    covers whole through a running sum of densities.
    """
    m = r_edges.size - 1
    first = np.searchsorted(r_edges, a, side="right") - 1
    last = np.searchsorted(r_edges, b, side="right") - 1
    point = (first == last) & (first >= 0) & (first < m)
    binned = np.bincount(first[point], flux[point], minlength=m)

    span = first != last
    a, b, first, last = a[span], b[span], first[span], last[span]
    density = flux[span] / (b - a)
    head, tail = first >= 0, last < m
    binned += np.bincount(first[head], density[head] * (r_edges[first[head] + 1] - a[head]), minlength=m)
    binned += np.bincount(last[tail], density[tail] * (b[tail] - r_edges[last[tail]]), minlength=m)
    lo, hi = np.maximum(first + 1, 0), np.minimum(last, m)
    whole = hi > lo
    starts = np.bincount(lo[whole], density[whole], minlength=m + 1)
    stops = np.bincount(hi[whole], density[whole], minlength=m + 1)
    return binned + np.cumsum(starts - stops)[:m] * np.diff(r_edges)


def tally_branch(
    x: np.ndarray, weight: np.ndarray, stratum_flux: np.ndarray, r_edges: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bin one branch of the tubes: edge landing points `x (k,2)`, edge Fresnel weights `(k,2)`, stratum flux `(k,)`.

    Returns the flux per annulus `(m,)` and the flux that landed, went up and
    straddled the horizon `(3,)`.
    """
    flux = stratum_flux * weight.mean(axis=1)
    down = ~np.isnan(x)
    landed, upward = down.all(axis=1), ~down.any(axis=1)
    a, b, segment_flux = fold_segments(x[landed].min(axis=1), x[landed].max(axis=1), flux[landed])
    sums = np.array([flux[landed].sum(), flux[upward].sum(), flux[~landed & ~upward].sum()])
    return bin_segments(a, b, segment_flux, r_edges), sums


def trace_tubes(
    R: float,
    n: float,
    centre_z: float,
    lamp_z: float,
    incidence: np.ndarray,
    stratum_flux: np.ndarray,
    r_edges: np.ndarray,
    max_events: int,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Trace every Fresnel branch of the tubes with edge incidence angles `(k,2)` and flux `(k,)`.

    Returns the flux per annulus `(m,)`, the flux that landed, went up and
    straddled the horizon `(3,)`, and the flux left inside the sphere: after
    `max_events` interface events, or in tubes whose edge weights both
    dropped below MIN_WEIGHT.
    """
    plane_z = -centre_z
    pos, dirs = first_hits(incidence, R, lamp_z - centre_z)
    reflected, dirs, fresnel = split(pos, dirs, 1.0 / n, 1.0)
    binned, sums = tally_branch(landing_x(pos, reflected, plane_z), fresnel, stratum_flux, r_edges)
    weight, lost = 1.0 - fresnel, 0.0
    for _ in range(max_events - 1):
        followed = weight.max(axis=1) >= MIN_WEIGHT
        lost += float(stratum_flux[~followed] @ weight[~followed].mean(axis=1))
        pos, dirs, weight, stratum_flux = pos[followed], dirs[followed], weight[followed], stratum_flux[followed]
        pos = chord_end(pos, dirs)
        dirs, refracted, fresnel = split(pos, dirs, n, -1.0)
        x = landing_x(pos, refracted, plane_z)
        branch_binned, branch_sums = tally_branch(x, weight * (1.0 - fresnel), stratum_flux, r_edges)
        binned, sums = binned + branch_binned, sums + branch_sums
        weight = weight * fresnel
    return binned, sums, lost + float(stratum_flux @ weight.mean(axis=1))


def unobstructed_irradiance(r: np.ndarray, lamp_z: float, I: float) -> np.ndarray:
    """Inverse-square law E = I cos(theta) / d^2 = I h / (h^2 + r^2)^(3/2) at radius r, lamp at height h."""
    return I * lamp_z / (lamp_z * lamp_z + r * r) ** 1.5


def unobstructed_annulus_irradiance(r_edges: np.ndarray, lamp_z: float, I: float) -> np.ndarray:
    """Exact average of I h / (h^2 + r^2)^(3/2) over each annulus of `r_edges (m+1,)`.

    The annulus [a, b] subtends 2 pi (h / sqrt(A) - h / sqrt(B)) sr with
    A = h^2 + a^2, B = h^2 + b^2; divided by its area pi (b^2 - a^2) that is
    2 I h / (sqrt(A) sqrt(B) (sqrt(A) + sqrt(B))), free of cancellation.
    """
    root_a = np.sqrt(lamp_z * lamp_z + r_edges[:-1] ** 2)
    root_b = np.sqrt(lamp_z * lamp_z + r_edges[1:] ** 2)
    return 2.0 * I * lamp_z / (root_a * root_b * (root_a + root_b))


def direct_irradiance(r: np.ndarray, R: float, centre_z: float, lamp_z: float, I: float) -> np.ndarray:
    """Lamp irradiance at radius r that missed the sphere: I cos(theta) / d^2 outside the shadow disc, 0 inside."""
    return np.where(r >= shadow_radius(R, centre_z, lamp_z), unobstructed_irradiance(r, lamp_z, I), 0.0)


def direct_annulus_irradiance(r_edges: np.ndarray, R: float, centre_z: float, lamp_z: float, I: float) -> np.ndarray:
    """Exact average of `direct_irradiance` over each annulus of `r_edges (m+1,)`.

    The lit part of an annulus is [max(a, r_shadow), max(b, r_shadow)]; its
    flux is the unobstructed average over that part times its area.
    """
    lit = np.maximum(r_edges, shadow_radius(R, centre_z, lamp_z))
    lit_flux = unobstructed_annulus_irradiance(lit, lamp_z, I) * annulus_areas(lit)
    return lit_flux / annulus_areas(r_edges)


def ball_lens_irradiance(
    R: float,
    n: float,
    centre_z: float,
    lamp_z: float,
    I: float,
    r_edges: np.ndarray,
    rays: int = DEFAULT_RAYS,
    max_events: int = MAX_EVENTS,
) -> BallLensIrradiance:
    """Caustic and direct irradiance averaged over each annulus of `r_edges (m+1,)`, with the flux budget.

    `rays` is the number of ray tubes, traced CHUNK at a time so that the
    work arrays stay in cache; `max_events` counts interface events per path.
    """
    check_scene(R, n, centre_z, lamp_z)
    r_edges = np.asarray(r_edges, dtype=np.float64)
    incidence, stratum_flux = lamp_strata(rays, R, lamp_z - centre_z, I)
    binned, sums, lost = np.zeros(r_edges.size - 1), np.zeros(3), 0.0
    for start in range(0, rays, CHUNK):
        stop = min(start + CHUNK, rays)
        tubes = np.stack([incidence[start:stop], incidence[start + 1 : stop + 1]], axis=1)
        chunk = trace_tubes(R, n, centre_z, lamp_z, tubes, stratum_flux[start:stop], r_edges, max_events)
        binned, sums, lost = binned + chunk[0], sums + chunk[1], lost + chunk[2]
    alpha = tangent_half_angle(R, centre_z, lamp_z)
    budget = FluxBudget(
        emitted=4.0 * np.pi * I * float(np.sin(0.5 * alpha)) ** 2,
        binned=float(binned.sum()),
        outside_bins=float(sums[0] - binned.sum()),
        upward=float(sums[1]),
        horizon=float(sums[2]),
        lost=lost,
    )
    direct = direct_annulus_irradiance(r_edges, R, centre_z, lamp_z, I)
    return BallLensIrradiance(r_edges, binned / annulus_areas(r_edges), direct, budget)


def self_error(
    R: float, n: float, centre_z: float, lamp_z: float, r_edges: np.ndarray, rays: int = DEFAULT_RAYS
) -> float:
    """Relative L2 difference ||E_rays - E_2rays|| / ||E_2rays|| of the caustic irradiance per annulus."""
    coarse = ball_lens_irradiance(R, n, centre_z, lamp_z, 1.0, r_edges, rays).caustic
    fine = ball_lens_irradiance(R, n, centre_z, lamp_z, 1.0, r_edges, 2 * rays).caustic
    return float(np.linalg.norm(coarse - fine) / np.linalg.norm(fine))


def traced_axis_crossing_z(R: float, n: float, centre_z: float, lamp_z: float, theta: np.ndarray) -> np.ndarray:
    """z where lamp rays at polar angles `theta (k,)`, refracted into and out of the sphere, cross the axis."""
    check_scene(R, n, centre_z, lamp_z)
    incidence = np.arcsin((lamp_z - centre_z) / R * np.sin(np.asarray(theta, dtype=np.float64)))
    pos, dirs = first_hits(incidence, R, lamp_z - centre_z)
    _, dirs, _ = split(pos, dirs, 1.0 / n, 1.0)
    pos = chord_end(pos, dirs)
    _, dirs, _ = split(pos, dirs, n, -1.0)
    return centre_z + pos[:, 1] - pos[:, 0] * dirs[:, 1] / dirs[:, 0]


def main() -> None:
    """Print the reference for the benchmark ball lens, its convergence and its paraxial check."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--R", type=float, default=1.0)
    parser.add_argument("--n", type=float, default=1.5)
    parser.add_argument("--centre-z", type=float, default=1.5)
    parser.add_argument("--lamp-z", type=float, default=6.0)
    parser.add_argument("--annuli", type=int, default=200)
    parser.add_argument("--rays", type=int, default=DEFAULT_RAYS)
    args = parser.parse_args()
    scene = (args.R, args.n, args.centre_z, args.lamp_z)
    r_edges = np.linspace(0.0, shadow_radius(args.R, args.centre_z, args.lamp_z), args.annuli + 1)

    start = time.perf_counter()
    result = ball_lens_irradiance(*scene, 1.0, r_edges, args.rays)
    seconds = time.perf_counter() - start
    paraxial = traced_axis_crossing_z(*scene, np.array([1e-6]))[0]
    expected = paraxial_image_z(*scene)
    ratio = result.caustic / unobstructed_annulus_irradiance(r_edges, args.lamp_z, 1.0)

    print(f"scene R={args.R} n={args.n} centre_z={args.centre_z} lamp_z={args.lamp_z}, I = 1 W/sr")
    print(f"{args.rays} ray tubes, {args.annuli} annuli over the shadow disc: {seconds:.2f} s")
    print(f"self-error (rays vs 2 x rays): {self_error(*scene, r_edges, args.rays):.2e}")
    print(f"paraxial image z: traced {paraxial:.12f}, two-surface formula {expected:.12f}")
    print(f"peak caustic / unobstructed irradiance: {ratio.max():.2f} at r = {r_edges[ratio.argmax()]:.4f}")
    print(f"flux budget (W): {result.budget}")


if __name__ == "__main__":
    main()
