"""A rough glass beside a smooth one: in beam mode the lamp sends photons
toward the rough ball and beams toward the smooth one, where before all of
its light went as photons; the caustics under each ball against a reference.

    .venv/bin/python benchmarks/rough_beside_smooth.py

The scene is two glass balls of radius 0.5 m, 3 m apart and 1 m over a white
floor, the smooth one (IOR 1.5) and the rough one (Roughness 0.2), under a
point lamp 4 m up (tests/engine/test_rough.py's `two_balls`). The
references are the engine's own, converged: the smooth ball alone in beam
mode at REFERENCE_RAYS lamp rays, exact to well under 0.1% here, and both
balls as photons (the adaptive estimate, k = 256) at as many. Measured, for
beam mode as it ships and as it was (every caster's light as photons, the
adaptive estimate), at each count of lamp rays: the relative L2 error of the
floor's irradiance within 0.7 m of each ball's axis (a polar grid of
SAMPLES points), and the render's time (the fastest of REPEATS).
"""

from __future__ import annotations

import math
import sys
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "engine"))

from benchmarks import record  # noqa: E402
from caustic_addon import RenderSettings, render  # noqa: E402
from caustic_addon.passes import beam  # noqa: E402
from test_rough import two_balls  # noqa: E402

APART = 1.5
REFERENCE_RAYS = 2_000_000
LAMP_RAYS = [40_000, 160_000]
SAMPLES = 200
REPEATS = 2


def disc_points(x: float) -> np.ndarray:
    """(SAMPLES^2, 2) floor points within 0.7 m of (x, 0): a polar midpoint
    grid, equal in area."""
    r = 0.7 * np.sqrt((np.arange(SAMPLES) + 0.5) / SAMPLES)
    phi = 2.0 * math.pi * (np.arange(SAMPLES) + 0.5) / SAMPLES
    rr, pp = (g.ravel() for g in np.meshgrid(r, phi))
    return np.stack([x + rr * np.cos(pp), rr * np.sin(pp)], axis=1)


@contextmanager
def all_photons():
    """Beam mode as it was: a lamp that lights a rough caster sends all its
    light as photons."""
    original = beam.photon_lamps

    def whole(lights, smooth, rough):
        both = original(lights, smooth, rough)
        return both[0] + both[1], []

    beam.photon_lamps = whole
    try:
        yield
    finally:
        beam.photon_lamps = original


def under(result, points: np.ndarray) -> np.ndarray:
    return result.maps["Floor"].irradiance_at(points)[:, 0]


def relative_l2(values: np.ndarray, reference: np.ndarray) -> float:
    return float(np.linalg.norm(values - reference) / np.linalg.norm(reference))


def main() -> None:
    smooth_at, rough_at = disc_points(-APART), disc_points(APART)
    render(two_balls(APART), RenderSettings(lamp_rays=2000, spp=1))
    smooth_reference = under(render(two_balls(APART, rough=False),
                                     RenderSettings(lamp_rays=REFERENCE_RAYS, spp=1)), smooth_at)
    rough_reference = under(render(two_balls(APART), RenderSettings(lamp_rays=REFERENCE_RAYS, spp=1,
                                                                    density="adaptive", k_nearest=256)), rough_at)
    runs = []
    for way, context in (("beams toward the smooth ball", nullcontext), ("all photons (before)", all_photons)):
        for rays in LAMP_RAYS:
            the_settings = RenderSettings(lamp_rays=rays, spp=1)
            with context():
                result = render(two_balls(APART), the_settings)
                seconds = record.fastest(REPEATS, lambda: render(two_balls(APART), the_settings))
            runs.append({"way": way, "lamp_rays": rays, "seconds": seconds,
                         "smooth_relative_l2": relative_l2(under(result, smooth_at), smooth_reference),
                         "rough_relative_l2": relative_l2(under(result, rough_at), rough_reference)})
            print(runs[-1], flush=True)
    record.write("rough_beside_smooth", {"reference_lamp_rays": REFERENCE_RAYS, "runs": runs})


if __name__ == "__main__":
    main()
