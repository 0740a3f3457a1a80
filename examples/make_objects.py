"""Write the paper's three object shapes as OBJ files next to this script:
round.obj (a sphere), flat.obj (a cylinder) and pointed.obj (a cone, point
down), each 1 m across with its lowest point at the origin, so that a scene
file's object.position is where the object's bottom rests.

    python examples/make_objects.py
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from caustic_addon import shapes  # noqa: E402
from caustic_addon.cli.obj import write_obj# noqa: E402

OBJECTS = {
    "round": ("sphere, radius 0.5 m, 64 segments x 32 rings", shapes.uv_sphere(0.5, (0.0, 0.0, 0.5), 64, 32)),
    "flat": ("cylinder, radius 0.5 m, height 0.5 m, 128 segments", shapes.cylinder(0.5, 0.5, segments=128)),
    "pointed": ("cone, point down, radius 0.5 m, height 0.75 m, 128 segments",
                shapes.cone(0.5, 0.75, segments=128)),
}

if __name__ == "__main__":
    for name, (description, mesh) in OBJECTS.items():
        path = HERE / f"{name}.obj"
        write_obj(path, mesh, f"{description}; lowest point at the origin.\nWritten by examples/make_objects.py.")
        print(f"{path.name}: {len(mesh.triangles)} triangles, {path.stat().st_size // 1024} KB")
