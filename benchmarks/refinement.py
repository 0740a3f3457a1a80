"""Beam refinement against a plain beam grid, on two casters: issue 4's
smooth ball lens (exact pixel reference) and a facetted gem (a 12-sided
diamond cone, IOR 2.41, flat-shaded, whose facet edges split the grid's
triangles between families), against a 1M-path plain beam render.

    .venv/bin/python benchmarks/refinement.py

Writes benchmarks/results/refinement.json and prints, for each caster and
refinement level, paths traced, seconds and relative L2 error.
"""

from __future__ import annotations

import json
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

import ball_lens  # noqa: E402
from caustic_addon import (Camera, Dielectric, Diffuse, Mesh, Object, PointLight, RenderSettings, Scene,  # noqa: E402
                           render, shapes)
from speed import machine  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
GRIDS = (1_000, 3_162, 10_000, 31_622)
LEVELS = (0, 1, 2)


def facetted_gem() -> Scene:
    cone = shapes.cone(0.5, 1.0, (0.0, 0.0, 0.2), segments=12)
    return Scene(objects=[Object("Floor", shapes.plane(4.0), Diffuse(albedo=1.0)),
                          Object("Gem", Mesh(cone.vertices, cone.triangles), Dielectric(2.41))],
                 lights=[PointLight((0.3, 0.2, 3.0), 1000.0)],
                 camera=Camera.look_at((0.0, -3.0, 2.5), (0.0, 0.0, 0.0), pixx=32, pixy=24))


def gem_caustic(photons: int, levels: int):
    """(irradiance (n,) over a 300x300 grid of 1 cm boxes on the floor, result)."""
    ticks = np.linspace(-1.5, 1.5, 300)
    xy = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    result = render(facetted_gem(), RenderSettings(lamp_rays=photons, spp=1, density="beam", map_scale=10.0,
                                                   beam_refinement=levels))
    return result.maps["Floor"].mean_over(xy - 0.005, xy + 0.005)[:, 0], result


def main() -> None:
    truth = ball_lens.pixel_reference(ball_lens.scene())
    gem_reference, _ = gem_caustic(1_000_000, 0)
    rows = []
    for levels in LEVELS:
        for grid in GRIDS:
            start = time.perf_counter()
            lens = render(ball_lens.scene(), RenderSettings(lamp_rays=grid, spp=1, density="beam",
                                                            beam_refinement=levels))
            lens_seconds = time.perf_counter() - start
            start = time.perf_counter()
            gem, gem_result = gem_caustic(grid, levels)
            gem_seconds = time.perf_counter() - start
            row = dict(levels=levels, grid=grid,
                       ball_lens=dict(paths=lens.stats["lamp_rays"], seconds=round(lens_seconds, 3),
                                      error=truth.error(lens.passes["caustic"])),
                       gem=dict(paths=gem_result.stats["lamp_rays"], seconds=round(gem_seconds, 3),
                                error=float(np.linalg.norm(gem - gem_reference) / np.linalg.norm(gem_reference))))
            rows.append(row)
            print(f"refinement {levels}  grid {grid:>6,d}   ball lens {row['ball_lens']['paths']:>7,d} paths "
                  f"{lens_seconds:5.2f} s {100 * row['ball_lens']['error']:6.2f}%   gem {row['gem']['paths']:>7,d} "
                  f"paths {gem_seconds:5.2f} s {100 * row['gem']['error']:6.2f}%", flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "refinement.json").write_text(json.dumps(
        dict(date=date.today().isoformat(), machine=machine(), rows=rows), indent=2) + "\n")


if __name__ == "__main__":
    main()
