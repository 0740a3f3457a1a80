"""Live caustics while a user drags the caster: the gallery's scenes
(benchmarks/gallery.py) built in Blender, each with its world (the dim
grey one Blender gives every new scene), Live on, and the caster (the
water: its height field moved sideways) dragged through 60 positions along
an arc, as a mouse moves it, one position every 1/30 s; the ball lens
lit by the gallery's sunny sky alone, a 2048 x 1024 HDRI in an Environment
Texture, as product shots are; and the ball lens in a black world, which
lights nothing and costs nothing.

    .venv/bin/python benchmarks/live.py [--positions 60]

Blender's event loop is played by hand, as the bpy module runs none: at
each step the caster moves, the depsgraph updates (Live's handler), Live's
timer runs, and the depsgraph updates again. Recorded per scene:

- latency: seconds from a change to the images that show it (median, p95);
- updates a second: previews shown over the drag's length;
- the main thread's milliseconds per update: the scene read and the
  images' write;
- the engine's milliseconds per preview (its render: the BVH, the pass
  from the lamps and the maps), which the machine's load moves less than
  the updates a second;
- the engine's milliseconds per preview for the BVH and the bodies'
  analysis (a caster that only moved keeps both: tracing/prototypes.py),
  over the previews that traced (one whose maps were kept builds none);
- the refine's delay: seconds from the last change to the full-quality
  images;
- the preview's error: relative L2 of the last preview's map against the
  refined map at the same position, the refined map averaged down to the
  preview's cells;
- the process's resident memory over the drag: its growth at the peak and
  at the end.

Then the ball lens plays 48 frames at 24 fps with Live on, twice round,
its ball keyframed along the arc, and again held still: frames shown a
second in each loop, and how many updates found their maps kept (a still
scene's frames are equal; in the second loop a moving ball's frames are
seen again).

Writes benchmarks/results/live.json.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "addon"))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

import blender_scenes  # noqa: E402
import conftest  # noqa: E402
from benchmarks import gallery, record  # noqa: E402
from caustic_addon import Dielectric, Diffuse, PointLight, Reflector, SunLight, World  # noqa: E402

SCENES = {"ball lens": gallery.ball_lens, "mirror ring": gallery.mirror_ring, "gem": gallery.dispersive_gem,
          "wavy pool": gallery.wavy_water, "ball lens under an HDRI": gallery.sunny_sky,
          "ball lens in a black world": lambda: replace(gallery.ball_lens(), world=World())}
# The HDRI's size: the add-on bakes a world 2048 pixels wide.
HDRI_WIDTH = 2048
STEP_S = 1 / 30
FPS = 24
ARC_M = 0.3


def material(name: str, kind: str, **inputs):
    mat = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    shader = nodes.new(kind)
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    mat.node_tree.links.new(shader.outputs[0], nodes["Material Output"].inputs["Surface"])
    return mat


def add_object(obj):
    """The engine object `obj` (world space) as a Blender mesh object."""
    mesh = bpy.data.meshes.new(obj.name)
    vertices, triangles = obj.mesh.vertices, obj.mesh.triangles
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
    mesh.loops.add(triangles.size)
    mesh.loops.foreach_set("vertex_index", triangles.astype(np.int32).ravel())
    mesh.polygons.add(len(triangles))
    mesh.polygons.foreach_set("loop_start", np.arange(0, triangles.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(triangles), 3, dtype=np.int32))
    mesh.update()
    if obj.mesh.corner_normals is not None:
        mesh.shade_smooth()
    m = obj.material
    if isinstance(m, Dielectric):
        mesh.materials.append(material(obj.name, 'ShaderNodeBsdfGlass', IOR=float(m.ior), Roughness=0.0))
    elif isinstance(m, Reflector):
        mesh.materials.append(material(obj.name, 'ShaderNodeBsdfGlossy', Roughness=0.0,
                                       Color=(*np.broadcast_to(m.color, 3).tolist(), 1.0)))
    else:
        mesh.materials.append(material(obj.name, 'ShaderNodeBsdfDiffuse',
                                       Color=(*np.broadcast_to(m.albedo, 3).tolist(), 1.0)))
    ob = bpy.data.objects.new(obj.name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    if isinstance(m, Dielectric) and math.isfinite(m.abbe):
        ob.caustic.abbe = float(m.abbe)
    return ob


def add_light(light):
    if isinstance(light, PointLight):
        data = bpy.data.lights.new("Lamp", 'POINT')
        data.energy, data.shadow_soft_size = float(light.power), 0.0
        ob = bpy.data.objects.new("Lamp", data)
        ob.location = np.asarray(light.position).tolist()
    elif isinstance(light, SunLight):
        data = bpy.data.lights.new("Sun", 'SUN')
        data.energy, data.angle = float(light.strength), 0.0
        ob = bpy.data.objects.new("Sun", data)
        down = np.asarray(light.direction, dtype=float)
        ob.rotation_mode = 'QUATERNION'
        ob.rotation_quaternion = Vector((-down).tolist()).to_track_quat('Z', 'Y')
    else:
        raise TypeError(type(light).__name__)
    bpy.context.scene.collection.objects.link(ob)


def add_world(world: World, folder: Path) -> None:
    """`world` as the scene's: its colour in the Background node, or its
    environment saved to an EXR in `folder`, in an Environment Texture."""
    _, tree, background = blender_scenes.world_nodes()
    if world.environment is None:
        background.inputs['Color'].default_value = (*world.color.tolist(), 1.0)
        return
    h, w = world.environment.shape[:2]
    image = bpy.data.images.new("Sky", w, h, float_buffer=True)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = world.environment[::-1] * world.color
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw, image.file_format = str(folder / "sky.exr"), 'OPEN_EXR'
    image.save()
    texture = tree.nodes.new('ShaderNodeTexEnvironment')
    texture.image = bpy.data.images.load(str(folder / "sky.exr"))
    tree.links.new(texture.outputs['Color'], background.inputs['Color'])


def build(make, folder: Path) -> object:
    """The gallery scene `make()` in a fresh file, a sky's image HDRI_WIDTH
    wide (saved in `folder`); returns its caster."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = make()
    objects = [add_object(obj) for obj in scene.objects]
    for light in scene.lights:
        add_light(light)
    world = scene.world
    if world.environment is not None:
        world = World(world.color, gallery.sky_with_sun(HDRI_WIDTH))
    add_world(world, folder)
    return next(ob for ob, obj in zip(objects, scene.objects) if not isinstance(obj.material, Diffuse))


def step(session_module) -> None:
    bpy.context.view_layer.update()
    session_module.tick()
    bpy.context.view_layer.update()


def floor_map(name: str) -> np.ndarray:
    image = bpy.data.images["Caustic Map " + name]
    w, h = image.size
    rgba = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(rgba)
    return rgba.reshape(h, w, 4)[..., :3].astype(np.float64)


def preview_error(preview: np.ndarray, full: np.ndarray) -> float:
    """Relative L2 of `preview` against `full` averaged down to its cells."""
    fy, fx = full.shape[0] // preview.shape[0], full.shape[1] // preview.shape[1]
    h, w = preview.shape[0] * fy, preview.shape[1] * fx
    coarse = full[:h, :w].reshape(preview.shape[0], fy, preview.shape[1], fx, 3).mean(axis=(1, 3))
    return float(np.linalg.norm(preview - coarse) / np.linalg.norm(coarse))


def resident_mb() -> float:
    """This process's resident memory, MB."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def live_on(session_module):
    """Live on, refined once; its session, with no figures yet."""
    bpy.context.view_layer.update()
    assert bpy.ops.caustic.toggle_live() == {'FINISHED'}
    while session_module.SESSION.schedule.shown != "refine":
        step(session_module)
        time.sleep(0.005)
    session = session_module.SESSION
    session.updates.clear()
    return session


def drag(session_module, caster, positions: int) -> dict:
    """Drag `caster` along the arc, then let Live refine."""
    receiver = next(o.name for o in bpy.data.objects if o.type == 'MESH' and o is not caster)
    session = live_on(session_module)
    resident = [resident_mb()]
    start = time.perf_counter()
    for k in range(positions):
        angle = 2 * math.pi * k / positions
        caster.location = (ARC_M * math.sin(angle), ARC_M * (1 - math.cos(angle)) / 2, 0.0)
        last_change = time.perf_counter()
        due = start + (k + 1) * STEP_S
        while True:
            step(session_module)
            if time.perf_counter() >= due:
                break
            time.sleep(0.002)
        resident.append(resident_mb())
    dragged = time.perf_counter() - start
    # the last preview shown (a refine may start meanwhile: a slow preview outlasts the quiet it waits for)
    while session.schedule.pending or (session.schedule.job is not None and session.schedule.kind == "preview"):
        step(session_module)
        time.sleep(0.002)
    previews = [u for u in session.updates if u.kind == "preview"]
    preview = floor_map(receiver)
    while session.schedule.shown != "refine":
        step(session_module)
        time.sleep(0.005)
    refined_after = time.perf_counter() - last_change
    refine = [u for u in session.updates if u.kind == "refine"][-1]
    latency = np.array([u.latency for u in previews])
    result = dict(
        triangles=sum(len(o.data.polygons) for o in bpy.data.objects if o.type == 'MESH'),
        drag_s=dragged, previews=len(previews), updates_per_s=len(previews) / dragged,
        latency_median_s=float(np.median(latency)), latency_p95_s=float(np.percentile(latency, 95)),
        main_thread_ms_median=float(np.median([u.main_thread for u in previews]) * 1000),
        engine_ms_median=float(np.median([sum(u.stages.values()) for u in previews if "bvh" in u.stages]) * 1000),
        bvh_ms_median=float(np.median([u.stages["bvh"] for u in previews if "bvh" in u.stages]) * 1000),
        refine_main_thread_ms=refine.main_thread * 1000, refined_after_s=refined_after,
        preview_error=preview_error(preview, floor_map(receiver)),
        resident_growth_mb=max(resident) - resident[0], resident_last_mb=resident[-1] - resident[0])
    assert bpy.ops.caustic.toggle_live() == {'FINISHED'}
    return result


def playback(session_module, caster, frames: int, moving: bool, loops: int = 2) -> dict:
    """Play `frames` frames at FPS with Live on, `loops` times round as
    Blender's playback wraps, the caster keyframed along the arc if
    `moving`, else still: for each loop, the frames shown a second and how
    many updates found their maps kept (a still caster's frames are equal;
    a moving one's are seen again in the next loop)."""
    scene = bpy.context.scene
    if moving:
        for frame in (1, frames):
            caster.location = (ARC_M * (frame - 1) / (frames - 1), 0.0, 0.0)
            caster.keyframe_insert("location", frame=frame)
    scene.frame_start, scene.frame_end = 1, frames
    scene.frame_set(1)
    session = live_on(session_module)
    rounds = []
    for loop in range(loops):
        session.updates.clear()
        played_frames = list(range(1 if loop else 2, frames + 1))
        start = time.perf_counter()
        for k, frame in enumerate(played_frames):
            scene.frame_set(frame)
            due = start + (k + 1) / FPS
            while True:
                step(session_module)
                if time.perf_counter() >= due:
                    break
                time.sleep(0.002)
        played = time.perf_counter() - start
        previews = [u for u in session.updates if u.kind == "preview"]
        rounds.append(dict(frames=len(played_frames), played_s=played, shown_per_s=len(previews) / played,
                           maps_kept=sum(u.maps_cached for u in previews), shown=len(previews)))
    assert bpy.ops.caustic.toggle_live() == {'FINISHED'}
    return dict(loops=rounds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--positions", type=int, default=60)
    args = parser.parse_args()
    addon = conftest.registered_addon()
    figures = {}
    with tempfile.TemporaryDirectory(prefix="caustic-live-") as folder:
        for name, make in SCENES.items():
            figures[name] = drag(addon.live.session, build(make, Path(folder)), args.positions)
            print(name, {k: round(v, 4) if isinstance(v, float) else v for k, v in figures[name].items()},
                  flush=True)
        played = {kind: playback(addon.live.session, build(SCENES["ball lens"], Path(folder)), 48,
                                 kind == "moving") for kind in ("moving", "still")}
    print("playback", played, flush=True)
    record.write("live", dict(positions=args.positions, step_s=STEP_S, scenes=figures, fps=FPS, playback=played))
    addon.unregister()


if __name__ == "__main__":
    main()
