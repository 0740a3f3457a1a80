"""Writes benchmarks/README.md from the kept measurements' results: one
section per measurement, with what it measures, when, where and at which
commit, a table of its headline figures and its plots.

    .venv/bin/python benchmarks/report.py [--out benchmarks/README.md]
    .venv/bin/python benchmarks/report.py --readme README.md   # also its headline figures

Every number comes from benchmarks/results/<name>.json (the gallery's from
docs/gallery/gallery.json), read by that measurement's formatter in
FORMATTERS; what a measurement measures is the first paragraph of its
script's docstring. The output depends on those files alone (no clock), so
running it twice writes the same README. With --readme, the table that
`headline()` makes also replaces what lies between the HEADLINE markers of
that file.
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import sys
from pathlib import Path
from typing import Callable

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks.record import RESULTS  # noqa: E402

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
GALLERY = REPO / "docs" / "gallery"
HEADLINE = ("<!-- headline figures: written by benchmarks/report.py from benchmarks/results/*.json -->",
            "<!-- end of headline figures -->")
NONE = "–"

Table = tuple[list[str], list[list[str]]]


# ---------------------------------------------------------------- numbers

def seconds(x) -> str:
    if x is None:
        return NONE
    return f"{x:.3g} s" if x < 0.1 else f"{x:.2f} s" if x < 100 else f"{x:,.0f} s"


def reached(x) -> str:
    """A time to reach an error level; None: not reached in the sweep."""
    return "not reached" if x is None else seconds(x)


def percent(x, digits: int | None = None) -> str:
    """x as a percentage: `digits` decimals, or by default 2, and 2
    significant digits below 0.1%."""
    if x is None:
        return NONE
    if digits is None and abs(100 * x) < 0.1:
        return f"{100 * x:.2g}%"
    return f"{100 * x:.{2 if digits is None else digits}f}%"


def rate(x) -> str:
    return NONE if x is None else f"{x / 1e6:.2f} M"


def count(x) -> str:
    return NONE if x is None else f"{int(x):,}"


def number(x, digits: int = 3) -> str:
    return NONE if x is None else f"{x:.{digits}g}"


def slashed(values, form: Callable = number, unit: str = "") -> str:
    return " / ".join(form(v) for v in values) + unit


# ------------------------------------------------------------- formatters
# Each takes a results file's figures and returns (header, rows): a short
# table of its headline figures.

def accuracy(d: dict) -> Table:
    rows = []
    for name, points in d["curves"].items():
        reach = d["time_to_reach"][name]
        best = min(points, key=lambda p: p["error"])
        rows.append([name, *(reached(reach[key]) for key in ("10%", "5%", "2%")),
                     f"{percent(best['error'])} ({count(best['lamp_rays'])} lamp rays, {seconds(best['seconds'])})"])
    return ["density estimate", "to 10%", "to 5%", "to 2%", "lowest error"], rows


def cycles_accuracy(d: dict) -> Table:
    names = list(d["curves"])
    by_samples = {name: {p["samples"]: p for p in points} for name, points in d["curves"].items()}
    samples = sorted({s for points in by_samples.values() for s in points})

    def cell(name, s):
        p = by_samples[name].get(s)
        return NONE if p is None else f"{seconds(p['seconds'])}, {percent(p['error'])}"

    return (["samples", *(f"{name}: time, error" for name in names)],
            [[count(s), *(cell(name, s) for name in names)] for s in samples])


MITSUBA_SCENES = {"ball_lens": "ball lens", "wavy_slab": "wavy slab (exact: water_reference's float64 tracer)",
                  "sine_slab": "one cosine wave", "sine_slab_diagonal": "one cosine wave, across the diagonals"}


def mitsuba_folds(d: dict) -> Table:
    def run(row) -> str:
        return NONE if row is None else f"{seconds(row['seconds'])}, {percent(row.get('error_vs_exact'))}"

    rows = []
    for scene, name in MITSUBA_SCENES.items():
        if scene not in d:
            continue
        entry = d[scene]
        curve = entry.get("curve", [])
        mitsuba = [r for r in curve if r["renderer"] == "mitsuba ptracer"]
        engine = [r for r in curve if r["renderer"] == "engine beams"]
        ref = entry["reference"]
        rows.append([name, f"{count(ref['particles_per_pixel'])}, noise {percent(ref['noise'])}, "
                           f"{percent(ref['error_vs_exact'])}",
                     run(max(mitsuba, key=lambda r: r["particles_per_pixel"], default=None)),
                     run(next((r for r in engine if r["lamp_rays"] == 100_000), None)),
                     run(max(engine, key=lambda r: r["lamp_rays"], default=None))])
    most = max((r["lamp_rays"] for s in MITSUBA_SCENES if s in d for r in d[s].get("curve", [])
                if r["renderer"] == "engine beams"), default=None)
    spp = max((r["particles_per_pixel"] for s in MITSUBA_SCENES if s in d for r in d[s].get("curve", [])
               if r["renderer"] == "mitsuba ptracer"), default=None)
    return (["scene", "Mitsuba's reference: particles/pixel, noise, error",
             f"Mitsuba, {count(spp)} particles/pixel: time, error", "engine, 100,000 lamp rays: time, error",
             f"engine, {count(most)} lamp rays: time, error"], rows)


def speed(d: dict) -> Table:
    raw = d["raw_embree_rays_per_s"]
    return ["measure", "figure"], [
        ["Embree alone, 2 threads", f"{rate(raw)} rays/s (through embreex: {rate(d['embreex_rays_per_s'])})"],
        [f"photon pass, {count(d['photons'])} photons", f"{seconds(d['photon_pass_s'])}: "
         f"{rate(d['photon_paths_per_s'])} paths/s, {rate(d['photon_pass_rays_per_s'])} rays/s "
         f"({percent(d['photon_pass_fraction_of_raw'], 0)} of raw)"],
        ["photon pass, the same sphere a mirror", f"{seconds(d['reflector_photon_pass_s'])}: "
         f"{rate(d['reflector_photon_paths_per_s'])} paths/s, {rate(d['reflector_photon_pass_rays_per_s'])} rays/s "
         f"({percent(d['reflector_over_glass_rays_per_s'], 0)} of the glass's per ray)"],
        [f"eye pass, {count(d['eye_pass_rays'])} rays", f"{seconds(d['eye_pass_s'])}: "
         f"{rate(d['eye_pass_rays_per_s'])} rays/s ({percent(d['eye_pass_fraction_of_raw'], 0)} of raw)"],
        ["BVH build", seconds(d["bvh_s"])],
        ["re-render after a camera move (maps cached)", seconds(d["rerender_after_camera_move_s"])],
    ]


def passes(d: dict) -> Table:
    targets = d["targets"]
    rows = []
    for view, rates in d["pass_rates"].items():
        for name, r in rates.items():
            rows.append([f"{name} pass, {view.replace('_', ' ')}",
                         f"{rate(r['rays_per_s'])} rays/s, {number(r['vs_embreex'], 2)}x embreex's "
                         f"{rate(r['embreex_rays_per_s'])}; Embree {percent(r['embree_share'], 0)} of the pass "
                         f"({number(r['embree_packets_of_8_s'] / r['embree_s'], 2)}x its time with closest hits "
                         "in packets of 8)",
                         f"{targets[name + '_vs_embreex']}x"])
    for level, t in d["seconds_to"].items():
        share = f"; Embree {percent(d['embree_share_at_5%'], 0)} of it" if level == "5%" else ""
        rows.append([f"ball lens 320x240 to {level} error, beams", f"{reached(t)} at "
                     f"{count(d['lamp_rays_to'][level])} lamp rays{share}", seconds(targets[f"seconds_to_{level}"])])
    full = d["render_1920x1080_4spp"]
    rows.append(["ball lens 1920x1080, 4 spp, beams", f"{seconds(full['wall_s'])} wall, {seconds(full['cpu_s'])} CPU; "
                 f"Embree {percent(full['embree_share'], 0)} of the wall", seconds(targets["seconds_1920x1080_4spp"])])
    return ["measure", "figure", "target"], rows


def bvh_build(d: dict) -> Table:
    rows = []
    for name, r in d["scenes"].items():
        cells = [f"{1e3 * r[q]['build_s']:.1f} ms + {seconds(r[q]['casts_s'])}" for q in d["qualities"]]
        rows.append([f"{name} ({count(r['triangles'])} triangles, {count(r['objects'])} objects, "
                     f"{count(r['rays'])} rays)", f"{1e3 * r['embreex_build_s']:.1f} ms", *cells])
    return ["scene", "embreex's build", *(f"{q} quality: build + casts" for q in d["qualities"])], rows


def beams_at_scale(d: dict) -> Table:
    scenes = list(d["curves"])
    by_rays = {scene: {r["lamp_rays"]: r for r in rows if r["refinement"] == 1} for scene, rows in d["curves"].items()}
    lamp_rays = sorted({n for rows in by_rays.values() for n in rows})

    def cell(scene, n):
        r = by_rays[scene].get(n)
        return NONE if r is None else (f"{seconds(r['cpu_seconds'])}, {percent(r['error'])}, "
                                       f"{r['peak_rss_mb']:,.0f} MB")

    return (["lamp rays", *(f"{scene.replace('_', ' ')}: CPU, error, peak memory" for scene in scenes)],
            [[count(n), *(cell(scene, n) for scene in scenes)] for n in lamp_rays])


def memory(d: dict) -> Table:
    return ["photons", "wall", "photons/s", "peak resident set"], [
        [count(r["photons"]), seconds(r["seconds"]), f"{r['photons_per_second']:,.0f}",
         f"{r['peak_rss_mb']:,.0f} MB"] for r in d["rows"]]


FIRST_RENDER = {"fresh_render_at_once": "fresh install, render at once",
                "fresh_render_after_background_compile": "fresh install, render after the background compile",
                "enabled_again_from_cache": "enabled again, kernels from the cache"}


def first_render(d: dict) -> Table:
    return ["case", "enable", "compile left", "first render", "second render"], [
        [name, seconds(d[key]["enable_s"]), seconds(d[key].get("background_compile_left_s")),
         seconds(d[key]["first_render_s"]), seconds(d[key]["second_render_s"])]
        for key, name in FIRST_RENDER.items() if key in d]


def animation(d: dict) -> Table:
    rows = []
    pool = d.get("pool")
    if pool:
        rows.append([f"Render Caustic Animation, {pool['resolution'][0]}x{pool['resolution'][1]}, "
                     f"mean of {pool['frames']} frames (the slowest {seconds(pool['max'])})",
                     seconds(pool["mean"]), seconds(pool["cpu_total"] / pool["frames"])])
    final = d["final_frame"]
    for name, figures in final["seconds_per_frame"].items():
        rows.append([name, seconds(figures["wall"]), seconds(figures["cpu"])])
    return [f"way (Cycles: {final['resolution_percentage']}% size, {final['cycles_samples']} samples)",
            "wall a frame", "CPU a frame"], rows


def farm(d: dict) -> Table:
    rows = [["one local Render Caustic Animation of the 6 frames", seconds(d["local_run_s"]), NONE],
            ["a process start alone (bpy, the add-on, the file)", seconds(d["process_start_s"]), NONE]]
    for chunk_size, r in d["one_worker"].items():
        chunks = f"{r['chunks']} chunk{'s' * (r['chunks'] > 1)}"
        rows.append([f"the job on one Worker, {chunks} of {chunk_size}", seconds(r["job_s"]),
                     seconds(r["overhead_per_chunk_s"])])
    rows.append(["the job on two Workers, chunks of 2", seconds(d["two_workers_chunks_of_2_s"]), NONE])
    return ["run", "wall", "over the local run, a chunk"], rows


def live(d: dict) -> Table:
    rows = [[f"drag the {name}", f"{f['triangles']:,}", number(f["updates_per_s"], 2), seconds(f["latency_median_s"]),
             seconds(f["latency_p95_s"]), f"{f['main_thread_ms_median']:.0f} ms", f"{f['refine_main_thread_ms']:.0f} ms",
             f"{f['engine_ms_median']:.0f} ms" if "engine_ms_median" in f else NONE,
             f"{f['bvh_ms_median']:.0f} ms" if "bvh_ms_median" in f else NONE,
             seconds(f["refined_after_s"]) if "refined_after_s" in f else NONE,
             percent(f["preview_error"]), f"{f['resident_growth_mb']:.0f} MB"] for name, f in d["scenes"].items()]
    for kind, played in d.get("playback", {}).items():
        for loop, f in enumerate(played["loops"]):
            rows.append([f"play {f['frames']} frames at {d['fps']} fps, the ball {kind}, loop {loop + 1}", NONE,
                         number(f["shown_per_s"], 2), NONE, NONE, NONE, NONE, NONE, NONE, NONE, NONE,
                         f"maps kept {f['maps_kept']} of {f['shown']} times"])
    return ["run", "triangles", "updates a second", "latency, median", "p95", "main thread, a preview",
            "main thread, the refine", "engine, a preview", "BVH and bodies, a preview",
            "full quality after the last change",
            "preview's error", "memory growth"], rows


def instances(d: dict) -> Table:
    rows = [[f"{f['instances']:,}", f"{f['triangles']:,}", seconds(f["render_s"]), seconds(f["read_s"]),
             seconds(f["engine_s"]), f"{f['peak_growth_mb']:,.0f} MB"] for f in d["runs"].values()]
    return [f"ico-spheres ({d['resolution'][0]}x{d['resolution'][1]})", "triangles", "Render Caustics",
            "scene read", "engine", "peak memory growth"], rows


def glints(d: dict) -> Table:
    reference = d["cycles_reference"]
    rows = [[f"the add-on, {name}", f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]), seconds(f["seconds"])]
            for name, f in d["ours"].items()]
    rows += [[f"Cycles, {samples} samples", f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]),
              seconds(f["seconds"])] for samples, f in d["cycles"].items()]
    rows.append([f"Cycles, {reference['samples']} samples (the reference; its own noise)", "x1", percent(
        reference["relative_l2_noise"]), seconds(reference["seconds"])])
    return ["render", "image mean against the reference", "relative L2 error", "time"], rows


def glossy_floor(d: dict) -> Table:
    rows = []
    for roughness, floor in d["roughness"].items():
        for samples, ours in floor["ours"].items():
            theirs = floor["cycles"][samples]
            rows.append([roughness, samples, f"x{ours['mean_ratio']:.3f}", percent(ours["relative_l2"]),
                         seconds(ours["seconds"]), percent(theirs["relative_l2"]), seconds(theirs["seconds"]),
                         percent(floor["cycles_reference"]["relative_l2_noise"])])
    return ["roughness", "samples a pixel", "the add-on's mean against the reference",
            "the add-on's relative L2 error", "its time", "Cycles' relative L2 error", "its time",
            "the reference's own noise"], rows


def emitters(d: dict) -> Table:
    reference = d["cycles_reference"]
    rows = [[f"the add-on, {name}", f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]),
             percent(f["caustic_relative_l2"]), seconds(f["seconds"])] for name, f in d["ours"].items()]
    rows += [[f"Cycles, {samples} samples", f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]),
              percent(f["caustic_relative_l2"]), seconds(f["seconds"])] for samples, f in d["cycles"].items()]
    rows.append([f"Cycles, {reference['samples']} samples (the reference; its own noise)", "x1",
                 percent(reference["relative_l2_noise"]), percent(reference["caustic_relative_l2_noise"]),
                 seconds(reference["seconds"])])
    return ["render", "image mean against the reference", "relative L2 error",
            f"over the caustic ({d['caustic_pixels']} pixels)", "time"], rows


def liquid_glass(d: dict) -> Table:
    reference = d["cycles_reference"]

    def row(name: str, f: dict) -> list[str]:
        return [name, f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]), f"x{f['caustic_mean_ratio']:.3f}",
                percent(f["caustic_relative_l2"]), seconds(f["seconds"])]

    rows = [row(f"the add-on, {name}", f) for name, f in d["ours"].items()]
    rows += [row(f"Cycles, {name}", f) for name, f in d["cycles"].items()]
    rows.append([f"Cycles, {reference['samples']} samples (the reference; its own noise)", "x1",
                 percent(reference["relative_l2_noise"]), "x1", percent(reference["caustic_relative_l2_noise"]),
                 seconds(reference["seconds"])])
    return ["render", "image mean against the reference", "relative L2 error",
            f"caustic's mean ({d['caustic_pixels']} pixels)", "its relative L2 error", "time"], rows


def coated_floor(d: dict) -> Table:
    rows = []
    for name, r in d["floors"].items():
        f, c = r["ours"], r["cycles"]
        caustic = f"x{f['caustic_mean_ratio']:.3f} ({r['caustic_pixels']} pixels)"
        rows.append([name, f"x{f['mean_ratio']:.3f}", percent(f["relative_l2"]), caustic,
                     percent(f["caustic_relative_l2"]), percent(c["caustic_relative_l2_noise"]),
                     seconds(f["seconds"]), seconds(c["seconds"])])
    samples = next(iter(d["floors"].values()))["cycles"]["samples"]
    return ["the floor", "image mean against Cycles", "relative L2 error", "caustic's mean", "its relative L2 error",
            "Cycles' own noise there", "the add-on's time", f"Cycles' ({samples} samples)"], rows


def smooth_edges(d: dict) -> Table:
    rows = [[name, f"x{f['glass_mean_ratio']:.3f}", percent(f["glass_relative_l2"]), seconds(f["seconds"]),
             seconds(f["cycles_seconds"])] for name, f in d["shadings"].items()]
    return ["the tumbler's shading", "the add-on's mean over the glass against Cycles'", "relative L2 error there",
            "the add-on's time", f"Cycles' ({d['cycles_samples']} samples)"], rows


def allocator(d: dict) -> Table:
    names = {"default": "glibc's default", "engine": "the engine's setting"}
    rows = [[blender, names.get(setting, setting), seconds(f["seconds_per_frame"]), seconds(f["cpu_seconds_per_frame"]),
             f"{f['page_faults']:,.0f}", seconds(f["kernel_cpu_seconds"]), f"{f['peak_resident_mb']:,.0f} MB"]
            for blender, settings in sorted(d["blenders"].items()) for setting, f in sorted(settings.items())]
    return ["Blender", "malloc", "wall a frame", "CPU a frame", "page faults", "kernel CPU", "peak memory"], rows


def paper(d: dict) -> Table:
    shapes = d["shapes"]["rows"]
    iors = sorted({r["ior"] for r in shapes if r["height"] == 0.0})

    def across(shape: str, height: float, key: str) -> str:
        values = {r["ior"]: r[key] for r in shapes if r["shape"] == shape and r["height"] == height}
        return slashed([values.get(n) for n in iors], unit=" m")

    n = " / ".join(f"{i:g}" for i in iors)
    rows = [[f"{shape} glass {where}: {key} for n = {n}", across(shape, height, key)]
            for shape, key in (("round", "r50"), ("flat", "r50"), ("pointed", "offset"))
            for where, height in (("at rest", 0.0), ("raised 1 m", 1.0))]
    photons = d["photons"]
    rows.append([f"noise at {slashed([r['photons'] for r in photons['rows']], count)} lamp rays",
                 f"{slashed([r['noise_flat'] for r in photons['rows']])} (N^{photons['noise_exponent']:.2f})"])
    energy = [r for r in d["energy"]["rows"] if r["shape"] == "round"]
    rows.append([f"round glass, energy {slashed([r['energy'] for r in energy], lambda e: f'{e:g}')}: peak",
                 f"{slashed([r['peak'] for r in energy], unit=' W/m²')}; every cell in proportion within "
                 f"{d['energy']['map_ratio_max_relative_deviation']:g}"])
    scale = [r for r in d["map_scale"]["rows"] if r["photons"] == min(r["photons"] for r in d["map_scale"]["rows"])]
    rows.append([f"{count(scale[0]['photons'])} lamp rays, {slashed([r['map_scale_mm'] for r in scale], lambda m: f'{m:g}')}"
                 " mm cells: peak, noise", f"{slashed([r['peak'] for r in scale], unit=' W/m²')}, noise "
                 f"{slashed([r['noise_flat'] for r in scale])}"])
    cx = d["complexity"]
    ends = cx["rows"][0], cx["rows"][-1]
    rows.append([f"render time, {count(ends[0]['triangles'])} to {count(ends[1]['triangles'])} triangles",
                 f"{seconds(ends[0]['total'])} to {seconds(ends[1]['total'])} (BVH build grows as triangles^"
                 f"{cx['exponents']['bvh']['all']:.2f})"])
    return ["measure", "figure"], rows


def sized_lamps(d: dict) -> Table:
    levels = ("10%", "5%", "2%")
    rows = [[f"{name}: seconds to {' / '.join(levels)}", slashed([reach[k] for k in levels], reached)]
            for name, reach in d["time_to_reach"].items()]
    rows.append(["sphere lamp over point lamp, in time", slashed([d["sized_over_point"][k] for k in levels],
                                                                  lambda x: NONE if x is None else f"{x:.1f}x")])
    rows.append([f"converged engine ({seconds(d['engine_converged_seconds'])}) against Cycles at "
                 f"{count(d['cycles_samples'])} samples", f"{percent(d['engine_against_cycles'])} "
                 f"(Cycles' own noise {percent(d['cycles_noise'])})"])
    return [f"sphere lamp of radius {d['radius']:g} m, {d['pixels'][0]}x{d['pixels'][1]}", "figure"], rows


def rough_glass(d: dict) -> Table:
    ways = list(d["runs"][0]["time_to_reach"]) if d["runs"] else []
    rows = [[f"{run['roughness']:g}", f"{run['width_m']['cycles']:.3f} / {run['width_m']['engine']:.3f} m",
             f"{percent(run['engine_against_cycles'])} ({percent(run['cycles_noise'])})",
             *(slashed([run["time_to_reach"][way][k] for k in ("5%", "2%")], reached) for way in ways)]
            for run in d["runs"]]
    return (["roughness", "caustic width, Cycles / engine", "converged engine against Cycles (its noise)",
             *(f"{way}: to 5% / 2%" for way in ways)], rows)


def rough_beside_smooth(d: dict) -> Table:
    rows = [[run["way"], count(run["lamp_rays"]), percent(run["smooth_relative_l2"]),
             percent(run["rough_relative_l2"]), seconds(run["seconds"])] for run in d["runs"]]
    return ["beam mode", "lamp rays", "under the smooth ball: relative L2 error",
            "under the rough ball", "time"], rows


def through_glass(d: dict) -> Table:
    rows = [["pixels seen through the ball", count(d["pixels"])]]
    rows += [[f"{r['spp']} sample{'s' if r['spp'] > 1 else ''} per pixel, {count(d['lamp_rays'])} lamp rays",
              f"{percent(r['error'])} from {d['reference_spp']} samples, {seconds(r['seconds'])}"] for r in d["rows"]]
    return ["measure", "figure"], rows


def dispersion(d: dict) -> Table:
    rows = []
    for key, s in d["cost_seconds"].items():
        density, abbe = (part.strip() for part in key.split(", abbe"))
        what = "no dispersion" if abbe == "inf" else f"Abbe number {float(abbe):g}"
        rows.append([f"render, {density}, {what}", f"{seconds(s['total'])} (lamp pass {seconds(s['lamp_pass'])}, "
                                                   f"maps {seconds(s['maps'])})"])
    rows.append(["coloured slab against Beer-Lambert, R / G / B", slashed(d["slab"]["relative_error"], percent)])
    rows.append(["white point: spectral render's flux against the plain one, R / G / B",
                 slashed(d["white_point"]["relative_difference"], percent)])
    return ["measure", "figure"], rows


def cycles_dispersion(d: dict) -> Table:
    rows = []
    for case in d["cases"]:
        fit = case.get("cycles_fit")
        cycles = (f"Abbe {fit['abbe']:g}, n_d {fit['ior_d']:g}" if fit else "no dispersion")
        spread = f"{case['cycles_red_blue_deg']:.2f}°"
        if "engine_red_blue_deg" in case:
            spread += f" / {case['engine_red_blue_deg']:.2f}°"
        expected = NONE if case["expected_abbe"] is None else f"{case['expected_abbe']:g}"
        rows.append([f"{case['scale']:g}", f"{case['abbe_number']:g}", expected, cycles, spread])
    floor = d.get("engine_floor_abbe_20")
    if floor:
        spread = floor["red_blue_spread_mm"]
        rows.append(["engine, on the floor", "20", "20", NONE,
                     f"{spread['measured']:.2f} mm (exact {spread['exact']:.2f} mm)"])
    return ["Dispersion Scale", "Abbe Number", "Abbe expected", "Cycles renders", "red-blue spread: Cycles / engine"], rows


def flicker(d: dict) -> Table:
    return ["mode", "flicker", "temporal noise", "static frames identical", "a frame"], [
        [m["mode"], f"{m['flicker']:.3f}", percent(m["temporal_noise"]), "yes" if m["static_identical"] else "no",
         seconds(m["seconds_per_frame"])] for m in d["modes"]]


def gallery(d: dict) -> Table:
    return ["scene", "render", "lamp rays", "triangles"], [
        [name.replace("_", " "), seconds(r["seconds"]), count(r["lamp_rays"]), count(r["triangles"])]
        for name, r in d["renders"].items()]


def generic(d: dict) -> Table:
    """A results file with no formatter of its own: its top-level numbers."""
    rows = [[key.replace("_", " "), number(value, 4) if isinstance(value, float) else str(value)]
            for key, value in d.items()
            if key not in ("date", "machine", "commit") and isinstance(value, (int, float, str))]
    return ["figure", "value"], rows[:12]


FORMATTERS: dict[str, Callable[[dict], Table]] = {
    "accuracy": accuracy, "cycles_accuracy": cycles_accuracy, "mitsuba_folds": mitsuba_folds,
    "speed": speed, "passes": passes, "bvh_build": bvh_build, "beams_at_scale": beams_at_scale, "memory": memory,
    "first_render": first_render, "animation": animation, "live": live, "instances": instances, "farm": farm,
    "allocator": allocator,
    "paper": paper, "sized_lamps": sized_lamps, "rough_glass": rough_glass,
    "rough_beside_smooth": rough_beside_smooth, "through_glass": through_glass,
    "dispersion": dispersion, "cycles_dispersion": cycles_dispersion, "sky_caustics": emitters,
    "flicker": flicker, "gallery": gallery, "glints": glints, "glossy_floor": glossy_floor,
    "emitters": emitters, "liquid_glass": liquid_glass, "smooth_edges": smooth_edges, "coated_floor": coated_floor,
}

# (group, [(results name, title)]), in the README's order
SECTIONS = [
    ("Accuracy against exact references, Cycles and Mitsuba", [
        ("accuracy", "Error against time on the ball lens"),
        ("cycles_accuracy", "Cycles on the ball lens"),
        ("mitsuba_folds", "Folds and cusps against Mitsuba's particle tracer"),
    ]),
    ("Speed", [
        ("speed", "The photon and eye passes against Embree alone"),
        ("passes", "Each pass on its own rays, and the speed targets"),
        ("bvh_build", "Building the BVH, and Embree's build qualities"),
        ("beams_at_scale", "Beams from 10k to 50M lamp rays"),
        ("memory", "Memory against photon count"),
        ("first_render", "The first render after installing"),
        ("animation", "Animated caustics in Blender"),
        ("live", "Live caustics while the glass is dragged"),
        ("instances", "Scattered instances"),
        ("farm", "The render farm's overhead per chunk"),
        ("allocator", "The engine's malloc setting"),
    ]),
    ("Features", [
        ("paper", "The paper's experiments"),
        ("sized_lamps", "Lamps with a size, against Cycles"),
        ("glints", "Glints: a lamp seen in glass, against Cycles"),
        ("glossy_floor", "A glossy floor under a large light, against Cycles"),
        ("emitters", "A softbox built as an emitting mesh, against Cycles"),
        ("sky_caustics", "The sky's caustic, against Cycles"),
        ("liquid_glass", "Water in a glass tumbler, against Cycles"),
        ("smooth_edges", "Glass shaded smooth across its edges, against Cycles"),
        ("coated_floor", "A caustic on coated and metallic floors, against Cycles"),
        ("rough_glass", "Rough glass, against Cycles"),
        ("rough_beside_smooth", "A rough glass beside a smooth one"),
        ("through_glass", "The caustic seen through glass"),
        ("dispersion", "Dispersion and coloured glass"),
        ("cycles_dispersion", "Dispersion against Cycles"),
        ("flicker", "Flicker from frame to frame"),
        ("gallery", "The gallery"),
    ]),
]
# results whose script is not benchmarks/<name>.py, or whose files live elsewhere
SCRIPTS = {"gallery": "gallery.py"}
SOURCES = {"gallery": GALLERY / "gallery.json"}
IMAGES = {"gallery": lambda d: [GALLERY / f"{name}.png" for name in d["renders"]]}


# ----------------------------------------------------------------- README

def text(s: str) -> str:
    """`s` safe in markdown prose and table cells."""
    return re.sub(r"([<>*|])", r"\\\1", s)


def description(script: Path) -> str:
    """The first paragraph of the script's docstring, on one line."""
    doc = ast.get_docstring(ast.parse(script.read_text())) or ""
    return text(" ".join(doc.split("\n\n")[0].split()))


def when(date: str) -> str:
    """A results file's date as 'YYYY-MM-DD' or 'YYYY-MM-DD HH:MM UTC'."""
    m = re.fullmatch(r"(\d{4}-\d\d-\d\d)T(\d\d:\d\d)(?::\d\d)?(?:\+00:00|Z)", date)
    return f"{m[1]} {m[2]} UTC" if m else date


def stamp_line(d: dict) -> str:
    """Measured <date> on <machine>, commit <commit>; what a results file
    written before record.py lacks is said to be not recorded."""
    date = when(d["date"]) if d.get("date") else "(date not recorded)"
    machine = f" on {d['machine']}" if d.get("machine") else ", machine: not recorded"
    commit = f"commit {d['commit']}" if d.get("commit") else "commit: not recorded"
    return f"Measured {date}{machine}, {commit}."


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(text(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(text(c) for c in row) + " |" for row in rows]
    return lines


def slug(title: str) -> str:
    """GitHub's anchor of a heading."""
    return re.sub(r"[^\w\- ]", "", title.lower()).replace(" ", "-")


def load(name: str) -> dict | None:
    path = SOURCES.get(name, RESULTS / f"{name}.json")
    return json.loads(path.read_text()) if path.exists() else None


def images(name: str, d: dict) -> list[Path]:
    if name in IMAGES:
        return [p for p in IMAGES[name](d) if p.exists()]
    return sorted(p for p in RESULTS.glob(f"{name}*.png") if p.stem == name or p.stem.startswith(name + "_"))


def section(name: str, title: str) -> list[str]:
    script = HERE / SCRIPTS.get(name, f"{name}.py")
    lines = [f"### {title}", "", description(script) + f" ([{script.name}]({script.name}))", ""]
    d = load(name)
    if d is None:
        return lines + [f"Not measured yet: `.venv/bin/python benchmarks/{script.name}`.", ""]
    lines += [stamp_line(d), ""]
    try:
        header, rows = FORMATTERS.get(name, generic)(d)
    except (KeyError, TypeError, ValueError, IndexError) as error:
        raise SystemExit(f"benchmarks/report.py: results of {name} do not read as its formatter expects: {error!r}")
    lines += table(header, rows) + [""]
    for path in images(name, d):
        relative = path.relative_to(REPO)
        link = relative.relative_to("benchmarks") if relative.parts[0] == "benchmarks" else Path("..") / relative
        lines += [f"![{path.stem}]({link.as_posix()})", ""]
    return lines


INTRO = """\
# Benchmarks

The measurements kept for every release: each renders its scenes, compares
the engine against an exact or unbiased reference (or Cycles, or Mitsuba 3),
and writes its figures to `results/<name>.json`, stamped with the date, the
machine and the commit (`record.py`). This file is written from those files
by `report.py`; do not edit it by hand, and quote its figures rather than
restating them.

- `make bench` runs every measurement that does not need Mitsuba 3 (it
  builds the extension first, whose first render it times), then writes
  this file: hours. `make bench-mitsuba` runs the comparisons with Mitsuba
  3's particle tracer (in a venv of its own); `make bench-report` only
  writes this file again.
- One measurement: `.venv/bin/python benchmarks/<name>.py` (`--help` for its
  options), then `make bench-report`.
- `scenes/` holds the scenes the measurements build, `references/` the exact
  or unbiased references and the error metric (`references/metrics.py`);
  the engine's tests import both. `PAPER.md` discusses the paper's claims.
"""


def readme() -> str:
    lines = INTRO.splitlines() + [""]
    for group, entries in SECTIONS:
        lines.append(f"- {group}: " + " · ".join(f"[{title}](#{slug(title)})" for _, title in entries))
    lines.append("")
    known = {name for _, entries in SECTIONS for name, _ in entries}
    others = sorted(p.stem for p in RESULTS.glob("*.json") if p.stem not in known)
    groups = SECTIONS + ([("Other results", [(name, name.replace("_", " ").capitalize()) for name in others])]
                         if others else [])
    for group, entries in groups:
        lines += [f"## {group}", ""]
        for name, title in entries:
            lines += section(name, title)
    return "\n".join(lines).rstrip() + "\n"


# ------------------------------------------------------ headline figures

def measured(*results: dict) -> str:
    """Where and when `results` were measured: date and machine, once each."""
    said = []
    for d in results:
        line = f"{when(d.get('date', '?'))}, {', '.join(d.get('machine', '?').split(', ')[:2])}"
        if line not in said:
            said.append(line)
    return "; ".join(said)


def headline() -> str:
    """The few figures the repository's README leads with, as a table, each
    row with where and when it was measured."""
    rows = []
    acc, cyc = load("accuracy"), load("cycles_accuracy")
    if acc and cyc:
        name, best = min(((name, p) for name, points in cyc["curves"].items() for p in points),
                         key=lambda item: item[1]["error"])
        rows.append(["ball lens, 320x240: time to 2% error against the exact caustic",
                     f"{reached(acc['time_to_reach']['beam']['2%'])} (beams)",
                     f"Cycles' lowest error: {percent(best['error'], 0)} ({name}, {count(best['samples'])} samples, "
                     f"{seconds(best['seconds'])})", measured(acc, cyc)])
    folds = load("mitsuba_folds")
    if folds:
        for scene in ("ball_lens", "wavy_slab"):
            curve = folds.get(scene, {}).get("curve", [])
            engine = [r for r in curve if r["renderer"] == "engine beams" and r["lamp_rays"] == 1_000_000]
            mitsuba = [r for r in curve if r["renderer"] == "mitsuba ptracer"]
            if engine and mitsuba:
                m = max(mitsuba, key=lambda r: r["particles_per_pixel"])
                rows.append([f"{MITSUBA_SCENES[scene].split(' (')[0]}: error against the exact image"
                             + (" (float64 tracer)" if scene == "wavy_slab" else ""),
                             f"{percent(engine[0]['error_vs_exact'])} in {seconds(engine[0]['seconds'])} "
                             f"(1,000,000 light rays)",
                             f"Mitsuba's particle tracer: {percent(m['error_vs_exact'])} in {seconds(m['seconds'])}",
                             measured(folds)])
    sized = load("sized_lamps")
    if sized:
        reach = sized["time_to_reach"]
        rows.append(["sphere light through the ball lens: time to 5% error",
                     reached(reach["sphere lamp"]["5%"]),
                     f"Cycles path tracing: {reached(reach['Cycles path tracing']['5%'])}", measured(sized)])
    return "\n".join(table(["measure", "this engine", "against", "measured"], rows))


def fill_readme(path: Path) -> None:
    """Replace what lies between the HEADLINE markers of `path` with headline()."""
    body = path.read_text()
    start, end = body.find(HEADLINE[0]), body.find(HEADLINE[1])
    if start < 0 or end < start:
        raise SystemExit(f"{path}: no headline markers ({HEADLINE[0]} ... {HEADLINE[1]})")
    start += len(HEADLINE[0])
    path.write_text(body[:start] + "\n" + headline() + "\n" + body[end:])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=HERE / "README.md")
    parser.add_argument("--readme", type=Path, help="also write the headline figures between this file's markers")
    args = parser.parse_args()
    args.out.write_text(readme())
    print(args.out)
    if args.readme:
        fill_readme(args.readme)
        print(args.readme)


if __name__ == "__main__":
    main()
