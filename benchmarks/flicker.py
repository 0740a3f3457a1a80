"""Flicker: how much of a caustic's change from frame to frame the motion
does not explain, against a converged render's change, for beams and for
photon maps.

    .venv/bin/python benchmarks/flicker.py [--frames 8] [--step 0.005]

The ball lens of benchmarks/scenes/ball_lens.py slides along x by `step` metres a
frame (0.3 pixel of the caustic's image at the default). What the motion
explains is the change of a converged render, beams from 4 times the lamp
rays with two levels of refinement: g[t+1] - g[t]. A mode's flicker is
what its own change f[t+1] - f[t] adds to that, against it:

    rms((f[t+1] - f[t]) - (g[t+1] - g[t])) / rms(g[t+1] - g[t])

over the caustic's pixels (those the mean reference lights above 2% of its
peak) and all frame pairs: 0 when the frames change as the motion does; a
noise that reshuffles each frame makes it large however slowly the ball
moves. The temporal noise is the same residual as a share of the mean
caustic. Each mode also renders a static frame twice, the maps traced
again: its frames must be identical. Writes benchmarks/results/flicker.json
and prints its table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from benchmarks.scenes import ball_lens  # noqa: E402
from caustic_addon import Camera, Dielectric, Diffuse, Object, PointLight, RenderSettings, Scene, render, shapes  # noqa: E402

PIXELS = (160, 120)
MODES = {
    "beam, 40,000 lamp rays (the default)": dict(density="beam", lamp_rays=40_000),
    "adaptive photons, 40,000": dict(density="adaptive", lamp_rays=40_000),
    "splat photons, 40,000 (the paper's)": dict(density="splat", lamp_rays=40_000),
    "adaptive photons, 400,000": dict(density="adaptive", lamp_rays=400_000),
}
REFERENCE = dict(density="beam", lamp_rays=160_000, beam_refinement=2)


def frame_scene(x: float) -> Scene:
    """The ball lens with its ball's centre at (x, 0, CENTER_Z)."""
    return Scene(
        objects=[Object("Floor", shapes.plane(8.0), Diffuse(albedo=1.0)),
                 Object("Glass", shapes.uv_sphere(ball_lens.RADIUS, (x, 0, ball_lens.CENTER_Z), 128, 64),
                        Dielectric(ball_lens.IOR))],
        lights=[PointLight((0, 0, ball_lens.LAMP_Z), ball_lens.POWER)],
        camera=Camera.look_at(ball_lens.EYE, ball_lens.TARGET, pixx=PIXELS[0], pixy=PIXELS[1], fov=ball_lens.FOV),
    )


def caustic(x: float, mode: dict) -> np.ndarray:
    """(pixy, pixx) caustic radiance (red channel) with the ball at x."""
    return render(frame_scene(x), RenderSettings(spp=1, **mode)).passes["caustic"][..., 0].astype(np.float64)


def rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values * values)))


def measure(frames: int, step: float) -> list[dict]:
    reference = np.stack([caustic(step * t, REFERENCE) for t in range(frames)])
    mean = reference.mean(axis=0)
    region = mean > 0.02 * mean.max()
    explained = np.diff(reference[:, region], axis=0)
    rows = []
    for name, mode in MODES.items():
        clock = time.perf_counter()
        film = np.stack([caustic(step * t, mode) for t in range(frames)])
        seconds = (time.perf_counter() - clock) / frames
        residual = np.diff(film[:, region], axis=0) - explained
        rows.append(dict(mode=name, flicker=rms(residual) / rms(explained),
                         temporal_noise=rms(residual) / float(mean[region].mean()),
                         static_identical=bool(np.array_equal(caustic(0.0, mode), caustic(0.0, mode))),
                         seconds_per_frame=seconds, pixels=int(region.sum())))
        print(f"{name}: flicker {rows[-1]['flicker']:.3f}, temporal noise {rows[-1]['temporal_noise']:.2%}, "
              f"static frames identical {rows[-1]['static_identical']}", flush=True)
    return rows


def markdown(rows: list[dict]) -> str:
    lines = ["| mode | flicker | temporal noise | static frames identical | s/frame |", "|---|---|---|---|---|"]
    lines += [f"| {r['mode']} | {r['flicker']:.3f} | {r['temporal_noise']:.2%} | "
              f"{'yes' if r['static_identical'] else 'no'} | {r['seconds_per_frame']:.2f} |" for r in rows]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--step", type=float, default=0.005, help="metres the ball moves per frame")
    args = parser.parse_args()
    start = time.perf_counter()
    rows = measure(args.frames, args.step)
    table = markdown(rows)
    record.write("flicker", dict(frames=args.frames, step_m=args.step, pixels=list(PIXELS),
                                 wall_seconds=time.perf_counter() - start, modes=rows, table=table))
    print("\n" + table)


if __name__ == "__main__":
    main()
