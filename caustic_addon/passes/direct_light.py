"""Direct light at opaque surface points, with shadow rays: from each lamp
(emission/lamp_samples.py) and from the world.

Radiance leaving a point toward the eye v, per sample of a lamp bringing
irradiance E at normal incidence along the unit vector l:

    L = E cos(theta_l) diffuse / pi + E f_s(v, l) cos(theta_l)

the Lambert term of the diffuse base (what a Cycles Diffuse BSDF returns;
under a Principled BSDF's specular layer, its base colour times the share
the layer leaves it) plus the layer's GGX lobe (optics/principled.py). A
lamp of size 0 takes one sample; a lamp with a size takes `samples`,
stratified over a pixel: eye sample s of a pixel uses points s K .. s K +
K - 1 of the R2 sequence, rotated by a hash of the pixel. A sample behind
the surface gets no shadow ray. Dielectrics and reflectors block shadow
rays: the light they redirect arrives through the illumination maps.

The world lights a surface with E = int L(w) V(w) cos(theta) dw over the
hemisphere, and its lobe with int L(w) V(w) f_s(v, w) cos(theta) dw, what
Cycles computes with bounces at 0. Both are estimated from the same
directions, drawn by cos(theta) / pi (Malley), for an image by the world's
radiance (environment.py), and where there is a lobe by its visible normals
(Heitz 2018), weighted by the balance heuristic (Veach 1997)."""

from __future__ import annotations

import math

import numpy as np

from ..emission import radiometry
from ..emission.environment import Environment
from ..emission.lamp_samples import sample_lamp
from ..optics.principled import Lobe
from ..sampling.hash import hash_uniform
from ..sampling.sequences import r2_sequence
from ..sampling.warps import cosine_hemisphere, frames
from ..scene import Light
from ..tracing.accelerator import Accelerator
from ..util.vectors import dot, max_channel

# Hash streams of the strata's rotations: two per lamp, two for each of the world's strategies.
_WORLD_STREAM = 1 << 16


def strata(ids: np.ndarray, index: np.ndarray, stream: int, seed: int) -> np.ndarray:
    """(n,2) points of the R2 sequence at `index (n,)`, rotated by a hash of
    `ids (n,)`: a pixel's samples spread evenly over the unit square."""
    return r2_sequence(index, np.stack([hash_uniform(ids, stream, seed), hash_uniform(ids, stream + 1, seed)], axis=1))


def direct_radiance(accel: Accelerator, lights: list[Light], energy: float, points: np.ndarray,
                    shading: np.ndarray, facing: np.ndarray, view: np.ndarray, diffuse: np.ndarray,
                    lobe: Lobe | None, far: float, pixel: np.ndarray, first_stratum: np.ndarray, samples: int,
                    seed: int) -> np.ndarray:
    """Radiance (n,3) toward the eye from all lamps' direct light.

    shading, facing   (n,3) shading and geometric normals, both on the eye's side
    view              (n,3) unit vectors from the points toward the eye
    diffuse           (n,3) the diffuse reflectance (under a layer, its share)
    lobe              the points' specular layers, or None
    pixel, first_stratum  (n,) the pixel each point is seen in, and the
                      index of its first stratum there
    """
    out = np.zeros((len(points), 3))
    for number, light in enumerate(lights):
        count = 1 if radiometry.is_delta(light) else samples
        for k in range(count):
            uv = strata(pixel, first_stratum * count + k, 2 * number, seed)
            lamp = sample_lamp(light, energy, points, uv, far)
            cos = dot(shading, lamp.dirs)
            lit = (cos > 0.0) & (dot(facing, lamp.dirs) > 0.0) & (max_channel(lamp.irradiance) > 0.0)
            idx = np.flatnonzero(lit)
            if len(idx) == 0:
                continue
            dirs = np.take(lamp.dirs, idx, axis=0)
            origins = accel.offset(np.take(points, idx, axis=0), np.take(facing, idx, axis=0), dirs)
            blocked = accel.occluded(origins, dirs, np.take(lamp.dist, idx) - 2.0 * accel.epsilon)
            idx, dirs = idx[~blocked], dirs[~blocked]
            if len(idx) == 0:
                continue
            irradiance = np.take(lamp.irradiance, idx, axis=0) / count
            out[idx] += irradiance * (np.take(diffuse, idx, axis=0) * (cos[idx] / math.pi)[:, None])
            if lobe is not None:
                glossy = np.flatnonzero(lobe.lamp_lit[idx])
                at = idx[glossy]
                out[at] += np.take(irradiance, glossy, axis=0) * lobe.take(at).weight(
                    np.take(shading, at, axis=0), np.take(view, at, axis=0), np.take(dirs, glossy, axis=0))
    return out


def world_light(accel: Accelerator, environment: Environment, points: np.ndarray, shading: np.ndarray,
                facing: np.ndarray, view: np.ndarray, lobe: Lobe | None, far: float, pixel: np.ndarray,
                first_stratum: np.ndarray, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(irradiance (n,3) W/m^2, glossy (n,3) W/(m^2 sr)) the world brings
    the points, shadows included, and the radiance their specular layers
    (`lobe`, or None) reflect of it toward `view (n,3)`, from `samples`
    directions of each strategy per point."""
    n = len(points)
    irradiance, glossy = np.zeros((n, 3)), np.zeros((n, 3))
    image = environment.world.environment is not None
    tangent, bitangent = frames(shading) if lobe is not None else (None, None)
    for k in range(samples):
        index = first_stratum * samples + k
        drawn = [(cosine_hemisphere(shading, strata(pixel, index, _WORLD_STREAM, seed)), None)]
        if image:
            drawn.append((environment.sample(strata(pixel, index, _WORLD_STREAM + 2, seed))[0], None))
        if lobe is not None:
            drawn.append((lobe.sample(shading, tangent, bitangent, view, strata(pixel, index, _WORLD_STREAM + 4, seed)),
                          lobe.active))
        for dirs, among in drawn:
            cos = dot(shading, dirs)
            density = np.maximum(cos, 0.0) / math.pi + (environment.density(dirs) if image else 0.0)
            if lobe is not None:
                density = density + lobe.pdf(shading, view, dirs)
            valid = (cos > 0.0) & (dot(facing, dirs) > 0.0) & (density > 0.0)
            idx = np.flatnonzero(valid if among is None else valid & among)
            if len(idx) == 0:
                continue
            toward = np.take(dirs, idx, axis=0)
            seen = ~accel.occluded(accel.offset(np.take(points, idx, axis=0), np.take(facing, idx, axis=0), toward),
                                   toward, np.full(len(idx), far))
            idx, toward = idx[seen], toward[seen]
            radiance = environment.light(toward) / (density[idx] * samples)[:, None]
            irradiance[idx] += radiance * cos[idx][:, None]
            if lobe is not None:
                glossy[idx] += radiance * lobe.take(idx).weight(np.take(shading, idx, axis=0),
                                                                 np.take(view, idx, axis=0), toward)
    return irradiance, glossy
