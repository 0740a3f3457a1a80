"""Write the paper's three objects (caustic_addon.paper.glass) as OBJ files
next to this script: round.obj (a sphere), flat.obj (a cylinder) and
pointed.obj (a cone, point down), each with its lowest point at the origin,
so that a scene file's object.position is where the object's bottom rests
(paper.toml puts it paper.GAP above the floor, as the paper's scene does).

    python examples/make_objects.py
"""

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from caustic_addon import Mesh, paper  # noqa: E402
from caustic_addon.cli.obj import write_obj  # noqa: E402

DESCRIPTIONS = {"round": "a sphere, radius 0.5 m, 128 segments x 64 rings",
                "flat": "a cylinder, radius 0.5 m, 0.8 m tall, 128 segments",
                "pointed": "a cone, point down, radius 0.5 m, 1 m tall, 128 segments"}


def resting_at_origin(mesh: Mesh) -> Mesh:
    """`mesh` moved down onto z = 0, without UVs (glass needs none)."""
    return Mesh(mesh.vertices - np.array([0.0, 0.0, mesh.vertices[:, 2].min()]), mesh.triangles,
                mesh.corner_normals)


if __name__ == "__main__":
    for shape in paper.SHAPES:
        path = HERE / f"{shape}.obj"
        mesh = resting_at_origin(paper.glass(shape))
        write_obj(path, mesh, f"The paper's {shape} object: {DESCRIPTIONS[shape]}; lowest point at the origin.\n"
                              "Written by examples/make_objects.py.")
        print(f"{path.name}: {len(mesh.triangles)} triangles, {path.stat().st_size // 1024} KB")
