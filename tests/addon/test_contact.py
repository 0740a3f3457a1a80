"""Issue 17's contact test through the add-on: a glass cylinder standing
exactly on a floor, as Blender's primitives put it there, renders its base's
caustic as cleanly as one lifted 1 mm."""

import bpy
import pytest

import blender_scenes as scenes

PIXELS = 48
# the base's middle, seen through the glass from straight above
BASE = (slice(16, 32), slice(16, 32))


def test_a_glass_standing_on_the_floor_is_as_clean_as_one_lifted_1_mm(addon):
    scenes.add_plane(8.0, scenes.diffuse_material())
    bpy.ops.mesh.primitive_cylinder_add(vertices=64, radius=0.5, depth=1.0, location=(0.0, 0.0, 0.5))
    glass = bpy.context.object
    glass.data.materials.append(scenes.glass_material())
    scenes.add_point_light((0.3, 0.2, 4.0), 1000.0)
    scenes.add_camera((0.0, 0.0, 6.0), target=(0.0, 0.0, 0.0), lens=100.0)
    scenes.set_resolution(PIXELS, PIXELS)
    props = bpy.context.scene.caustic
    props.lamp_rays = 40_000
    caustic = {}
    for lift in (0.0, 1e-3):
        glass.location.z = 0.5 + lift
        bpy.context.view_layer.update()
        read = addon.export.read_scene(bpy.context)
        base = read.scene.objects[[o.name for o in read.scene.objects].index(glass.name)].mesh.vertices[:, 2].min()
        assert base == (0.0 if lift == 0.0 else pytest.approx(lift, rel=1e-4))
        settings = addon.export.render_settings(props, spp=1)
        caustic[lift] = addon.caustic_addon.render(read.scene, settings).passes["caustic"][BASE][..., 0]
    standing, lifted = caustic[0.0], caustic[1e-3]
    print(f"pixel variance under the base: standing {standing.var():.4g}, lifted {lifted.var():.4g}; "
          f"means {standing.mean():.4g}, {lifted.mean():.4g}")
    assert standing.mean() > 0.0
    assert standing.var() <= 1.1 * lifted.var()
    assert abs(standing.mean() / lifted.mean() - 1.0) < 0.01
