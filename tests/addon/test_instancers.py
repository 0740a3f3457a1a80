"""Geometry Nodes' instances read in bulk (export/instancers.py, Blender 4.5
on) against the depsgraph's object instances walked one by one: the same
engine scene, object by object, and the walk where bulk cannot read."""

import bpy
import numpy as np
import pytest

import blender_scenes as scenes

pytestmark = pytest.mark.skipif(bpy.app.version < (4, 5, 0), reason="Object.evaluated_geometry is Blender 4.5's")


def both_reads(addon, monkeypatch, reader=None):
    """(bulk, walk, read): the scene read as the add-on reads it (`reader`:
    export.read_scene), what read_instancers found there (None: the walk
    was taken), and the scene walked (read_instancers says None)."""
    reader = reader or addon.export.read_scene
    found = []

    def spy(depsgraph):
        found.append(real(depsgraph))
        return found[-1]

    real = addon.export.scene.read_instancers
    with monkeypatch.context() as patch:
        patch.setattr(addon.export.scene, "read_instancers", spy)
        bulk = reader(bpy.context)
        patch.setattr(addon.export.scene, "read_instancers", lambda depsgraph: None)
        walk = reader(bpy.context)
    return bulk, walk, found[0]


def assert_same(bulk, walk):
    assert [o.name for o in bulk.scene.objects] == [o.name for o in walk.scene.objects]
    assert bulk.instanced == walk.instanced and bulk.sources == walk.sources and bulk.materials == walk.materials
    assert bulk.warnings == walk.warnings
    for a, b in zip(bulk.scene.objects, walk.scene.objects):
        assert a.copies == b.copies and a.visibility == b.visibility and a.body == b.body, a.name
        assert type(a.material) is type(b.material), a.name
        if a.instances is None:
            np.testing.assert_allclose(a.mesh.vertices, b.mesh.vertices, atol=1e-6)
            np.testing.assert_array_equal(a.mesh.triangles, b.mesh.triangles)
        else:
            np.testing.assert_array_equal(a.instances.mesh.vertices, b.instances.mesh.vertices)
            np.testing.assert_array_equal(a.instances.mesh.triangles, b.instances.mesh.triangles)
            np.testing.assert_allclose(a.instances.transforms, b.instances.transforms, atol=1e-6)


def scene_of_instancers():
    """A floor, a lamp, a camera; an Ico Sphere scatter moved and turned;
    a scatter of an Object Info node's realized ball; a scatter of another
    ball "As Instance", of two materials; a scatter of diffuse cubes, which
    receive and so are read one by one; a scatter of a Collection Info
    node's collection (rock_collection)."""
    scenes.add_plane(6.0, scenes.diffuse_material())
    scenes.add_point_light((0.0, 0.0, 3.0), 500.0)
    scenes.add_camera((0.0, -4.0, 3.0))
    gems = scenes.scatter(3, 0.3, name="Gems")
    gems.location, gems.rotation_euler = (1.0, 0.5, 0.5), (0.3, 0.0, 1.0)
    for name, as_instance, z in (("Realized", False, 1.0), ("Placed", True, 1.5)):
        ball = scenes.add_sphere(0.1, (4.0, 0.0, 0.0), scenes.glass_material(), f"{name} ball", segments=8, rings=4)
        if as_instance:
            ball.data.materials.append(scenes.glossy_material())
            ball.data.polygons.foreach_set("material_index", np.arange(len(ball.data.polygons)) % 2)
        holder = scenes.scatter(2, 0.4, name=name)
        holder.location.z = z
        tree = holder.modifiers[0].node_group
        info = tree.nodes.new('GeometryNodeObjectInfo')
        info.inputs['Object'].default_value = ball
        info.inputs['As Instance'].default_value = as_instance
        tree.links.new(info.outputs['Geometry'], tree.nodes['Instance on Points'].inputs['Instance'])
    cubes = scenes.scatter(2, 0.5, 'GeometryNodeMeshCube', name="Cubes", size=0.05)
    cubes.modifiers[0].node_group.nodes['Set Material'].inputs['Material'].default_value = scenes.diffuse_material()
    cubes.location.z = 2.0
    rocks = scenes.scatter(2, 0.6, name="Rocks")
    rocks.location.z = 2.5
    tree = rocks.modifiers[0].node_group
    info = tree.nodes.new('GeometryNodeCollectionInfo')
    info.inputs['Collection'].default_value = rock_collection()
    tree.links.new(info.outputs[0], tree.nodes['Instance on Points'].inputs['Instance'])


def rock_collection():
    """A collection off to the side, with an Instance Offset: two glass
    rocks, one of them subdivided, a third hidden from renders, an empty,
    and a child collection with a pebble."""
    rocks = bpy.data.collections.new("Rock pile")
    bpy.context.scene.collection.children.link(rocks)
    pebbles = bpy.data.collections.new("Pebbles")
    rocks.children.link(pebbles)
    rocks.instance_offset = (5.0, 0.2, 0.0)
    for name, y, collection in (("Rock A", 0.0, rocks), ("Rock B", 0.3, rocks), ("Hidden rock", 0.6, rocks),
                                ("Pebble", 0.9, pebbles)):
        rock = scenes.add_sphere(0.1, (5.0, y, 0.0), scenes.glass_material(), name, segments=8, rings=4)
        for old in list(rock.users_collection):
            old.objects.unlink(rock)
        collection.objects.link(rock)
    bpy.data.objects["Rock B"].modifiers.new("Smooth", 'SUBSURF')
    bpy.data.objects["Hidden rock"].hide_render = True
    rocks.objects.link(bpy.data.objects.new("Marker", None))
    return rocks


def test_instances_read_in_bulk_are_those_the_walk_reads(addon, monkeypatch):
    scene_of_instancers()
    bulk, walk, read = both_reads(addon, monkeypatch)
    assert set(read) == {"Gems", "Realized", "Placed", "Cubes", "Rocks"}
    assert_same(bulk, walk)
    copies = {o.name: o.copies for o in bulk.scene.objects}
    assert copies["Gems [Gems]"] == 9 and copies["Realized [Realized]"] == 4
    assert [n for name, n in copies.items() if name.startswith("Placed ball [Placed] [")] == [4, 4]  # two materials
    assert sum(name.startswith("Cubes [Cubes #") for name in copies) == 4
    assert copies["Rock A [Rocks]"] == copies["Rock B [Rocks]"] == copies["Pebble [Rocks]"] == 4
    assert "Hidden rock [Rocks]" not in copies


def test_without_a_camera_the_viewports_instances_are_read_in_bulk(addon, monkeypatch):
    """With no camera the bake reads the scene as the viewport shows it,
    where a collection's objects hidden from renders are shown."""
    scene_of_instancers()
    bpy.data.objects.remove(bpy.data.objects["Camera"])
    bulk, walk, read = both_reads(addon, monkeypatch, addon.export.read_for_bake)
    assert read is not None
    assert_same(bulk, walk)
    assert "Hidden rock [Rocks]" in [o.name for o in bulk.scene.objects]


def test_particles_and_collection_instances_are_walked(addon, monkeypatch):
    scene_of_instancers()
    source = bpy.data.collections.new("Source")
    source.objects.link(bpy.data.objects["Realized ball"])
    placer = bpy.data.objects.new("Placer", None)
    placer.instance_type, placer.instance_collection = 'COLLECTION', source
    bpy.context.scene.collection.objects.link(placer)
    bulk, walk, read = both_reads(addon, monkeypatch)
    assert read is None
    assert_same(bulk, walk)
    assert any(name.startswith("Realized ball [Placer") for name in bulk.instanced)
