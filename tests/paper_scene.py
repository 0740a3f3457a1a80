"""The paper's scene in Blender, rendered by the add-on into out/.

    blender -b --factory-startup --python tests/paper_scene.py [-- options]
    .venv/bin/python tests/paper_scene.py [options]

A round glass object (a sphere 10 cm across, IOR 1.33, its bottom 6 cm up)
on a 2 m diffuse plane under a 0.8 W point lamp 60 cm up, seen by a 40 degree
camera at 640x480: the scene of examples/paper.toml, with the paper's 40,000
lamp rays, lamp energy 10 and map scale 5 mm. With --compare the same view
is also rendered by Cycles (MNEE shadow caustics); the lamp energy of 10 is
then moved into the lamp (8 W, energy 1) so both renderers see the same
light, and a side-by-side image is written too.

Uses the installed extension if Blender has it, else the add-on in this
source tree (its engine needs embreex importable). Exits 1 on any failure.
"""

import argparse
import importlib.util
import math
import sys
import traceback
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

REPO = Path(__file__).resolve().parents[1]


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description="Render the paper's scene with the caustics add-on.")
    parser.add_argument("--out", type=Path, default=REPO / "out", help="output folder [out/]")
    parser.add_argument("--percentage", type=int, default=100, help="resolution percentage of 640x480 [100]")
    parser.add_argument("--preset", default="PAPER_10_5", help="caustic.apply_preset preset [PAPER_10_5]")
    parser.add_argument("--compare", action="store_true", help="also render with Cycles, side by side")
    parser.add_argument("--samples", type=int, default=128, help="Cycles samples for --compare [128]")
    return parser.parse_args(argv)


def enable_addon():
    """The add-on's module if this script had to register it, else None."""
    if hasattr(bpy.types, "CAUSTIC_OT_render"):
        return None
    spec = importlib.util.spec_from_file_location("caustics", REPO / "__init__.py",
                                                  submodule_search_locations=[str(REPO)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["caustics"] = module
    spec.loader.exec_module(module)
    module.register()
    return module


def material(name, kind, **inputs):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    shader = nodes.new(kind)
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    mat.node_tree.links.new(shader.outputs[0], nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    return mat


def build_scene(percentage):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    bpy.context.object.data.materials.append(material("Plane", 'ShaderNodeBsdfDiffuse',
                                                      Color=(0.8, 0.8, 0.8, 1.0)))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.05, location=(0.0, 0.0, 0.11))
    ball = bpy.context.object
    ball.name = "Round"
    ball.data.shade_smooth()
    ball.data.materials.append(material("Water", 'ShaderNodeBsdfGlass', IOR=1.33, Roughness=0.0))
    light = bpy.data.lights.new("Lamp", 'POINT')
    light.energy, light.shadow_soft_size = 0.8, 0.0
    lamp = bpy.data.objects.new("Lamp", light)
    lamp.location = (0.0, 0.0, 0.6)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.sensor_fit, camera.data.angle = 'HORIZONTAL', math.radians(40.0)
    camera.location = (0.0, -0.55, 0.4)
    camera.rotation_euler = (Vector((0.0, 0.0, 0.03)) - camera.location).to_track_quat('-Z', 'Y').to_euler()
    for ob in (lamp, camera):
        scene.collection.objects.link(ob)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    scene.render.resolution_percentage = percentage
    return scene


def save(image, scene, path: Path):
    """`image` as a linear float EXR, or as a PNG through the scene's view transform."""
    settings = scene.render.image_settings
    settings.file_format = 'OPEN_EXR' if path.suffix == ".exr" else 'PNG'
    if path.suffix == ".exr":
        settings.color_depth = '32'
    image.save_render(str(path), scene=scene)
    print(f"wrote {path}")


def side_by_side(left, right):
    """A new image with `left` and `right` (same size) next to each other."""
    w, h = left.size
    halves = []
    for image in (left, right):
        pixels = np.empty(w * h * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        halves.append(pixels.reshape(h, w, 4))
    both = bpy.data.images.new("Side by Side", 2 * w, h, alpha=True, float_buffer=True)
    both.pixels.foreach_set(np.concatenate(halves, axis=1).ravel())
    return both


def main():
    args = arguments()
    args.out.mkdir(parents=True, exist_ok=True)
    module = enable_addon()
    try:
        scene = build_scene(args.percentage)
        bpy.ops.caustic.apply_preset(preset=args.preset)
        if args.compare:
            bpy.data.lights["Lamp"].energy *= scene.caustic.energy
            scene.caustic.energy = 1.0
            scene.caustic.cycles_samples = args.samples
            bpy.ops.caustic.compare_cycles()
        else:
            bpy.ops.caustic.render()
        result = bpy.data.images["Caustic Render"]
        save(result, scene, args.out / "paper_caustics.exr")
        save(result, scene, args.out / "paper_caustics.png")
        props = scene.caustic
        print(f"caustic render: {props.last_seconds:.2f} s, {props.last_lamp_rays:,} lamp rays")
        if args.compare:
            save(bpy.data.images["Cycles Reference"], scene, args.out / "paper_cycles.png")
            save(side_by_side(result, bpy.data.images["Cycles Reference"]), scene,
                 args.out / "paper_side_by_side.png")
            print(f"Cycles: {props.cycles_seconds:.2f} s, relative L2 over the caustics "
                  f"{props.cycles_relative_l2:.3f}, PSNR {props.cycles_psnr:.1f} dB")
    finally:
        if module is not None:
            module.unregister()


if __name__ == "__main__":
    try:
        main()
    except Exception:
        traceback.print_exc()
        sys.exit(1)
