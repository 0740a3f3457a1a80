"""Objects with several materials: each triangle takes its own slot's
material, as parts of one body (engine objects "name [material]"), each
with its own map and bake; against Cycles with direct light only."""

import bpy
import bmesh
import numpy as np
import pytest

import blender_scenes as scenes
from test_textures_vs_cycles import LUMINANCE, random_image

PIXELS = 40
HALF = 1.5


def two_colour_floor():
    """A 20 m floor whose half x < 0 is 'Red' and half x > 0 'Blue' (one
    object, two slots), under a point lamp, seen straight down by an
    orthographic camera 3 m across."""
    floor = scenes.add_plane(20.0, scenes.diffuse_material("Red", (0.8, 0.2, 0.1)))
    floor.data.materials.append(scenes.diffuse_material("Blue", (0.1, 0.3, 0.7)))
    bm = bmesh.new()
    bm.from_mesh(floor.data)
    bmesh.ops.bisect_plane(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:], plane_co=(0.0, 0.0, 0.0),
                           plane_no=(1.0, 0.0, 0.0))
    for face in bm.faces:
        face.material_index = int(face.calc_center_median().x > 0.0)
    bm.to_mesh(floor.data)
    bm.free()
    camera = scenes.add_camera((0.0, 0.0, 5.0))
    camera.data.type, camera.data.ortho_scale, camera.rotation_euler = 'ORTHO', 2 * HALF, (0.0, 0.0, 0.0)
    scenes.add_point_light((0.4, 0.2, 2.0), 300.0)
    scenes.set_resolution(PIXELS, PIXELS)
    bpy.context.scene.caustic.lamp_rays = 1000
    return floor


def texture_the_blue_half():
    """The Blue material's colour from a random 16x16 image on the UV map,
    tiled 4 times across the floor: texels 0.31 m, 4 pixels, wide,
    interpolated linearly."""
    tree = bpy.data.materials["Blue"].node_tree
    shader = next(n for n in tree.nodes if n.bl_idname == 'ShaderNodeBsdfDiffuse')
    texture, mapping = tree.nodes.new('ShaderNodeTexImage'), tree.nodes.new('ShaderNodeMapping')
    texture.image = random_image()
    coordinates = tree.nodes.new('ShaderNodeTexCoord')
    mapping.inputs['Scale'].default_value = (4.0, 4.0, 1.0)
    tree.links.new(coordinates.outputs['UV'], mapping.inputs['Vector'])
    tree.links.new(mapping.outputs['Vector'], texture.inputs['Vector'])
    tree.links.new(texture.outputs['Color'], shader.inputs['Color'])


@pytest.mark.parametrize("textured", [False, True], ids=["plain", "blue half textured"])
def test_each_half_of_a_two_material_floor_matches_cycles(addon, tmp_path, textured):
    two_colour_floor()
    if textured:
        texture_the_blue_half()
    read = addon.export.read_scene(bpy.context)
    parts = {o.name: o for o in read.scene.objects}
    assert set(parts) == {"Floor [Red]", "Floor [Blue]"}
    assert {o.body for o in parts.values()} == {"Floor"}
    assert np.allclose(parts["Floor [Red]"].material.albedo, (0.8, 0.2, 0.1))
    assert (parts["Floor [Blue]"].material.texture is not None) == textured
    assert read.materials == {"Floor [Red]": "Red", "Floor [Blue]": "Blue"}
    assert bpy.ops.caustic.render() == {'FINISHED'}
    ours = scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64)
    theirs = scenes.cycles_render(str(tmp_path), samples=16)[..., :3]
    # Pixel columns 0-18 see x < -0.075 (red), 21-39 see x > 0.075 (blue); 19 and 20 straddle the seam.
    for half, columns in (("red", slice(0, PIXELS // 2 - 1)), ("blue", slice(PIXELS // 2 + 1, PIXELS))):
        mine, cycles = ours[:, columns].mean(axis=(0, 1)), theirs[:, columns].mean(axis=(0, 1))
        error = np.linalg.norm((ours - theirs)[:, columns] @ LUMINANCE) / np.linalg.norm(theirs[:, columns] @ LUMINANCE)
        print(f"{half}: ours / Cycles {mine / cycles}, relative L2 of luminance {100 * error:.2f}%")
        assert mine == pytest.approx(cycles, rel=0.02) and error < 0.05


def test_an_empty_slot_renders_as_cycles_default_surface(addon, tmp_path):
    """Blue's slot emptied: its half is Cycles' default surface (a grey
    diffuse before Blender 5.0, a grey Principled BSDF since), highlight and all."""
    floor = two_colour_floor()
    floor.material_slots[1].material = None
    assert bpy.ops.caustic.render() == {'FINISHED'}
    ours = scenes.pixels_of("Caustic Render")[..., :3].astype(np.float64)
    theirs = scenes.cycles_render(str(tmp_path), samples=16)[..., :3]
    columns = slice(PIXELS // 2 + 1, PIXELS)
    error = np.linalg.norm((ours - theirs)[:, columns] @ LUMINANCE) / np.linalg.norm(theirs[:, columns] @ LUMINANCE)
    print(f"empty slot: ours / Cycles {ours[:, columns].mean() / theirs[:, columns].mean()}, "
          f"relative L2 of luminance {100 * error:.2f}%")
    assert ours[:, columns].mean() == pytest.approx(theirs[:, columns].mean(), rel=0.02) and error < 0.05


def test_the_bake_writes_a_map_into_each_material_of_the_receiver(addon):
    floor = two_colour_floor()
    scenes.add_sphere(0.4, (0.0, 0.0, 0.8), scenes.glass_material(), segments=16, rings=8)
    assert bpy.ops.caustic.bake() == {'FINISHED'}
    for material in floor.data.materials:
        nodes = [n for n in material.node_tree.nodes if n.bl_idname == 'ShaderNodeGroup']
        assert [n.node_tree.name for n in nodes] == [f"Caustic Bake Floor [{material.name}]"]
    assert {"Caustic Map Floor [Red]", "Caustic Map Floor [Blue]"} <= set(bpy.data.images.keys())
    assert bpy.ops.caustic.unbake() == {'FINISHED'}


def tumbler(base_material=None):
    """A closed glass cylinder (radius 0.3, 0.6 tall) on a 6 m floor under a
    point lamp, its bottom cap of `base_material` if given; seen from above."""
    scenes.add_plane(6.0, scenes.diffuse_material())
    bpy.ops.mesh.primitive_cylinder_add(vertices=48, radius=0.3, depth=0.6, location=(0.0, 0.0, 0.35))
    glass = bpy.context.object
    glass.name = "Tumbler"
    glass.data.materials.append(scenes.glass_material())
    if base_material is not None:
        glass.data.materials.append(base_material)
        for polygon in glass.data.polygons:
            polygon.material_index = int(polygon.normal.z < -0.5)
    scenes.add_point_light((0.2, 0.0, 3.0), 1000.0)
    scenes.add_camera((0.0, -1.6, 2.4), target=(0.0, 0.0, 0.2))
    scenes.set_resolution(48, 36)
    bpy.context.scene.caustic.lamp_rays = 20_000
    return glass


def passes(addon):
    read = addon.export.read_scene(bpy.context)
    result = addon.caustic_addon.render(read.scene, addon.export.render_settings(bpy.context.scene.caustic))
    return read, result


def test_glass_with_a_base_of_another_material_is_one_closed_body(addon):
    tumbler()
    _, whole = passes(addon)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    tumbler(scenes.glass_material("Base glass"))
    read, parts = passes(addon)
    assert {o.name for o in read.scene.objects} == {"Floor", "Tumbler [Glass]", "Tumbler [Base glass]"}
    assert not any("closed" in w or "leak" in w for w in parts.warnings)
    # Both parts of one glass: the eye rays, the lamp's aims and its beams as through the one mesh.
    for name in ("direct", "ambient", "caustic"):
        assert np.allclose(parts.passes[name], whole.passes[name], rtol=1e-4, atol=1e-6), name


@pytest.mark.parametrize("base", ["denser glass", "painted"])
def test_a_glass_whose_base_is_another_kind_of_material_stays_closed(addon, base):
    material = (scenes.glass_material("Base", ior=1.8) if base == "denser glass"
                else scenes.diffuse_material("Base", (0.2, 0.6, 0.2)))
    tumbler(material)
    read, parts = passes(addon)
    assert not any("closed" in w or "leak" in w for w in parts.warnings)
    assert read.scene.objects[2].is_transparent == (base == "denser glass")
    assert np.isfinite(parts.image).all() and parts.passes["caustic"].max() > 0.0
