"""The add-on beside Cycles, into out/:

    .venv/bin/python examples/demo.py [options]         (make demo)
    blender -b --factory-startup --python examples/demo.py -- [options]

A wine glass and a glass ball on a wooden table under a low sun with a
1-degree disc, in a pale sky: what an artist sets up for a caustic shot.
The add-on renders it with its default settings; Cycles renders the same
scene, path tracing its caustics, in the same time. Both go through
Blender's AgX view transform, as Blender shows them. The third panel is the
paper's own scene with the paper's settings (40,000 lamp rays splatted
into a 5 mm map).

The kernels are compiled (or loaded from their cache) first, and that
one-time step is reported on its own line: it is never a render's time.

Writes out/demo.png (the three panels, labelled; needs matplotlib, which
the demo's venv has), out/demo_<panel>.exr (linear) and out/demo.json.
Uses the installed extension if Blender has it, else the add-on in this
source tree, imported as the installed one is (packaging/source_tree.py).
Exits 1 on any failure.
"""

import argparse
import json
import math
import sys
import tempfile
import time
import traceback
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "packaging"))

from source_tree import blender_user_folders, import_addon  # noqa: E402

blender_user_folders()

import bpy  # noqa: E402
import numpy as np  # noqa: E402
PIXELS = (640, 400)


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description="The add-on beside Cycles at equal time.")
    parser.add_argument("--out", type=Path, default=REPO / "out", help="output folder [out/]")
    parser.add_argument("--percentage", type=int, default=100, help="resolution percentage of 640x400 [100]")
    return parser.parse_args(argv)


def enable_addon():
    """(the add-on's module, whether this script registered it)."""
    for name, module in sys.modules.items():
        if name.endswith(".caustics") and hasattr(module, "export") and hasattr(bpy.types, "CAUSTIC_OT_render"):
            return module, False
    module = import_addon()
    module.register()
    return module, True


def material(name: str, **inputs):
    """A Principled BSDF material with `inputs` (socket name: value)."""
    made = bpy.data.materials.new(name)
    if made.node_tree is None:
        made.use_nodes = True
    shader = made.node_tree.nodes["Principled BSDF"]
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    return made


def wine_glass_mesh(segments: int = 96) -> bpy.types.Mesh:
    """A wine glass 20 cm tall, its bowl 3 mm thick: a closed profile in
    (r, z), from the bowl's inner bottom on the axis to the foot's bottom,
    turned about z, smooth."""
    inner_radius, bottom, top, wall = 0.04, 0.11, 0.20, 0.003
    bend = np.linspace(0.0, 0.95 * math.pi / 2, 24)
    inner = [(0.0, bottom + wall)] + [((inner_radius - wall) * math.sin(a),
                                       bottom + wall + (inner_radius - wall) * (1 - math.cos(a))) for a in bend[1:]]
    outer = [(inner_radius * math.sin(a), bottom + inner_radius * (1 - math.cos(a))) for a in bend[::-1][:-1]]
    profile = (inner + [(inner_radius - wall, top), (inner_radius, top)] + outer
               + [(0.004, bottom), (0.004, 0.008), (0.035, 0.008), (0.035, 0.0), (0.0, 0.0)])
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    ring = np.arange(segments)
    verts, faces, previous = [], [], None
    for r, z in profile:
        if r == 0.0:
            here = [len(verts)]
            verts.append((0.0, 0.0, z))
        else:
            here = list(range(len(verts), len(verts) + segments))
            verts += list(zip(r * np.cos(phi), r * np.sin(phi), np.full(segments, z)))
        if previous is not None:
            for s in ring:
                quad = [previous[s % len(previous)], here[s % len(here)], here[(s + 1) % len(here)],
                        previous[(s + 1) % len(previous)]]
                faces.append(tuple(dict.fromkeys(quad)))
        previous = here
    mesh = bpy.data.meshes.new("Wine glass")
    mesh.from_pydata(verts, [], faces)
    return mesh


def artist_scene(percentage: int):
    """The wine glass and the ball on the table, the sun and the sky."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=3.0)
    bpy.context.object.name = "Table"
    bpy.context.object.data.materials.append(material("Wood", **{"Base Color": (0.42, 0.26, 0.15, 1.0),
                                                                "Roughness": 0.6}))
    glass = material("Glass", **{"Base Color": (1.0, 1.0, 1.0, 1.0), "Transmission Weight": 1.0,
                                 "Roughness": 0.0, "IOR": 1.5})
    wine = bpy.data.objects.new("Wine glass", wine_glass_mesh())
    scene.collection.objects.link(wine)
    wine.location = (0.06, 0.05, 0.0)
    wine.data.materials.append(glass)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.055, location=(-0.09, -0.04, 0.055), segments=96, ring_count=48)
    ball = bpy.context.object
    ball.name = "Ball"
    ball.data.materials.append(glass)
    for ob in (wine, ball):
        ob.data.shade_smooth()
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.energy, sun.data.angle, sun.data.color = 4.0, math.radians(1.0), (1.0, 0.93, 0.85)
    # behind the glasses: their shadows and caustics fall toward the camera
    sun.rotation_euler = (math.radians(-50.0), 0.0, math.radians(-25.0))
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("Sky")
    world.color = (0.35, 0.45, 0.6)
    if world.node_tree is None:
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.35, 0.45, 0.6, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.4
    scene.world = world
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.lens = 50.0
    camera.location = (0.0, -0.62, 0.30)
    camera.rotation_euler = (math.radians(66.0), 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = PIXELS
    scene.render.resolution_percentage = percentage
    scene.view_settings.view_transform = 'AgX'
    return scene


def paper_scene(percentage: int):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert bpy.ops.caustic.add_paper_scene(shape='ROUND', ior_preset='WATER') == {'FINISHED'}
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.resolution_percentage = percentage
    scene.view_settings.view_transform = 'AgX'
    return scene


def pixels(name: str) -> np.ndarray:
    """(h,w,4) float32 of image `name`, top row first."""
    image = bpy.data.images[name]
    w, h = image.size
    out = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(out)
    return out.reshape(h, w, 4)[::-1].copy()


def shown(rgba: np.ndarray, folder: Path, name: str) -> np.ndarray:
    """(h,w,3) in 0..1: `rgba` (linear, top row first) as the scene's view
    transform shows it, through Blender's own colour management."""
    h, w = rgba.shape[:2]
    image = bpy.data.images.new(name, w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    path = folder / f"{name}.png"
    # save_render writes in the scene's output format: an 8-bit PNG is what takes the view transform
    output = bpy.context.scene.render.image_settings
    kept = output.file_format, output.color_depth
    output.file_format, output.color_depth = 'PNG', '8'
    image.save_render(str(path), scene=bpy.context.scene)
    output.file_format, output.color_depth = kept
    bpy.data.images.remove(image)
    loaded = bpy.data.images.load(str(path))
    view = np.empty(w * h * 4, dtype=np.float32)
    loaded.pixels.foreach_get(view)
    bpy.data.images.remove(loaded)
    srgb = view.reshape(h, w, 4)[::-1, :, :3]
    return srgb


def metered(rgba: np.ndarray) -> np.ndarray:
    """`rgba` exposed so that its median lit pixel is mid-grey (0.18), as a
    photographer meters the paper's dim floor; alpha as it was."""
    luminance = rgba[..., :3] @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
    lit = luminance[luminance > 0.0]
    out = rgba.copy()
    if len(lit):
        out[..., :3] *= 0.18 / float(np.median(lit))
    return out


def save_exr(rgba: np.ndarray, path: Path) -> None:
    h, w = rgba.shape[:2]
    image = bpy.data.images.new(path.stem, w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    image.filepath_raw, image.file_format = str(path), 'OPEN_EXR'
    image.save()
    bpy.data.images.remove(image)


def render_addon(addon, **settings) -> tuple[np.ndarray, float]:
    """The add-on's Render at its defaults and `settings` (Scene.caustic
    fields): (image (h,w,4) linear, seconds)."""
    props = bpy.context.scene.caustic
    for name, value in settings.items():
        setattr(props, name, value)
    assert bpy.ops.caustic.render() == {'FINISHED'}
    return pixels("Caustic Render"), bpy.context.window_manager.caustic.last_seconds


def render_cycles(seconds: float, folder: Path) -> tuple[np.ndarray, float, int]:
    """Cycles path tracing the scene's caustics for `seconds`: (image (h,w,4)
    linear, seconds, samples it reached)."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.time_limit = 'CPU', 1 << 16, seconds
    cycles.use_denoising, cycles.use_adaptive_sampling = False, False
    cycles.caustics_reflective = cycles.caustics_refractive = True
    cycles.blur_glossy = 0.0
    cycles.max_bounces = cycles.transmission_bounces = cycles.glossy_bounces = 12
    cycles.diffuse_bounces = 1
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '32'
    scene.render.filepath = str(folder / "cycles.exr")
    samples = []
    bpy.app.handlers.render_stats.append(lambda stats: samples.append(stats))
    clock = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    took = time.perf_counter() - clock
    bpy.app.handlers.render_stats.clear()
    loaded = bpy.data.images.load(str(folder / "cycles.exr"))
    w, h = loaded.size
    out = np.empty(w * h * 4, dtype=np.float32)
    loaded.pixels.foreach_get(out)
    bpy.data.images.remove(loaded)
    reached = max((int(s.split("Sample ")[1].split("/")[0]) for s in samples if "Sample " in s), default=0)
    return out.reshape(h, w, 4)[::-1].copy(), took, reached


def figure(panels: list[tuple[str, np.ndarray]], path: Path) -> bool:
    """The panels (view-transformed, 0..1) side by side with their titles;
    False without matplotlib."""
    try:
        import matplotlib
    except ImportError:
        return False
    matplotlib.use("Agg")
    from matplotlib import pyplot

    fig, axes = pyplot.subplots(1, len(panels), figsize=(5.6 * len(panels), 4.2))
    for ax, (title, image) in zip(axes, panels):
        ax.imshow(np.clip(image, 0.0, 1.0))
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.95))
    fig.savefig(path, dpi=110)
    pyplot.close(fig)
    return True


def main():
    args = arguments()
    args.out.mkdir(parents=True, exist_ok=True)
    addon, registered = enable_addon()
    engine = sys.modules[addon.__name__ + ".caustic_addon"]
    try:
        clock = time.perf_counter()
        kernels = engine.compile_kernels()
        compile_seconds = time.perf_counter() - clock
        print(f"compiling the engine's {kernels} kernels, once (or loading them from their cache): "
              f"{compile_seconds:.1f} s", flush=True)
        with tempfile.TemporaryDirectory(prefix="caustic-demo-") as tmp:
            folder = Path(tmp)
            artist_scene(args.percentage)
            ours, ours_seconds = render_addon(addon)
            ours_shown = shown(ours, folder, "ours")
            cycles, cycles_seconds, cycles_samples = render_cycles(ours_seconds, folder)
            cycles_shown = shown(cycles, folder, "cycles")
            paper_scene(args.percentage)
            bpy.ops.caustic.apply_preset(preset='PAPER_10_5')
            paper, paper_seconds = render_addon(addon, energy=1.0)
            paper_shown = shown(metered(paper), folder, "paper")
        panels = {
            "caustics": (f"the add-on, default settings: {ours_seconds:.1f} s", ours, ours_shown, ours_seconds),
            "cycles": (f"Cycles in the same time: {cycles_seconds:.1f} s, {cycles_samples} samples", cycles,
                       cycles_shown, cycles_seconds),
            "paper": (f"the paper's scene and settings: {paper_seconds:.1f} s", paper, paper_shown, paper_seconds)}
        for key, (_, linear, _, _) in panels.items():
            save_exr(linear, args.out / f"demo_{key}.exr")
        labelled = figure([(title, image) for title, _, image, _ in panels.values()], args.out / "demo.png")
        summary = dict(kernels=dict(count=kernels, seconds=round(compile_seconds, 2)),
                       panels={key: dict(title=title, seconds=round(seconds, 3))
                               for key, (title, _, _, seconds) in panels.items()},
                       cycles_samples=cycles_samples, pixels=list(ours.shape[1::-1]),
                       blender=bpy.app.version_string)
        (args.out / "demo.json").write_text(json.dumps(summary, indent=2) + "\n")
        for title, _, _, _ in panels.values():
            print(f"  {title}")
        print(f"wrote {args.out / 'demo.png'}" if labelled else "matplotlib is missing: no demo.png")
    finally:
        if registered:
            addon.unregister()


if __name__ == "__main__":
    try:
        main()
    except Exception:
        traceback.print_exc()
        sys.exit(1)
