"""The engine's folds and cusps against an independent unbiased reference,
Mitsuba 3's particle tracer, and against exact images: on the ball lens's
fold ring, on sunlight through a wavy water slab, and on water with one
cosine wave whose exact caustic is known.

The scenes: benchmarks/scenes/ball_lens.py; benchmarks/scenes/wavy_slab.py's
under_water(); benchmarks/scenes/sine_slab.py (sine_slab, the wave along
the quads' edges under a vertical sun; sine_slab_diagonal, across their
diagonals under a slanted sun).

    .venv/bin/python benchmarks/mitsuba_folds.py [--scenes ball_lens wavy_slab sine_slab sine_slab_diagonal]
        [--counts 1e4 3e4 ...]
        [--refinement 1] [--mitsuba-python /tmp/mitsuba-venv/bin/python] [--reference-passes 64]

Mitsuba runs in its own venv (benchmarks/references/mitsuba_ptracer.py in a subprocess;
`pip install mitsuba`, its llvm_ad_rgb variant with Debian's libLLVM-19):
it is never a dependency of the add-on or of the tests. Both renderers see
the same triangles (the engine's meshes exported corner by corner, with
their shading normals), the same lamp and the same pinhole camera with a box
pixel filter, and their caustic on a white floor is radiance E / pi.

Paths: Mitsuba's ptracer counts every path, the engine's caustic pass only
light that reached the floor after a specular event, and no floor-to-floor
light. So that both count the same paths:
- max_depth 5: lamp, the glass twice (once more for an internal reflection
  in the ball), floor, camera; light from the floor back to the floor by
  the glass takes at least 6;
- the ball lens's point lamp becomes a spot of the same intensity whose cone
  just holds the ball (so no floor is lit directly, which the ball's
  underside would mirror into its shadow at depth 4);
- the wavy slab's floor in Mitsuba is only the part the slab shades, for the
  same reason (the lit floor around it, mirrored by the water's flat bottom,
  would add about 2%); its camera is between the water and the floor,
  looking down, since a particle tracer cannot see a diffuse floor through
  water (its connection to the camera is a shadow ray).

Errors are relative L2 over the caustic's pixels
(references/metrics.region_relative_l2), against Mitsuba's reference ("error") and against an exact
one ("error_vs_exact"): the ball lens's pixels inside the shadow disc,
against ball_lens.pixel_reference; the slabs' pixels that no wall's light
reaches (water_reference.wall_free), against the cosine waves' exact image
(sine_slab) and the wavy slab's image by water_reference's own float64
particle tracer (2 x 5e8 particles, its noise 0.05%). Mitsuba's reference is
`--reference-passes` passes of `--reference-spp` particles per pixel; its own noise is half the relative
L2 distance between its two halves (the halves' errors add in quadrature).
Mitsuba's curve renders independent seeds at increasing particles per pixel.

Writes benchmarks/results/mitsuba_folds.json and mitsuba_folds_<scene>_<label>.png
(engine, Mitsuba, and each one less the exact image, side by side).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root

from benchmarks import record  # noqa: E402
from benchmarks.references import water_reference  # noqa: E402
from benchmarks.references.metrics import region_relative_l2 as relative_l2  # noqa: E402
from benchmarks.references.water_reference import BOTTOM, DEPTH  # noqa: E402
from benchmarks.scenes import ball_lens, sine_slab, wavy_slab  # noqa: E402
from caustic_addon import RenderSettings, Scene, render, shapes  # noqa: E402
from caustic_addon.scene import Dielectric, PointLight, SunLight  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = record.RESULTS
PTRACER = HERE / "references" / "mitsuba_ptracer.py"
MITSUBA_PYTHON = "/tmp/mitsuba-venv/bin/python"
MAX_DEPTH = 5
COUNTS = (1e4, 3e4, 1e5, 3e5, 1e6)
MITSUBA_SPP = (4, 16, 64, 256, 1024)
SLAB_SIZE, SLAB_CELLS, SLAB_WAVES = wavy_slab.SIZE, wavy_slab.CELLS, wavy_slab.WAVES


def scene_of(name: str) -> Scene:
    if name == "ball_lens":
        return ball_lens.scene()
    if name.startswith("sine_slab"):
        return sine_slab.scene(name)
    return wavy_slab.under_water()


def _corners_and_normals(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(t,3,3) corners and (t,3,3) shading normals, wound so that the face
    normal agrees with them (Mitsuba's dielectric tells inside from outside
    by the shading normal)."""
    corners = mesh.corners
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals = mesh.corner_normals
    if normals is None:
        normals = np.repeat((face / np.linalg.norm(face, axis=1, keepdims=True))[:, None], 3, axis=1)
    flip = np.einsum("ij,ij->i", face, normals.sum(axis=1)) < 0
    corners[flip] = corners[flip][:, ::-1]
    normals = normals.copy()
    normals[flip] = normals[flip][:, ::-1]
    return corners, normals


def export_scene(name: str, scene: Scene, path: Path) -> None:
    """The scene as mitsuba_ptracer.py reads it (see the module docstring
    for the changes that keep both renderers to the same paths)."""
    cam = scene.camera
    rot, eye = cam.matrix[:3, :3], cam.matrix[:3, 3]
    meta = dict(max_depth=MAX_DEPTH, camera=dict(eye=eye.tolist(), target=(eye - rot[:, 2]).tolist(),
                                                 up=rot[:, 1].tolist(), fov_deg=math.degrees(cam.fov),
                                                 fov_axis="x" if cam.pixx >= cam.pixy else "y",
                                                 pixx=cam.pixx, pixy=cam.pixy))
    arrays = {}
    described = []
    (light,) = scene.lights
    if isinstance(light, PointLight):
        glass = next(o for o in scene.objects if isinstance(o.material, Dielectric))
        centre = 0.5 * (glass.mesh.vertices.min(axis=0) + glass.mesh.vertices.max(axis=0))
        reach = float(np.linalg.norm(glass.mesh.vertices - centre, axis=1).max())
        half = math.degrees(math.asin(reach / np.linalg.norm(centre - light.position)))
        meta["lamp"] = dict(type="spot", position=light.position.tolist(), target=centre.tolist(),
                            up=[0.0, 1.0, 0.0], intensity=float(light.power * light.color[0] / (4 * math.pi)),
                            cutoff_deg=half + 0.02, beam_width_deg=half + 0.01)
        assert abs(meta["lamp"]["intensity"] - ball_lens.INTENSITY) < 1e-9
    else:
        assert isinstance(light, SunLight)
        meta["lamp"] = dict(type="directional", direction=light.direction.tolist(),
                            irradiance=float(light.strength * light.color[0]))
    for obj in scene.objects:
        if isinstance(obj.material, Dielectric):
            shape = dict(bsdf="dielectric", ior=float(obj.material.ior))
            mesh = obj.mesh
        else:
            shape = dict(bsdf="diffuse", albedo=float(np.asarray(obj.material.albedo).reshape(-1)[0]))
            mesh = obj.mesh
            if name != "ball_lens":
                # only the floor the slab shades, moved as its shadow is by the sun's slant
                shift = -light.direction[:2] / light.direction[2] * BOTTOM
                mesh = shapes.plane(SLAB_SIZE - 0.1, (shift[0], shift[1], 0.0))
        corners, normals = _corners_and_normals(mesh)
        arrays[f"corners{len(described)}"], arrays[f"normals{len(described)}"] = corners, normals
        described.append(shape)
    meta["shapes"] = described
    np.savez(path, meta=json.dumps(meta), **arrays)


def mitsuba(name: str, scene: Scene, spp: int, passes: int, seed: int, args) -> dict:
    """Mitsuba's passes (cached in results/_mitsuba_*.npz, not committed)."""
    out = RESULTS / f"_mitsuba_{name}_{spp}x{passes}_{seed}.npz"
    if not out.exists():
        scene_file = RESULTS / f"_mitsuba_{name}_scene.npz"
        export_scene(name, scene, scene_file)
        subprocess.run([args.mitsuba_python, str(PTRACER), str(scene_file), str(out),
                        "--spp", str(spp), "--passes", str(passes), "--seed", str(seed),
                        "--threads", str(args.threads)], check=True)
    data = np.load(out)
    return dict(images=data["images"], wall=data["wall"], cpu=data["cpu"])


def water_reference_image(scene: Scene) -> tuple[np.ndarray, float]:
    """The wavy slab's image by water_reference's own float64 particle
    tracer, 2 x 5e8 particles (cached in results/_own_wavy_slab.npz, not
    committed), and its noise (half the relative L2 between the halves)."""
    out = RESULTS / "_own_wavy_slab.npz"
    if not out.exists():
        (sun,) = scene.lights
        halves = [water_reference.radiance(SLAB_SIZE, SLAB_CELLS, SLAB_WAVES, sun.direction,
                                           float(sun.strength * sun.color[0]), particles=5e8, seed=seed)
                  for seed in (0, 77)]
        np.savez(out, halves=np.array(halves))
    halves = np.load(out)["halves"]
    return halves.mean(axis=0), 0.5 * relative_l2(halves[0], halves[1], np.ones(halves[0].shape, dtype=bool))


def engine(scene: Scene, lamp_rays: int, refinement: int, threads: int) -> tuple[dict, np.ndarray]:
    settings = RenderSettings(lamp_rays=lamp_rays, spp=1, beam_refinement=refinement, threads=threads)
    wall, cpu = time.perf_counter(), time.process_time()
    result = render(scene, settings)
    figures = dict(lamp_rays=lamp_rays, refinement=refinement, paths=result.stats["lamp_rays"],
                   seconds=time.perf_counter() - wall, cpu_seconds=time.process_time() - cpu)
    return figures, result.passes["caustic"][..., 0].astype(np.float64)


def side_by_side(path: Path, images: list[np.ndarray], titles: list[str], region: np.ndarray, scale: float) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(images), figsize=(4.2 * len(images), 3.6))
    for ax, image, title in zip(axes, images, titles):
        if title.startswith("("):
            shown = ax.imshow(np.where(region, image, 0.0), cmap="RdBu_r", vmin=-0.1, vmax=0.1)
            fig.colorbar(shown, ax=ax, fraction=0.04)
        else:
            ax.imshow(np.clip(image / scale, 0, 1) ** (1 / 2.2), cmap="gray", vmin=0, vmax=1)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["ball_lens", "wavy_slab"])
    parser.add_argument("--counts", type=float, nargs="+", default=COUNTS)
    parser.add_argument("--refinement", type=int, nargs="+", default=[1])
    parser.add_argument("--mitsuba-spp", type=int, nargs="+", default=MITSUBA_SPP)
    parser.add_argument("--reference-spp", type=int, default=256)
    parser.add_argument("--reference-passes", type=int, nargs="+", default=[8, 48],
                        help="per scene, in the order of --scenes")
    parser.add_argument("--mitsuba-python", default=MITSUBA_PYTHON)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--label", default="curve", help="the key the engine's and Mitsuba's rows go under")
    parser.add_argument("--no-mitsuba-curve", action="store_true",
                        help="the engine's rows only (Mitsuba's rows under --label kept from the last run)")
    args = parser.parse_args()

    RESULTS.mkdir(exist_ok=True)
    report = record.read("mitsuba_folds")
    report.update(load=os.getloadavg())
    for name, reference_passes in zip(args.scenes, args.reference_passes):
        scene = scene_of(name)
        ref = mitsuba(name, scene, args.reference_spp, reference_passes, 1000, args)
        reference = ref["images"].mean(axis=0)
        np.save(RESULTS / f"_reference_{name}.npy", reference)
        halves = ref["images"][0::2].mean(axis=0), ref["images"][1::2].mean(axis=0)
        entry = report.setdefault(name, {})
        if name == "ball_lens":
            truth = ball_lens.pixel_reference(scene)
            region, exact = truth.region, truth.irradiance / math.pi
        elif name.startswith("sine_slab"):
            region, exact = sine_slab.region(name), sine_slab.exact_radiance(name)
        else:
            exact, own_noise = water_reference_image(scene)
            top = DEPTH + sum(wave[0] for wave in SLAB_WAVES)
            region = water_reference.wall_free(SLAB_SIZE, top, scene.lights[0].direction)
        entry["reference"] = dict(
            particles_per_pixel=args.reference_spp * reference_passes, wall=float(ref["wall"].sum()),
            cpu_seconds=float(ref["cpu"].sum()), pixels=int(region.sum()),
            noise=0.5 * relative_l2(halves[0], halves[1], region))
        if name == "wavy_slab":
            entry["reference"]["own_tracer_noise"] = own_noise
        entry["reference"]["error_vs_exact"] = relative_l2(reference, exact, region)
        entry["reference"]["mean_ratio_vs_exact"] = float(reference[region].sum() / exact[region].sum())
        rows = [row for row in entry.get(args.label, []) if row["renderer"] != "engine beams"] \
            if args.no_mitsuba_curve else []
        for spp in [] if args.no_mitsuba_curve else args.mitsuba_spp:
            passes = max(1, spp // args.reference_spp)
            run = mitsuba(name, scene, spp // passes, passes, 7 * spp, args)
            image = run["images"].mean(axis=0)
            row = dict(renderer="mitsuba ptracer", particles_per_pixel=spp, seconds=float(run["wall"].sum()),
                       cpu_seconds=float(run["cpu"].sum()), error=relative_l2(image, reference, region),
                       error_vs_exact=relative_l2(image, exact, region))
            rows.append(row)
            print(name, row, flush=True)
        best = None
        for refinement in args.refinement:
            for count in args.counts:
                figures, caustic = engine(scene, int(count), refinement, args.threads)
                figures.update(renderer="engine beams", error=relative_l2(caustic, reference, region),
                               error_vs_exact=relative_l2(caustic, exact, region))
                rows.append(figures)
                best = caustic
                print(name, figures, flush=True)
        entry[args.label] = rows
        record.write("mitsuba_folds", report)
        if best is not None:
            scale = float(np.quantile(reference[region], 0.995))
            # the caustic's box, with a margin
            rows, cols = np.nonzero(region & (reference > 0.02 * scale))
            crop = (slice(max(rows.min() - 8, 0), rows.max() + 9), slice(max(cols.min() - 8, 0), cols.max() + 9))
            best, reference, exact, region = best[crop], reference[crop], exact[crop], region[crop]
            images = [best, reference, (best - exact) / scale, (reference - exact) / scale]
            titles = [f"engine, {int(args.counts[-1]):,} lamp rays", f"Mitsuba ptracer, "
                      f"{args.reference_spp * reference_passes:,} particles/pixel",
                      "(engine - exact) / bright level", "(Mitsuba - exact) / bright level"]
            side_by_side(RESULTS / f"mitsuba_folds_{name}_{args.label}.png", images, titles, region, scale)
            np.save(RESULTS / f"_engine_{name}.npy", best)


if __name__ == "__main__":
    main()
