"""The paper's experiments (section 4) reproduced on this engine, and each of
its claims measured against physics (benchmarks/PAPER.md has the verdicts).

    .venv/bin/python benchmarks/paper.py [--quick]

Renders every sweep of benchmarks/scenes/paper_scenes.py: index of refraction x
base shape at rest and raised (tables 1-3), lamp ray count (table 4), lamp
energy (table 5), map scale (table 6) and object height (table 7); then
times the engine's stages against the triangle count of the round glass.
Writes benchmarks/results/paper.json (every measured figure),
paper_<table>.png (one gallery per table, sRGB with one fixed exposure per
gallery) and paper_complexity.png (log-log). --quick runs fewer photons,
heights and mesh sizes.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from benchmarks import record  # noqa: E402
from benchmarks.scenes import paper_scenes as ps  # noqa: E402
from caustic_addon import Dielectric, Object, RenderSettings, paper, render, shapes  # noqa: E402
from caustic_addon.emission.aims import Sphere  # noqa: E402

RESULTS = record.RESULTS
# Index 1.5 (glass) and the heights between resting and RAISED are not in the
# paper; they show where its trends turn.
WATER, ZIRCONIA, DIAMOND = paper.INDICES.values()
IORS = (WATER, ps.GLASS_IOR, ZIRCONIA, DIAMOND)
HEIGHTS = (0.0, 0.25, 0.5, paper.RAISED, 2.0)
COMPLEXITY_SIZES = (1_000, 4_000, 16_000, 64_000, 256_000, 1_000_000)
ENERGY = ps.PAPER_DEFAULTS["energy"]
# Linear radiance of the unobstructed floor under the lamp on display.
FLOOR_GREY = 0.18


def srgb(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function of linear values clipped to [0, 1]."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def exposure(scene, energy: float) -> float:
    """Multiplier that shows the floor right under the lamp, lit by `energy`, at FLOOR_GREY."""
    lamp = scene.lights[0]
    under = ps.unobstructed_irradiance(scene, energy, lamp.position[None, :2])[0]
    return FLOOR_GREY / (paper.FLOOR_ALBEDO * under / math.pi)


def shot(scene, settings: RenderSettings, patch: tuple[np.ndarray, float] | None = None) -> dict:
    """Render `scene`; return its linear image (pixy,pixx,3), the floor's
    caustic measures, the stage times (s) and, given a `patch` (centre (2,),
    radius m), the noise there."""
    result = render(scene, settings)
    floor = result.maps["Floor"]
    out = {"image": result.image[..., :3], "caustic": ps.measure(floor, scene, settings.energy),
           "seconds": result.stats["seconds"]}
    if patch is not None:
        out["noise"] = ps.noise(floor, *patch)
    return out


def record(case: dict, out: dict, **extra) -> dict:
    """One row of paper.json: the case's parameters, its measures and times."""
    return {**case, **out["caustic"].as_dict(), **extra, "seconds": rounded(out["seconds"])}


def rounded(seconds: dict) -> dict:
    """Stage times to the millisecond."""
    return {k: round(v, 3) for k, v in seconds.items()}


def save_grid(path: Path, title: str, images: list[list[np.ndarray]], rows: list[str], cols: list[str],
              captions: list[list[str]], gain: float) -> None:
    """A gallery of linear images (pixy,pixx,3), all shown through srgb(gain * image)."""
    fig, axes = plt.subplots(len(rows), len(cols), figsize=(3.2 * len(cols), 2.75 * len(rows)), squeeze=False)
    for i, row in enumerate(images):
        for j, image in enumerate(row):
            ax = axes[i, j]
            ax.imshow(srgb(gain * image))
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_xlabel(captions[i][j], fontsize=8)
            if i == 0:
                ax.set_title(cols[j], fontsize=10)
            if j == 0:
                ax.set_ylabel(rows[i], fontsize=10)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def shape_sweeps(photons: int, heights: tuple[float, ...]) -> dict[tuple, dict]:
    """Every (shape, ior, height) of tables 1-3 and 7: all IORS at rest and
    at RAISED, glass at every height. Returns case -> shot."""
    cases = {(s, n, h) for s in paper.SHAPES for h in heights
             for n in (IORS if h in (0.0, paper.RAISED) else (ps.GLASS_IOR,))}
    shots = {}
    for shape, ior, height in sorted(cases):
        scene = ps.paper_scene(shape, ior, height)
        settings = ps.splat_settings(scene, ps.SHAPE_MAP_SCALE, lamp_rays=photons, energy=ENERGY)
        shots[shape, ior, height] = shot(scene, settings) | {"scene": scene}
        print(f"  {shape:7s} n = {ior:<4} height {height:4.2f} m: {caption(shots[shape, ior, height]['caustic'])}",
              flush=True)
    return shots


def shape_rows(shots: dict[tuple, dict]) -> list[dict]:
    """paper.json rows of the shape sweeps; the round glass's also carry the
    exact on-axis r50 and its paraxial image and floor distances (m)."""
    rows = []
    for (shape, ior, height), out in sorted(shots.items()):
        extra = {}
        if shape == "round":
            scene = out["scene"]
            extra = {"reference_r50": ps.reference_r50(scene), "paraxial_image": ps.paraxial_image_distance(scene),
                     "floor_distance": ps.floor_distance(scene)}
        rows.append(record({"shape": shape, "ior": ior, "height": height}, out, **extra))
    return rows


def caption(c: ps.Caustic) -> str:
    """The caustic in one line."""
    return f"r50 {c.r50:.3f} m, peak {c.peak:.3g} W/m², offset {c.offset:.2f} m"


def shape_galleries(shots: dict[tuple, dict], heights: tuple[float, ...]) -> None:
    """paper_ior_<shape>.png (rest and RAISED x IORS) and paper_height.png (shapes x heights, glass)."""
    gain = exposure(ps.paper_scene("round"), ENERGY)
    for shape in paper.SHAPES:
        grid = [[shots[shape, n, h] for n in IORS] for h in (0.0, paper.RAISED)]
        save_grid(RESULTS / f"paper_ior_{shape}.png",
                  f"Table {ps.PAPER_TABLES['ior_' + shape]}: {shape} base, index of refraction",
                  [[o["image"] for o in row] for row in grid], ["resting", f"raised {paper.RAISED} m"],
                  [f"n = {n}" for n in IORS], [[caption(o["caustic"]) for o in row] for row in grid], gain)
    grid = [[shots[s, ps.GLASS_IOR, h] for h in heights] for s in paper.SHAPES]
    save_grid(RESULTS / "paper_height.png",
              f"Table {ps.PAPER_TABLES['height']}: object height (n = {ps.GLASS_IOR})",
              [[o["image"] for o in row] for row in grid], list(paper.SHAPES), [f"{h} m" for h in heights],
              [[caption(o["caustic"]) for o in row] for row in grid], gain)


def target_fraction(scene) -> float:
    """Share of a lamp's rays over the whole sphere of directions (the
    paper's eq. 1) that head into the glass's bounding sphere."""
    sphere = Sphere.around(scene.objects[1].mesh.vertices)
    distance = np.linalg.norm(sphere.center - scene.lights[0].position)
    return 0.5 * (1.0 - math.sqrt(1.0 - (sphere.radius / distance) ** 2))


def log_slope(x, y) -> float:
    """Least-squares slope of log y against log x."""
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def resting_pair() -> tuple:
    """The round and the flat glass at rest on the ps.RESTING_FLOOR."""
    return ps.paper_scene("round", floor=ps.RESTING_FLOOR), ps.paper_scene("flat", floor=ps.RESTING_FLOOR)


def photon_sweep(counts: tuple[int, ...]) -> dict:
    """Table 4: the paper's map (splat, 5 mm), energy 10, at each lamp ray
    count: the round glass's caustic and the noise on the flat glass's even patch."""
    round_scene, flat_scene = resting_pair()
    patch = ps.flat_patch(flat_scene)
    rows, lenses, slabs = [], [], []
    for count in counts:
        lens = shot(round_scene, ps.splat_settings(round_scene, 5.0, lamp_rays=count, energy=ENERGY))
        slab = shot(flat_scene, ps.splat_settings(flat_scene, 5.0, lamp_rays=count, energy=ENERGY), patch)
        rows.append(record({"photons": count}, lens, noise_flat=slab["noise"], seconds_flat=rounded(slab["seconds"])))
        lenses.append(lens)
        slabs.append(slab)
        print(f"  {count:>10,} rays: noise {slab['noise']:.4f}; {caption(lens['caustic'])}", flush=True)
    save_grid(RESULTS / "paper_photons.png", f"Table {ps.PAPER_TABLES['lamp_rays']}: lamp rays (splat map, 5 mm)",
              [[o["image"] for o in lenses], [o["image"] for o in slabs]], ["round", "flat"],
              [f"{c:,} rays" for c in counts],
              [[caption(o["caustic"]) for o in lenses], [f"noise {o['noise']:.3f}" for o in slabs]],
              exposure(round_scene, ENERGY))
    return {"map_scale_mm": 5.0, "rows": rows, "noise_exponent": log_slope(counts, [r["noise_flat"] for r in rows]),
            "patch": {"centre": patch[0].tolist(), "radius": patch[1]},
            "rays_into_glass_per_sphere_ray": target_fraction(round_scene)}


def energy_sweep(photons: int) -> dict:
    """Table 5: lamp energy 10 and 20 on the paper's map (splat, 5 mm), same
    seed; also how far the brighter map is from exactly proportional."""
    low, high = ps.PAPER_SWEEPS["energy"]
    rows, images, captions, flux = [], [], [], {}
    for shape in ("round", "flat"):
        scene = ps.paper_scene(shape, floor=ps.RESTING_FLOOR)
        images.append([])
        captions.append([])
        for energy in (low, high):
            result = render(scene, ps.splat_settings(scene, 5.0, lamp_rays=photons, energy=energy))
            caustic = ps.measure(result.maps["Floor"], scene, energy)
            flux[shape, energy] = result.maps["Floor"].flux
            rows.append({"shape": shape, "energy": energy, **caustic.as_dict(),
                         "seconds": rounded(result.stats["seconds"])})
            images[-1].append(result.image[..., :3])
            captions[-1].append(caption(caustic))
    save_grid(RESULTS / "paper_energy.png",
              f"Table {ps.PAPER_TABLES['energy']}: lamp energy ({photons:,} rays, splat 5 mm)", images,
              ["round", "flat"], [f"energy {e:g}" for e in (low, high)], captions,
              exposure(ps.paper_scene("round"), low))
    deviation = max(float(np.abs(flux[s, high] - (high / low) * flux[s, low]).max() / flux[s, high].max())
                    for s in ("round", "flat"))
    return {"photons": photons, "rows": rows, "map_ratio_max_relative_deviation": deviation}


def map_scale_sweep(counts: tuple[int, ...]) -> dict:
    """Table 6: the paper's map at 5 and 40 mm cells, at each ray count of
    `counts`: the round glass's caustic and the flat glass's noise."""
    round_scene, flat_scene = resting_pair()
    patch = ps.flat_patch(flat_scene)
    scales = ps.PAPER_SWEEPS["map_scale"]
    rows, images, captions = [], [], []
    for count in counts:
        lenses = [shot(round_scene, ps.splat_settings(round_scene, mm, lamp_rays=count, energy=ENERGY)) for mm in scales]
        slabs = [shot(flat_scene, ps.splat_settings(flat_scene, mm, lamp_rays=count, energy=ENERGY), patch)
                 for mm in scales]
        for mm, lens, slab in zip(scales, lenses, slabs):
            rows.append(record({"photons": count, "map_scale_mm": mm}, lens, noise_flat=slab["noise"]))
            print(f"  {count:>10,} rays, {mm:g} mm: noise {slab['noise']:.4f}; {caption(lens['caustic'])}",
                  flush=True)
        images += [[o["image"] for o in lenses], [o["image"] for o in slabs]]
        captions += [[caption(o["caustic"]) for o in lenses], [f"noise {o['noise']:.3f}" for o in slabs]]
    save_grid(RESULTS / "paper_map_scale.png", f"Table {ps.PAPER_TABLES['map_scale']}: map scale (splat)",
              images, [f"{s}, {c:,} rays" for c in counts for s in ("round", "flat")],
              [f"{mm:g} mm" for mm in scales], captions, exposure(round_scene, ENERGY))
    return {"rows": rows}


def complexity_scene(triangles: int):
    """The resting glass ball as a UV sphere of about `triangles` triangles, seen at 320x240."""
    scene = ps.paper_scene("round")
    mesh = shapes.sphere_for_triangles(triangles, paper.RADIUS, (0.0, 0.0, paper.GAP + paper.RADIUS))
    scene.objects[1] = Object("Glass", mesh, Dielectric(ps.GLASS_IOR))
    return scene


def complexity(sizes: tuple[int, ...], photons: int, repeats: int) -> dict:
    """Seconds per stage (best of `repeats`) against the triangle count, and
    each stage's growth exponent: over all sizes and from 16k triangles up."""
    rows = []
    for size in sizes:
        scene = complexity_scene(size)
        runs = [render(scene, RenderSettings(lamp_rays=photons, spp=1, energy=ENERGY, density="adaptive")).stats for _ in range(repeats)]
        best = {stage: min(r["seconds"][stage] for r in runs) for stage in ("bvh", "photons", "eye")}
        rows.append({"triangles": len(scene.objects[1].mesh.triangles), **best, "total": sum(best.values()),
                     "rays_lamp_pass": runs[0]["rays_lamp_pass"], "rays_eye_pass": runs[0]["rays_eye_pass"]})
        print(f"  {rows[-1]['triangles']:>9,} triangles: " + ", ".join(f"{k} {best[k]:.3f} s" for k in best),
              flush=True)
    n = [r["triangles"] for r in rows]
    large = [i for i, r in enumerate(rows) if r["triangles"] >= 16_000]
    exponents = {}
    for stage in ("bvh", "photons", "eye", "total"):
        t = [r[stage] for r in rows]
        exponents[stage] = {"all": log_slope(n, t),
                            "from_16k": log_slope([n[i] for i in large], [t[i] for i in large])
                            if len(large) > 1 else None}
    plot_complexity(rows, exponents)
    return {"photons": photons, "pixels": "320x240, 1 spp", "repeats": repeats, "rows": rows, "exponents": exponents,
            "load_average_1min": os.getloadavg()[0]}


def plot_complexity(rows: list[dict], exponents: dict) -> None:
    """paper_complexity.png: stage seconds against triangles, log-log, with n and n log n guides."""
    n = np.array([r["triangles"] for r in rows], dtype=float)
    fig, ax = plt.subplots(figsize=(7, 5))
    for stage, marker in (("bvh", "o"), ("photons", "s"), ("eye", "^"), ("total", "D")):
        ax.loglog(n, [r[stage] for r in rows], marker=marker,
                  label=f"{stage}: n^{exponents[stage]['all']:.2f} (all), "
                        + (f"n^{exponents[stage]['from_16k']:.2f} (>=16k)" if exponents[stage]["from_16k"] else ""))
    bvh_end = rows[-1]["bvh"]
    ax.loglog(n, bvh_end * n / n[-1], "k:", label="linear, through the last BVH point")
    ax.loglog(n, bvh_end * n * np.log(n) / (n[-1] * np.log(n[-1])), "k--", label="n log n")
    ax.set_xlabel("triangles")
    ax.set_ylabel("seconds (best of runs)")
    ax.set_title("Time against mesh complexity (the paper says linear)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(RESULTS / "paper_complexity.png", dpi=100)
    plt.close(fig)


def shape_results(photons: int, heights: tuple[float, ...]) -> dict:
    """Tables 1-3 and 7: render, draw the galleries, return the rows."""
    shots = shape_sweeps(photons, heights)
    shape_galleries(shots, heights)
    return {"photons": photons, "map_scale_mm": ps.SHAPE_MAP_SCALE, "rows": shape_rows(shots)}



def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer photons, heights and mesh sizes")
    args = parser.parse_args()
    start = time.perf_counter()
    photons = 200_000 if args.quick else 1_000_000
    heights = (0.0, 0.25, paper.RAISED) if args.quick else HEIGHTS
    counts = ps.PAPER_SWEEPS["lamp_rays"][:-1] if args.quick else ps.PAPER_SWEEPS["lamp_rays"]
    RESULTS.mkdir(exist_ok=True)

    report = {"quick": args.quick,
              "scene": {"lamp": paper.LAMP_POSITION, "lamp_power_w": paper.LAMP_POWER, "radius": paper.RADIUS,
                        "cylinder_height": paper.CYLINDER_HEIGHT, "cone_height": paper.CONE_HEIGHT, "gap": paper.GAP,
                        "floor": paper.FLOOR_SIZE, "resting_floor": ps.RESTING_FLOOR, "eye": paper.EYE, "target": paper.TARGET,
                        "fov": paper.FOV},
              "seconds": {}}
    steps = [
        ("shapes", lambda: shape_results(photons, heights)),
        ("photons", lambda: photon_sweep(counts)),
        ("energy", lambda: energy_sweep(ps.PAPER_DEFAULTS["lamp_rays"])),
        ("map_scale", lambda: map_scale_sweep((ps.PAPER_DEFAULTS["lamp_rays"], photons))),
        ("complexity", lambda: complexity(COMPLEXITY_SIZES[:4] if args.quick else COMPLEXITY_SIZES, photons,
                                          1 if args.quick else 2)),
    ]
    for name, step in steps:
        print(f"{name}:", flush=True)
        clock = time.perf_counter()
        report[name] = step()
        report["seconds"][name] = round(time.perf_counter() - clock, 1)
    report["seconds"]["total"] = round(time.perf_counter() - start, 1)
    path = record.write("paper", report, indent=1)
    print(f"done in {report['seconds']['total']} s: {path}")


if __name__ == "__main__":
    main()
