"""Animated caustics in Blender: the speed of Render Caustic Animation on an
animated pool, and what each way of getting caustics into an EEVEE or
Cycles render costs a frame, against Cycles alone.

    .venv/bin/python benchmarks/animation.py [--frames 24] [--cycles-frames 3]

The pool: an 8 m floor (albedo 0.8) under a 6 m x 6 m body of water
(IOR 1.33, a 128 x 128 grid with an animated Wave modifier and Solidify
down to the floor, so the mesh is closed), lit by a sun 20 degrees off the
vertical, seen at 1280 x 720 with the add-on's default settings.

1. Render Caustic Animation over `frames` frames, in one run: seconds per
   frame (each frame's waves differ, so every frame traces its maps), wall
   and CPU (all threads; other jobs on a shared machine add wall time, not
   CPU), the total, and the load average before and after.
2. Caustics in Cycles, per frame, at 25% resolution and 16 samples: Cycles
   alone (no caustics of ours); Bake Caustic Animation then Cycles
   (a bake step, then the render); Bake While Rendering (the render
   handlers bake each frame, no step; command-line renders only); Render
   Animation with Caustics and Render Image with Caustics (the Render
   menu's entries: the bake, then Blender's render, in one click; they
   work in the interface too). All trace the same maps. Wall seconds, and
   the process's CPU seconds beside them (2 cores: up to twice the wall).

Writes benchmarks/results/animation.json (with --frames 0, part 1's
figures are kept from the last run).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "packaging")]  # the repository root, and its source_tree

from source_tree import blender_user_folders, import_addon  # noqa: E402

blender_user_folders()

import bpy  # noqa: E402

from benchmarks import record  # noqa: E402


def register_addon() -> None:
    module = import_addon()
    module.register()
    # the frames are timed with the kernels compiled, as a user's are after the first start
    module.jobs.kernels.wait()


def node_material(name: str, kind: str, **inputs):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    shader, output = nodes.new(kind), nodes.new('ShaderNodeOutputMaterial')
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    material.node_tree.links.new(shader.outputs[0], output.inputs['Surface'])
    return material


def pool(folder: Path) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=8.0)
    bpy.context.object.data.materials.append(node_material("Pool", 'ShaderNodeBsdfDiffuse',
                                                           Color=(0.8, 0.8, 0.8, 1.0)))
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=128, y_subdivisions=128, size=6.0, location=(0, 0, 1.0))
    water = bpy.context.object
    water.name = "Water"
    water.data.shade_smooth()
    wave = water.modifiers.new("Waves", 'WAVE')
    wave.height, wave.width, wave.speed, wave.narrowness = 0.03, 0.8, 0.04, 1.5
    solid = water.modifiers.new("Depth", 'SOLIDIFY')
    solid.thickness, solid.offset = 0.95, -1.0
    water.data.materials.append(node_material("Water", 'ShaderNodeBsdfGlass', IOR=1.33, Roughness=0.0))
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.energy, sun.data.angle = 3.0, math.radians(0.5)
    sun.rotation_euler = (math.radians(20.0), 0.0, math.radians(30.0))
    scene.collection.objects.link(sun)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (0.0, -5.5, 4.0)
    camera.rotation_euler = (math.radians(52.0), 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 1280, 720, 100
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '16'
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "pool.blend"))


def caustic_animation(frames: int) -> dict:
    """One Render Caustic Animation over frames 1 to `frames`, as an artist
    runs it; a frame's time runs from the operator setting that frame (a
    frame_change_post handler notes the clocks) to it setting the next, the
    first from the call, the last to the call's return."""
    marks = {}

    def mark(scene, *_):
        marks.setdefault(scene.frame_current, (time.perf_counter(), time.process_time()))

    load = [os.getloadavg()[0]]
    bpy.app.handlers.frame_change_post.append(mark)
    try:
        start = time.perf_counter(), time.process_time()
        assert bpy.ops.caustic.render_animation(filepath="//frames/pool_####", frame_start=1,
                                                frame_end=frames) == {'FINISHED'}
        end = time.perf_counter(), time.process_time()
    finally:
        bpy.app.handlers.frame_change_post.remove(mark)
    load.append(os.getloadavg()[0])
    clocks = [start] + [marks[frame] for frame in range(2, frames + 1)] + [end]
    seconds = [b[0] - a[0] for a, b in zip(clocks, clocks[1:])]
    cpu = [b[1] - a[1] for a, b in zip(clocks, clocks[1:])]
    for frame, (wall, process) in enumerate(zip(seconds, cpu), start=1):
        print(f"frame {frame}: {wall:.2f} s, {process:.2f} CPU s", flush=True)
    return dict(frames=frames, seconds_per_frame=seconds, cpu_seconds_per_frame=cpu, mean=sum(seconds) / frames,
                max=max(seconds), total=sum(seconds), cpu_total=sum(cpu), load_average=load,
                resolution=[1280, 720])


def per_frame(frames: int, run) -> dict:
    """Wall and CPU seconds a frame of `run()`, which traces every map afresh (none kept from an earlier run)."""
    import_addon().jobs.MAP_CACHE.clear()
    clock, cpu = time.perf_counter(), time.process_time()
    run()
    return dict(wall=(time.perf_counter() - clock) / frames, cpu=(time.process_time() - cpu) / frames)


def cycles_animation(folder: Path, name: str, frames: int, render=None) -> dict:
    scene = bpy.context.scene
    scene.render.filepath = str(folder / name / "f_####")
    scene.frame_start, scene.frame_end = 1, frames
    return per_frame(frames, render or (lambda: bpy.ops.render.render(animation=True)))


def final_frame_options(folder: Path, frames: int) -> dict:
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = 'CPU', 16, False
    scene.render.resolution_percentage = 25
    plain = cycles_animation(folder, "plain", frames)
    bake = per_frame(frames, lambda: bpy.ops.caustic.bake_animation(frame_start=1, frame_end=frames))
    baked = cycles_animation(folder, "baked", frames)
    bpy.ops.caustic.unbake()
    scene.caustic.use_bake_on_render = True
    live = cycles_animation(folder, "live", frames)
    bpy.ops.caustic.unbake()
    scene.caustic.use_bake_on_render = False
    menu = cycles_animation(folder, "menu", frames,
                            lambda: bpy.ops.caustic.render_animation_with_caustics('INVOKE_DEFAULT'))
    bpy.ops.caustic.unbake()
    scene.frame_set(2)
    still = per_frame(1, lambda: bpy.ops.caustic.render_image_with_caustics('INVOKE_DEFAULT'))
    return dict(frames=frames, resolution_percentage=25, cycles_samples=16, seconds_per_frame={
        "Cycles alone": plain, "Bake Caustic Animation (the step)": bake,
        "Cycles of the baked sequence": baked, "Bake While Rendering (bake and Cycles)": live,
        "Render Animation with Caustics (bake and Cycles)": menu,
        "Render Image with Caustics (one frame: bake and Cycles)": still})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=24, help="frames of part 1 (0 skips it)")
    parser.add_argument("--cycles-frames", type=int, default=3)
    args = parser.parse_args()
    register_addon()
    with tempfile.TemporaryDirectory(prefix="caustic-animation-") as folder:
        pool(Path(folder))
        speed = caustic_animation(args.frames) if args.frames else None
        options = final_frame_options(Path(folder), args.cycles_frames)
    if speed is None:
        speed = record.read("animation").get("pool")
    record.write("animation", dict(pool=speed, final_frame=options))
    if speed is not None:
        print(f"pool 1280x720: {speed['mean']:.2f} s a frame on average, at most {speed['max']:.2f} s, "
              f"{speed['total']:.1f} s for {speed['frames']} frames ({speed['cpu_total']:.1f} CPU s; load "
              f"{speed['load_average'][0]:.1f} then {speed['load_average'][1]:.1f})")
    for name, seconds in options["seconds_per_frame"].items():
        print(f"{name}: {seconds['wall']:.2f} s a frame (CPU {seconds['cpu']:.2f} s)")


if __name__ == "__main__":
    main()
