"""What reading the scene as a render sees it costs (export/render_view.py):
Blender evaluates a scene at its render settings only for a render, so the
add-on renders the view layer with a render engine of its own that hands
the render depsgraph to the reader and draws nothing. Timed against reading
the viewport's depsgraph, which Blender keeps evaluated, with the same
reader (the add-on's way before issue 17):

    .venv/bin/python benchmarks/render_view.py [--repeats 5]

Scenes, each at 640x480 (and the paper's at 3840x2160, to show whether the
Render Result Blender makes for the empty render costs by its size):
- the paper's scene (caustic.add_paper_scene: a glass of water, a floor, a
  lamp, a camera);
- 200 separate glass balls of 8x4 faces over a floor;
- a ball under a Subdivision Surface at level 3 in both the viewport and
  the render (65,536 triangles), and the same at viewport 1 / render 3,
  where the render read evaluates the finer mesh the viewport never made.
Each figure is the best of `repeats` reads; "render setup" is the render
read with a reader that reads nothing (the engine switch, the render, the
Render Result's slot). Writes benchmarks/results/render_view.json.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from datetime import date
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))

import bpy  # noqa: E402

from speed import machine  # noqa: E402

PACKAGE = "caustics_source"


def load_addon():
    """The add-on from the source tree, registered (as tests/addon/conftest.py does)."""
    spec = importlib.util.spec_from_file_location(PACKAGE, REPO / "__init__.py", submodule_search_locations=[str(REPO)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[PACKAGE] = module
    spec.loader.exec_module(module)
    module.register()
    return module


def material(name: str, kind: str):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    output, shader = nodes.new('ShaderNodeOutputMaterial'), nodes.new(kind)
    mat.node_tree.links.new(shader.outputs[0], output.inputs['Surface'])
    return mat


def base_scene(width: int = 640, height: int = 480):
    """An empty file with a floor, a point lamp and a camera."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_plane_add(size=10.0)
    bpy.context.object.data.materials.append(material("Floor", 'ShaderNodeBsdfDiffuse'))
    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", 'POINT'))
    lamp.location = (0.0, 0.0, 5.0)
    bpy.context.scene.collection.objects.link(lamp)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location, camera.rotation_euler = (0.0, -8.0, 5.0), (1.0, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100


def paper_scene(width: int = 640, height: int = 480) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert bpy.ops.caustic.add_paper_scene() == {'FINISHED'}
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100


def many_balls() -> None:
    base_scene()
    glass = material("Glass", 'ShaderNodeBsdfGlass')
    for i in range(200):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=8, ring_count=4, radius=0.15,
                                             location=(0.4 * (i % 20) - 4.0, 0.4 * (i // 20) - 2.0, 0.5))
        bpy.context.object.data.materials.append(glass)


def subdivided_ball(viewport_levels: int) -> None:
    base_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0, location=(0.0, 0.0, 1.5))
    ball = bpy.context.object
    ball.data.materials.append(material("Glass", 'ShaderNodeBsdfGlass'))
    subdivide = ball.modifiers.new("Subdivide", 'SUBSURF')
    subdivide.levels, subdivide.render_levels = viewport_levels, 3


def best(call, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def measure(addon, build, repeats: int) -> dict:
    from caustics_source.export.render_view import read_as_render
    from caustics_source.export.scene import _read_objects

    build()
    context, scene = bpy.context, bpy.context.scene
    depsgraph = context.evaluated_depsgraph_get()
    render_read = addon.export.read_scene(context)
    viewport_read = _read_objects(scene, depsgraph, True)
    return {
        "triangles (render / viewport)": [sum(len(o.mesh.triangles) for o in r.scene.objects)
                                          for r in (render_read, viewport_read)],
        "render read s": best(lambda: addon.export.read_scene(context), repeats),
        "viewport read s": best(lambda: _read_objects(scene, context.evaluated_depsgraph_get(), True), repeats),
        "render setup s": best(lambda: read_as_render(scene, context.view_layer, lambda graph: None), repeats),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    addon = load_addon()
    scenes = {
        "paper's scene, 640x480": paper_scene,
        "paper's scene, 3840x2160": lambda: paper_scene(3840, 2160),
        "200 glass balls": many_balls,
        "Subdivision 3 / 3 (viewport / render)": lambda: subdivided_ball(3),
        "Subdivision 1 / 3 (viewport / render)": lambda: subdivided_ball(1),
    }
    rows = {name: measure(addon, build, args.repeats) for name, build in scenes.items()}
    print(f"{'scene':40s} {'triangles':>16s} {'render read':>12s} {'viewport':>9s} {'setup':>7s}")
    for name, row in rows.items():
        tris = "{:,} / {:,}".format(*row["triangles (render / viewport)"])
        print(f"{name:40s} {tris:>16s} {row['render read s']:11.3f}s {row['viewport read s']:8.3f}s "
              f"{row['render setup s']:6.3f}s")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "render_view.json").write_text(json.dumps(
        {"date": date.today().isoformat(), "machine": machine(), "blender": bpy.app.version_string,
         "repeats": args.repeats, "scenes": rows}, indent=2) + "\n")
    addon.unregister()


if __name__ == "__main__":
    main()
