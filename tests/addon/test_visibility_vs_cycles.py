"""Objects' ray visibility and holdouts, rendered by the add-on and by
Cycles with no diffuse bounces (direct light only, so Cycles has no
caustics either): an object hidden from camera rays still casts its shadow
and shows in a mirror; one hidden from shadow rays casts none; an object
hidden from glossy rays is missing from the mirror; a holdout cuts its
pixels out (colour and alpha 0) but shows in the mirror; a collection set
to Indirect Only hides its objects from camera rays."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

PIXELS = 48
BLOCK = 4


def cube(name, location, size=0.5):
    bpy.ops.mesh.primitive_cube_add(size=size, location=location)
    ob = bpy.context.object
    ob.name = name
    ob.data.materials.append(scenes.diffuse_material(f"{name} paint", (0.7, 0.25, 0.15)))
    return ob


def ours_and_cycles(tmp_path, specular_bounces=0):
    """(ours, Cycles): (h, w, 4) RGBA; ours is the direct light, the
    caustic-free light Cycles renders with no diffuse bounces, and alpha."""
    bpy.context.scene.caustic.spp = 16
    assert bpy.ops.caustic.render() == {'FINISHED'}
    image = scenes.pixels_of("Caustic Render").astype(np.float64)
    return image, scenes.cycles_render(str(tmp_path), samples=64, specular_bounces=specular_bounces)


def blocks(image):
    """Means over BLOCK x BLOCK pixels, which leave out Cycles' noise along edges."""
    h, w = image.shape[:2]
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, -1).mean(axis=(1, 3))


def test_camera_and_shadow_visibility_holdout_and_indirect_only_on_a_floor(tmp_path):
    scenes.add_plane(20.0, scenes.diffuse_material())
    unseen = cube("Unseen", (-0.75, 0.75, 0.25))
    unseen.visible_camera = False
    cube("Shadowless", (0.75, 0.75, 0.25)).visible_shadow = False
    cube("Cutout", (-0.75, -0.75, 0.25)).is_holdout = True
    indirect = bpy.data.collections.new("Indirect")
    bpy.context.scene.collection.children.link(indirect)
    sideline = cube("Sideline", (0.75, -0.75, 0.25))
    indirect.objects.link(sideline)
    bpy.context.scene.collection.objects.unlink(sideline)
    bpy.context.view_layer.layer_collection.children["Indirect"].indirect_only = True
    camera = scenes.add_camera((0.0, 0.0, 5.0))
    camera.data.type, camera.data.ortho_scale, camera.rotation_euler = 'ORTHO', 3.0, (0.0, 0.0, 0.0)
    scenes.add_point_light((0.3, 0.2, 2.5), 300.0)
    scenes.set_resolution(PIXELS, PIXELS)
    bpy.context.scene.caustic.lamp_rays = 1000
    ours, theirs = ours_and_cycles(tmp_path)
    # The holdout's pixels: alpha and colour 0 in both.
    cut = theirs[..., 3] < 0.5
    assert 60 < cut.sum() < 200
    assert np.abs(ours[..., 3] - theirs[..., 3]).mean() < 0.01
    assert ours[cut, :3].max() < 0.05 * ours[..., :3].max()
    # The rest, block by block, against the unshadowed floor's level.
    level = theirs[..., :3].max()
    difference = np.abs(blocks(ours) - blocks(theirs))[..., :3] / level
    print(f"blocks: largest difference {difference.max():.3f}, mean {difference.mean():.4f} of the floor's peak")
    assert difference.max() < 0.03 and difference.mean() < 0.004


def mirror_scene():
    """A mirror tilted 45 degrees under an orthographic camera looking
    straight down, so the camera sees, in it, what lies toward +x: three
    cubes side by side at x = 3.5, lit by a point lamp; a black world."""
    bpy.ops.mesh.primitive_plane_add(size=4.0, rotation=(0.0, math.radians(45.0), 0.0))
    bpy.context.object.name = "Mirror"
    bpy.context.object.data.materials.append(scenes.glossy_material())
    shown = {}
    for name, y in (("Unseen", -1.0), ("Unreflected", 0.0), ("Cutout", 1.0)):
        shown[name] = cube(name, (3.5, y, 0.0), size=0.9)
    shown["Unseen"].visible_camera = False
    shown["Unreflected"].visible_glossy = False
    shown["Cutout"].is_holdout = True
    camera = scenes.add_camera((0.0, 0.0, 5.0))
    camera.data.type, camera.data.ortho_scale, camera.rotation_euler = 'ORTHO', 2.4, (0.0, 0.0, 0.0)
    scenes.add_point_light((2.0, 0.0, 2.0), 300.0)
    scenes.set_resolution(PIXELS, PIXELS)
    bpy.context.scene.caustic.lamp_rays = 1000
    return shown


def test_a_mirror_shows_what_camera_rays_skip_and_holdouts_but_not_what_glossy_rays_skip(addon, tmp_path):
    mirror_scene()
    read = addon.export.read_scene(bpy.context)
    result = addon.caustic_addon.render(read.scene, addon.export.render_settings(bpy.context.scene.caustic, spp=16))
    ours = result.passes["direct"][..., :3].astype(np.float64)
    theirs = scenes.cycles_render(str(tmp_path), samples=64, specular_bounces=1)
    assert np.all(result.image[..., 3] == 1.0) and np.all(theirs[..., 3] == 1.0)
    # Image rows run along y: the unseen cube's reflection at the bottom, the holdout's at the top.
    columns = slice(PIXELS // 2 - 6, PIXELS // 2 + 6)
    thirds = [slice(2, PIXELS // 3 - 2), slice(PIXELS // 3 + 2, 2 * PIXELS // 3 - 2), slice(2 * PIXELS // 3 + 2, -2)]
    mine = [ours[rows, columns].mean() for rows in thirds]
    cycles = [theirs[rows, columns, :3].mean() for rows in thirds]
    print(f"ours / Cycles, top to bottom (holdout, glossy-invisible, camera-invisible): {mine} / {cycles}")
    holdout, unreflected, unseen = zip(mine, cycles)
    assert unseen[0] == pytest.approx(unseen[1], rel=0.03) and unseen[0] > 0.1
    assert holdout[0] == pytest.approx(holdout[1], rel=0.03) and holdout[0] > 0.1
    assert unreflected[0] == unreflected[1] == 0.0
