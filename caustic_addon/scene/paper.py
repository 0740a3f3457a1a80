"""The paper's scene (section 4), the one that the demo, the command line's
example (examples/paper.toml), the add-on's caustic.add_paper_scene and the
benchmarks all build: a clear object of base SHAPES over a diffuse floor
facing +z at z = 0, under one point lamp above, slightly to the side and
behind, so that shadows and caustics fall toward the paper's camera, which
looks down from in front. Lengths in metres:

    round    a sphere, radius 0.5 (the paper's "round base": sphere or droplet)
    flat     a cylinder, radius 0.5, 0.8 tall (a flat-bottomed glass)
    pointed  a cone, radius 0.5, 1.0 tall, point down (a gem's pavilion)
"""

from __future__ import annotations

from .camera import Camera
from .geometry import Mesh
from .lights import PointLight
from .materials import Dielectric, Diffuse
from .scene import Object, Scene
from .shapes import cone, cylinder, plane, uv_sphere

SHAPES = ("round", "flat", "pointed")
# The paper's indices of refraction: water, cubic zirconia, diamond.
INDICES = {"water": 1.33, "cubic zirconia": 1.9, "diamond": 2.41}
# The paper's lamp rays, lamp energy (10 makes LAMP_POWER the paper's 100 W)
# and map scale (mm), and its image.
LAMP_RAYS = 40_000
ENERGY = 10.0
MAP_SCALE = 5.0
PIXELS = (640, 480)
RADIUS = 0.5
CYLINDER_HEIGHT = 0.8
CONE_HEIGHT = 1.0
# m between the floor and the object's lowest point at rest: keeps the glass off the plane.
GAP = 1e-3
# m: the height of the paper's raised position
RAISED = 1.0
# m: wide enough to catch the fan of light a raised cone throws
FLOOR_SIZE = 16.0
FLOOR_ALBEDO = 0.8
LAMP_POSITION = (0.8, 0.5, 4.0)
# W: the paper's lamp energy 10 makes it 100 W.
LAMP_POWER = 10.0
EYE = (0.0, -4.0, 6.5)
TARGET = (0.0, 0.0, 0.3)
# degrees across the image's width
FOV = 40.0


def glass(shape: str, height: float = 0.0) -> Mesh:
    """The paper's object of base `shape` (one of SHAPES), centred on
    the z axis, its lowest point GAP + `height` m above z = 0."""
    bottom = GAP + height
    if shape == "round":
        return uv_sphere(RADIUS, (0.0, 0.0, bottom + RADIUS), 128, 64)
    if shape == "flat":
        return cylinder(RADIUS, CYLINDER_HEIGHT, (0.0, 0.0, bottom))
    if shape == "pointed":
        return cone(RADIUS, CONE_HEIGHT, (0.0, 0.0, bottom))
    raise ValueError(f"shape must be one of {SHAPES}, got {shape!r}")


def camera(pixx: int = PIXELS[0], pixy: int = PIXELS[1]) -> Camera:
    """The paper's pinhole: FOV degrees across pixx x pixy pixels, screen S = 1."""
    return Camera.from_paper(FOV, pixx, pixy, 1.0, EYE, TARGET)


def scene(shape: str = "round", ior: float = INDICES["water"], height: float = 0.0,
          pixels: tuple[int, int] = PIXELS, floor: float = FLOOR_SIZE) -> Scene:
    """Clear glass of base `shape` and index `ior` at `height` m over a
    `floor` m square of albedo FLOOR_ALBEDO, lit by a LAMP_POWER W point lamp."""
    return Scene(
        objects=[Object("Floor", plane(floor), Diffuse(albedo=FLOOR_ALBEDO)),
                 Object("Glass", glass(shape, height), Dielectric(ior))],
        lights=[PointLight(LAMP_POSITION, LAMP_POWER, name="Lamp")],
        camera=camera(*pixels),
    )
