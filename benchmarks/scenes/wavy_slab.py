"""Sunlight through a slab of rippled water (three cosine waves on
shapes.wavy_slab's 12.5 mm vertices): the network of lines on a pool's floor.

- `pool()`: the gallery's water, 2.4 m across, seen from above at 240x180
  (beams_at_scale.py);
- `under_water()`: the same waves cut down to SIZE, seen from under the
  water looking straight down at the floor (mitsuba_folds.py; its image is
  traced independently by references/water_reference.py).
"""

from __future__ import annotations

import math

from benchmarks.references.water_reference import BOTTOM, DEPTH, EYE_HEIGHT, PIXX, PIXY
from caustic_addon import Camera, Dielectric, Diffuse, Object, Scene, SunLight, shapes

# (amplitude m, wavelength m, direction rad) of each wave
WAVES = ((0.012, 0.45, 0.3), (0.009, 0.31, 1.4), (0.006, 0.23, 2.5))
IOR = 1.33
# under_water's cut: 1 m of water on the pool's 12.5 mm vertices
SIZE = 1.0
CELLS = round(SIZE / 0.0125)


def pool() -> Scene:
    """The gallery's sunlight through rippled water, seen from above at 240x180."""
    water = shapes.wavy_slab(2.4, 0.25, WAVES, 192, (0.0, 0.0, 0.35))
    return Scene(objects=[Object("Pool floor", shapes.plane(4.0), Diffuse(albedo=1.0)),
                          Object("Water", water, Dielectric(IOR))],
                 lights=[SunLight((0.15, 0.1, -1.0), 4.0)],
                 camera=Camera.look_at((0.0, -1.6, 2.2), (0.0, 0.15, 0.0), pixx=240, pixy=180,
                                       fov=math.radians(40.0)))


def under_water() -> Scene:
    """pool()'s water cut down to SIZE (the same waves on the same
    vertices, so the same caustic away from its rim; a directional
    emitter's particles cover the scene's bounding disc, and at 2.4 m 97%
    of them missed the view), seen from under the water: a camera 0.05 m
    below its flat bottom (z = 0.35) looking straight down at the floor, 90
    degrees across 240x180 (0.6 m by 0.45 m of floor)."""
    whole = pool()
    water = shapes.wavy_slab(SIZE, DEPTH, WAVES, CELLS, (0.0, 0.0, BOTTOM))
    objects = [o if o.name != "Water" else Object("Water", water, o.material) for o in whole.objects]
    camera = Camera.look_at((0.0, 0.0, EYE_HEIGHT), (0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), pixx=PIXX, pixy=PIXY,
                            fov=math.radians(90.0))
    return Scene(objects=objects, lights=whole.lights, camera=camera)
