"""The paper's scene rendered three ways, side by side, into out/:

    .venv/bin/python examples/demo.py [options]         (make demo)
    blender -b --factory-startup --python examples/demo.py -- [options]

The add-on's Add Paper Scene builds the paper's round glass of water over
its floor, under its lamp, seen by its camera (caustic_addon.paper). It is
rendered with the add-on's default settings (beams), with the paper's own
settings (40,000 lamp rays splatted into a 5 mm illumination map, which
the add-on coarsens to the 1024 cells a side it allows: 15.6 mm on the
16 m floor), and by
Cycles (with MNEE shadow caustics, the best Cycles has for a point lamp
through glass). Each gets its time and its error against a reference: the
same view with 25 times the lamp rays as beams refined twice, which the
accuracy benchmark shows within 1% of the exact caustic on a ball lens. The
paper's lamp energy 10 is moved into the lamp (100 W) so that Cycles sees
the same light.

Writes out/demo.png (the three, labelled; needs matplotlib, which the demo's
venv has), out/demo_beams.exr, demo_paper.exr and demo_cycles.exr (linear)
and out/demo.json (the figures).
Uses the installed extension if Blender has it, else the add-on in this
source tree. Exits 1 on any failure.
"""

import argparse
import importlib.util
import json
import math
import sys
import time
import traceback
from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[1]
# Exposure (stops) of the PNG: the paper's lamp lights its floor dimly.
EXPOSURE = 2.0


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description="Render the paper's scene three ways, side by side.")
    parser.add_argument("--out", type=Path, default=REPO / "out", help="output folder [out/]")
    parser.add_argument("--percentage", type=int, default=100, help="resolution percentage of 640x480 [100]")
    parser.add_argument("--samples", type=int, default=128, help="Cycles samples [128]")
    parser.add_argument("--reference-lamp-rays", type=int, default=1_000_000,
                        help="lamp rays of the reference render [1000000]")
    return parser.parse_args(argv)


def enable_addon():
    """(the add-on's module, whether this script registered it)."""
    for name, module in sys.modules.items():
        if name.endswith(".caustics") and hasattr(module, "export") and hasattr(bpy.types, "CAUSTIC_OT_render"):
            return module, False
    spec = importlib.util.spec_from_file_location("caustics", REPO / "__init__.py",
                                                  submodule_search_locations=[str(REPO)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["caustics"] = module
    spec.loader.exec_module(module)
    module.register()
    return module, True


def paper_scene(percentage: int):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert bpy.ops.caustic.add_paper_scene(shape='ROUND', ior_preset='WATER') == {'FINISHED'}
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.resolution_percentage = percentage
    bpy.data.lights["Lamp"].energy *= 10.0
    return scene


def pixels(name: str) -> np.ndarray:
    """(h,w,4) float32 of image `name`, top row first."""
    image = bpy.data.images[name]
    w, h = image.size
    out = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(out)
    return out.reshape(h, w, 4)[::-1]


def render_with(preset: str, **settings) -> tuple[np.ndarray, float]:
    """The add-on's render with a preset and then `settings` (Scene.caustic
    fields): (image (h,w,4), seconds)."""
    props = bpy.context.scene.caustic
    bpy.ops.caustic.apply_preset(preset=preset)
    props.energy = 1.0
    for name, value in settings.items():
        setattr(props, name, value)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return pixels("Caustic Render").copy(), props.last_seconds


def relative_error(image: np.ndarray, reference: np.ndarray, region: np.ndarray) -> float:
    """|image - reference| / |reference| over `region (h,w)`, RGB."""
    difference = image[..., :3][region] - reference[..., :3][region]
    return float(np.linalg.norm(difference) / np.linalg.norm(reference[..., :3][region]))


def save_exr(rgba: np.ndarray, path: Path) -> None:
    h, w = rgba.shape[:2]
    image = bpy.data.images.new(path.stem, w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    image.filepath_raw, image.file_format = str(path), 'OPEN_EXR'
    image.save()
    bpy.data.images.remove(image)


def figure(panels: list[tuple[str, np.ndarray]], path: Path) -> bool:
    """The panels side by side with their titles, sRGB at EXPOSURE; False
    without matplotlib."""
    try:
        import matplotlib
    except ImportError:
        return False
    matplotlib.use("Agg")
    from matplotlib import pyplot

    fig, axes = pyplot.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.6))
    for ax, (title, rgba) in zip(axes, panels):
        linear = np.clip(rgba[..., :3] * 2.0 ** EXPOSURE, 0.0, 1.0)
        srgb = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
        ax.imshow(srgb)
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    pyplot.close(fig)
    return True


def main():
    args = arguments()
    args.out.mkdir(parents=True, exist_ok=True)
    addon, registered = enable_addon()
    engine = sys.modules[addon.__name__ + ".caustic_addon"]
    try:
        scene = paper_scene(args.percentage)
        beams = render_with('DEFAULT')
        splat = render_with('PAPER_10_5')
        bpy.ops.caustic.apply_preset(preset='DEFAULT')
        scene.caustic.energy, scene.caustic.cycles_samples = 1.0, args.samples
        assert bpy.ops.caustic.compare_cycles() == {'FINISHED'}
        cycles = pixels("Cycles Reference").copy(), scene.caustic.cycles_seconds

        read = addon.export.read_scene(bpy.context)
        clock = time.perf_counter()
        exact = engine.render(read.scene, engine.RenderSettings(lamp_rays=args.reference_lamp_rays,
                                                                beam_refinement=2))
        reference_seconds = time.perf_counter() - clock
        caustic = exact.passes["caustic"].sum(axis=-1)
        region = caustic > 0.01 * caustic.max()

        rows = {"beams": ("beams (the default)", beams), "paper": ("the paper's settings: splat map", splat),
                "cycles": (f"Cycles, MNEE, {args.samples} samples", cycles)}
        figures = {key: {"title": title, "seconds": round(seconds, 3),
                         "relative_l2": relative_error(image, exact.image, region)}
                   for key, (title, (image, seconds)) in rows.items()}
        for key, (_, (image, _)) in rows.items():
            save_exr(image, args.out / f"demo_{key}.exr")
        labelled = figure([(f"{f['title']}\n{f['seconds']:.1f} s, error {100 * f['relative_l2']:.1f}%", rows[key][1][0])
                           for key, f in figures.items()], args.out / "demo.png")
        summary = dict(figures=figures, reference=dict(lamp_rays=args.reference_lamp_rays, beam_refinement=2,
                                                       seconds=round(reference_seconds, 3)),
                       pixels=list(exact.image.shape[1::-1]), blender=bpy.app.version_string)
        (args.out / "demo.json").write_text(json.dumps(summary, indent=2) + "\n")
        print(f"The paper's scene at {exact.image.shape[1]}x{exact.image.shape[0]}; error against "
              f"{args.reference_lamp_rays:,} lamp rays as beams ({reference_seconds:.1f} s), over the caustic:")
        for f in figures.values():
            print(f"  {f['title']:32s} {f['seconds']:6.2f} s   {100 * f['relative_l2']:6.2f}%")
        print(f"wrote {args.out / 'demo.png'}" if labelled else "matplotlib is missing: no demo.png")
        if not all(math.isfinite(f["relative_l2"]) for f in figures.values()):
            raise RuntimeError("an error is not finite")
    finally:
        if registered:
            addon.unregister()


if __name__ == "__main__":
    try:
        main()
    except Exception:
        traceback.print_exc()
        sys.exit(1)
