"""caustic.bake writes each receiver's illumination map into its material
through one node group; caustic.unbake takes exactly that out again."""

import math

import bpy
import numpy as np
import pytest

import blender_scenes as scenes
from snapshot import material_state, snapshot_file
from test_render import cycles_render
from test_textures_vs_cycles import random_image

def test_bake_adds_one_node_group_and_unbake_restores_the_material():
    parts = scenes.ball_lens_scene(32, 24, lamp_rays=100_000)
    floor_material = parts["floor"].active_material
    glass_before = material_state(parts["ball"].active_material)
    bpy.context.view_layer.update()
    before, floor_before = snapshot_file(), material_state(floor_material)

    assert bpy.ops.caustic.bake() == {'FINISHED'}

    nodes, _ = material_state(floor_material)
    added = set(nodes) - set(floor_before[0])
    assert len(added) == 1 and set(floor_before[0]) <= set(nodes)
    group_node = floor_material.node_tree.nodes[added.pop()]
    assert group_node.bl_idname == 'ShaderNodeGroup'
    assert set(bpy.data.node_groups.keys()) == {group_node.node_tree.name}
    output = floor_material.node_tree.get_output_node('CYCLES')
    assert output.inputs['Surface'].links[0].from_node == group_node
    assert group_node.inputs[0].links[0].from_node.bl_idname == 'ShaderNodeBsdfDiffuse'
    assert material_state(parts["ball"].active_material) == glass_before

    image = bpy.data.images["Caustic Map Floor"]
    assert image.is_float and image.packed_file is not None
    w, h = image.size
    irradiance = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(irradiance)
    # Irradiance the floor would get right under the lamp with no ball in the way.
    lamp = parts["lamp"]
    unshadowed = lamp.data.energy / (4.0 * math.pi) / lamp.location.z ** 2
    print(f"baked map {w}x{h}: max {irradiance.max():.4g} W/m^2, unshadowed {unshadowed:.4g} W/m^2")
    assert irradiance.reshape(h, w, 4)[..., :3].max() > 5.0 * unshadowed

    assert bpy.ops.caustic.unbake() == {'FINISHED'}
    assert material_state(floor_material) == floor_before
    assert snapshot_file() == before


def camera_rays_clear_sphere(rows, cols, centre, radius):
    """Whether the scene camera's rays through the centres of pixels
    rows x cols all pass outside the sphere."""
    scene = bpy.context.scene
    camera = scene.camera
    w, h = scene.render.resolution_x, scene.render.resolution_y
    top_right, _, bottom_left, _ = camera.data.view_frame(scene=scene)
    rotation = np.array(camera.matrix_world.to_3x3())
    eye = np.array(camera.matrix_world.translation)
    for r in rows:
        for c in cols:
            x = bottom_left.x + (c + 0.5) / w * (top_right.x - bottom_left.x)
            y = top_right.y - (r + 0.5) / h * (top_right.y - bottom_left.y)
            d = rotation @ np.array([x, y, top_right.z])
            d /= np.linalg.norm(d)
            offset = np.asarray(centre) - eye
            if np.linalg.norm(offset - np.dot(offset, d) * d) <= radius:
                return False
    return True


@pytest.mark.parametrize("floor_kind", ["flat", "bent", "principled"])
def test_baked_caustic_renders_like_the_caustic_pass(addon, tmp_path, floor_kind):
    """Cycles shows the baked material's emission (lamp and ball hidden)
    where the caustic render's caustic pass has the caustic, as bright. The
    lamp is off to the side so the caustic is not symmetric about the chart's
    axes, and the camera sees it clear of the ball. A bent floor (one corner
    raised) is not a plane: its map is charted by its UV map instead. A
    Principled floor's caustic is its diffuse base's, the share its specular
    layer leaves toward the eye (11% less here at Specular IOR Level 1)."""
    material = (scenes.principled_material(level=1.0) if floor_kind == "principled"
                else scenes.diffuse_material())
    floor = scenes.add_plane(6.0, material)
    if floor_kind == "bent":
        floor.data.vertices[0].co.z = 0.05
    ball = scenes.add_sphere(0.5, (0.0, 0.0, 0.75), scenes.glass_material())
    lamp = scenes.add_point_light((-1.5, 0.6, 3.0), 1000.0)
    scenes.add_camera((3.5, -2.5, 2.5), target=(0.5, -0.2, 0.0))
    scenes.set_resolution(64, 48)
    bpy.context.scene.caustic.lamp_rays, bpy.context.scene.caustic.density = 200_000, 'ADAPTIVE'
    read = addon.export.read_scene(bpy.context)
    settings = addon.export.render_settings(bpy.context.scene.caustic, spp=64)
    caustic = addon.caustic_addon.render(read.scene, settings).passes["caustic"]
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    chart_input = 'ShaderNodeUVMap' if floor_kind == "bent" else 'ShaderNodeNewGeometry'
    assert any(node.bl_idname == chart_input for node in bpy.data.node_groups[0].nodes)

    ball.hide_render = lamp.hide_render = True
    baked = cycles_render(str(tmp_path), samples=64)[..., :3]

    row, col = np.unravel_index(caustic[..., 0].argmax(), caustic.shape[:2])
    rows, cols = range(row - 3, row + 4), range(col - 3, col + 4)
    assert camera_rays_clear_sphere(rows, cols, ball.location, 0.5)
    peak = np.unravel_index(baked[..., 0].argmax(), baked.shape[:2])
    assert abs(peak[0] - row) <= 1 and abs(peak[1] - col) <= 1
    window = (slice(rows.start, rows.stop), slice(cols.start, cols.stop))
    core = (slice(row - 1, row + 2), slice(col - 1, col + 2))
    ratio = baked[window].sum() / caustic[window].sum()
    # Around the sub-pixel focus: the image's cells, interpolated, against exact look-ups.
    ratio_around = (baked[window].sum() - baked[core].sum()) / (caustic[window].sum() - caustic[core].sum())
    print(f"baked caustic in Cycles / caustic pass around the peak: 7x7 pixels {ratio:.3f}, "
          f"7x7 without the central 3x3 {ratio_around:.4f}")
    assert abs(ratio - 1.0) < 0.15
    assert abs(ratio_around - 1.0) < 0.03


def baked_map_size(scale_length, map_scale_text):
    """The baked map's (width, height) in cells of the ball-lens scene built
    in units of `scale_length` metres, with Map Scale typed as
    `map_scale_text` (Blender stores what is typed in scene units)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    parts = scenes.ball_lens_scene(16, 12, lamp_rays=5_000, segments=16, rings=8)
    scene = bpy.context.scene
    scene.unit_settings.scale_length = scale_length
    for ob in parts.values():
        ob.location *= 1.0 / scale_length
        ob.scale *= 1.0 / scale_length
    scene.caustic.use_auto_map_scale = False
    scene.caustic.map_scale = bpy.utils.units.to_value('METRIC', 'LENGTH', map_scale_text) / scale_length
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    return tuple(bpy.data.images["Caustic Map Floor"].size)


def test_map_scale_is_a_length_that_follows_the_unit_scale():
    in_metres = baked_map_size(1.0, "20 mm")
    # the 6 m floor in cells of 20 mm
    assert in_metres == (300, 300)
    assert baked_map_size(0.01, "20 mm") == in_metres
    assert baked_map_size(0.01, "2 cm") == in_metres


@pytest.mark.parametrize("floor_kind", ["diffuse", "principled", "textured"])
def test_a_baked_receiver_reads_as_before_the_bake(addon, floor_kind):
    """The bake's node group sits between the receiver's shader and its
    output: a Render or a second Bake after it still reads the shader's
    colour, texture and specular layer (it read a default grey before)."""
    material = (scenes.principled_material(level=1.0) if floor_kind == "principled"
                else scenes.diffuse_material("Floor", (0.7, 0.3, 0.2)))
    if floor_kind == "textured":
        tree = material.node_tree
        texture = tree.nodes.new('ShaderNodeTexImage')
        texture.image = random_image()
        tree.links.new(texture.outputs['Color'], tree.nodes["Diffuse BSDF"].inputs['Color'])
    scenes.add_plane(6.0, material)
    scenes.add_sphere(0.5, (0.0, 0.0, 0.75), scenes.glass_material(), segments=16, rings=8)
    scenes.add_point_light((-1.5, 0.6, 3.0), 1000.0)
    scenes.add_camera((3.5, -2.5, 2.5), target=(0.5, -0.2, 0.0))
    scenes.set_resolution(16, 12)
    bpy.context.scene.caustic.lamp_rays = 2000

    def floor():
        read = addon.export.read_scene(bpy.context)
        return next(o for o in read.scene.objects if o.name == "Floor").material, read.warnings

    before, _ = floor()
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    after, warnings = floor()
    assert np.allclose(after.albedo, before.albedo)
    assert (after.texture is None) == (before.texture is None) == (floor_kind != "textured")
    assert (after.specular is None) == (before.specular is None) == (floor_kind != "principled")
    assert not any("Floor" in w for w in warnings)
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    assert len([n for n in material.node_tree.nodes if n.bl_idname == 'ShaderNodeGroup']) == 1


def test_a_sphere_without_uvs_bakes_through_its_box_chart(addon, tmp_path):
    """A ball with no UV map, lit by a sun through a glass slab: the bake
    looks its box chart up from the position and true normal, and Cycles
    shows the baked caustic (slab and sun hidden) as the caustic pass has
    it, pixel by pixel, seams included; the mesh gets no UV map."""
    ball = scenes.add_sphere(0.5, (0.0, 0.0, 0.0), scenes.diffuse_material(), segments=96, rings=48)
    while ball.data.uv_layers:
        ball.data.uv_layers.remove(ball.data.uv_layers[0])
    bpy.ops.mesh.primitive_cylinder_add(vertices=64, radius=0.9, depth=0.1, location=(4.0 * math.tan(0.5), 0, 4.0))
    slab = bpy.context.object
    slab.data.materials.append(scenes.glass_material())
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.energy, sun.data.angle = 10.0, 0.0
    sun.rotation_euler = (0.0, 0.5, 0.0)  # travelling along (-sin 0.5, 0, -cos 0.5)
    bpy.context.scene.collection.objects.link(sun)
    scenes.add_camera((0.6, -2.6, 1.6), target=(0.0, 0.0, 0.1), lens=85.0)
    scenes.set_resolution(64, 64)
    bpy.context.scene.caustic.lamp_rays = 100_000
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    kinds = {node.bl_idname for node in bpy.data.node_groups[0].nodes}
    assert 'ShaderNodeNewGeometry' in kinds and 'ShaderNodeUVMap' not in kinds
    assert len(ball.data.uv_layers) == 0
    read = addon.export.read_scene(bpy.context)
    caustic = addon.caustic_addon.render(read.scene, addon.export.render_settings(bpy.context.scene.caustic,
                                                                                   spp=16)).passes["caustic"]
    slab.hide_render = sun.hide_render = True
    baked = cycles_render(str(tmp_path), samples=64)[..., :3]
    luminance = caustic[..., 1]
    pad = np.pad(luminance, 1)
    lowest = np.min([pad[i:i + 64, j:j + 64] for i in range(3) for j in range(3)], axis=0)
    lit = lowest > 0.3 * luminance.max()
    difference = (baked[..., 1] - luminance)[lit] / luminance[lit]
    print(f"baked in Cycles against the caustic pass over {lit.sum()} lit pixels: mean {difference.mean():+.4f}, "
          f"mean |difference| {np.abs(difference).mean():.4f}, 99th percentile {np.percentile(np.abs(difference), 99):.4f}")
    assert lit.sum() > 500
    assert abs(difference.mean()) < 0.02
    assert np.percentile(np.abs(difference), 99) < 0.1


def test_a_material_shared_by_two_receivers_shows_each_one_s_own_caustic(addon, tmp_path, reports):
    """A floor and a wall with one material (both bent, so charted by their
    UV maps, which overlap), each under its own glass ball and lamp: the
    bake gives each its own image and numbers the two objects, and Cycles
    shows the same picture as when each has a material of its own (read
    without the numbers, each image would show on both), each caustic at
    its receiver's peak of the caustic pass. Unbake takes the numbers off."""
    shared = scenes.diffuse_material("Plaster")
    floor, wall = scenes.add_plane(6.0, shared), scenes.add_plane(6.0, shared, name="Wall")
    for plane in (floor, wall):
        plane.data.vertices[0].co.z = 0.05
    wall.rotation_euler, wall.location = (math.pi / 2, 0.0, 0.0), (0.0, 1.5, 3.0)
    balls = [scenes.add_sphere(0.5, (0.8, -0.6, 0.75), scenes.glass_material(), name="Ball"),
             scenes.add_sphere(0.4, (-1.0, 0.7, 1.8), bpy.data.materials["Glass"], name="Marble")]
    lamps = [scenes.add_point_light((0.5, -0.2, 3.5), 1000.0),
             scenes.add_point_light((-1.2, -2.5, 1.9), 1000.0, name="Side")]
    scenes.add_camera((0.0, -6.0, 2.2), target=(0.0, 0.5, 1.0))
    scenes.set_resolution(64, 48)
    bpy.context.scene.caustic.lamp_rays = 200_000
    bpy.context.view_layer.update()
    material_before = material_state(shared)
    for ball in balls:
        ball.visible_camera = False
    read = addon.export.read_scene(bpy.context)
    caustic = addon.caustic_addon.render(read.scene, addon.export.render_settings(
        bpy.context.scene.caustic, spp=16)).passes["caustic"].sum(axis=-1)
    for ball in balls:
        ball.visible_camera = True

    def baked_in_cycles():
        assert bpy.ops.caustic.bake() == {'FINISHED'}
        for hidden in balls + lamps:
            hidden.hide_render = True
        bpy.context.scene.cycles.max_bounces = 0  # each receiver's caustic seen, not lighting the other
        image = cycles_render(str(tmp_path), samples=16)[..., :3].sum(axis=-1)
        for hidden in balls + lamps:
            hidden.hide_render = False
        return image

    reports()
    shared_image = baked_in_cycles()
    assert "is shared by" not in reports()
    assert {floor["caustic_receiver"], wall["caustic_receiver"]} == {1, 2}
    assert {"Caustic Map Floor", "Caustic Map Wall"} <= set(bpy.data.images.keys())
    for window in caustic_peaks(caustic, 2):
        ratio = shared_image[window].sum() / caustic[window].sum()
        print(f"baked caustic in Cycles / caustic pass, 7x7 around a peak: {ratio:.3f}")
        assert abs(ratio - 1.0) < 0.25

    assert bpy.ops.caustic.unbake() == {'FINISHED'}
    assert "caustic_receiver" not in floor and "caustic_receiver" not in wall
    assert material_state(shared) == material_before
    wall.material_slots[0].material = shared.copy()
    own_image = baked_in_cycles()
    assert "caustic_receiver" not in floor and "caustic_receiver" not in wall
    difference = np.abs(shared_image - own_image).sum() / own_image.sum()
    print(f"one shared material against a material each: relative L1 {difference:.4f}")
    assert difference < 0.02


def caustic_peaks(image, count):
    """Windows of 7x7 pixels around the `count` brightest peaks of `image`, each clear of the others."""
    image, windows = image.copy(), []
    for _ in range(count):
        row, col = np.unravel_index(image.argmax(), image.shape)
        window = (slice(max(row - 3, 0), row + 4), slice(max(col - 3, 0), col + 4))
        windows.append(window)
        image[max(row - 6, 0):row + 7, max(col - 6, 0):col + 7] = 0.0
    return windows
