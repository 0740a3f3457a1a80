"""What the add-on reads from Blender: the evaluated scene in world space,
render visibility, roles and materials, lamps and the camera."""

import math

import bpy
import numpy as np
import pytest
from mathutils import Matrix

import blender_scenes as scenes


def read(addon):
    return addon.export.read_scene(bpy.context)


def engine_object(result, name):
    return next(o for o in result.scene.objects if o.name == name)


def lamp_scene():
    """A floor and a lamp: the least the reader accepts."""
    floor = scenes.add_plane(4.0, scenes.diffuse_material())
    lamp = scenes.add_point_light((0.0, 0.0, 2.0), 100.0)
    scenes.add_camera((0.0, -3.0, 3.0))
    return floor, lamp


def test_modifiers_are_read_at_their_render_settings(addon):
    lamp_scene()
    ball = scenes.add_sphere(1.0, (0.0, 0.0, 1.0), scenes.glass_material(), segments=16, rings=8)
    subdivide = ball.modifiers.new("Subdivide", 'SUBSURF')
    subdivide.levels, subdivide.render_levels = 1, 3
    twice = ball.modifiers.new("Twice", 'ARRAY')
    twice.count, twice.show_viewport, twice.relative_offset_displace = 2, False, (3.0, 0.0, 0.0)
    quads, fans = 16 * (8 - 2), 2 * 16
    # Level L makes 4^L quads of a quad and 3 x 4^(L-1) of a triangle; each quad is 2 triangles.
    render_level = 2 * (4 ** 3 * quads + 3 * 4 ** 2 * fans)
    assert len(engine_object(read(addon), "Ball").mesh.triangles) == 2 * render_level
    assert (subdivide.levels, subdivide.render_levels, twice.show_viewport) == (1, 3, False)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    assert len(ball.evaluated_get(depsgraph).data.loop_triangles) == 2 * (4 * quads + 3 * fans)


def test_world_space_with_normals_by_the_inverse_transpose(addon):
    lamp_scene()
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    box = bpy.context.object
    box.data.materials.append(scenes.glass_material())
    box.matrix_world = (Matrix.Translation((1.0, 2.0, 3.0)) @ Matrix.Rotation(0.7, 4, (1.0, 1.0, 0.0))
                        @ Matrix.Diagonal((3.0, 1.0, 0.25, 1.0)))
    mesh = engine_object(read(addon), box.name).mesh
    corners = mesh.corners
    assert np.allclose(corners.reshape(-1, 3).mean(axis=0), (1.0, 2.0, 3.0), atol=1e-6)
    # Flat faces: each corner normal is perpendicular to its triangle's world-space edges, and points out.
    for a, b in ((0, 1), (1, 2), (2, 0)):
        edges = corners[:, b] - corners[:, a]
        edges /= np.linalg.norm(edges, axis=-1, keepdims=True)
        assert np.abs(np.einsum("ti,tci->tc", edges, mesh.corner_normals)).max() < 1e-6
    outward = corners.mean(axis=1) - (1.0, 2.0, 3.0)
    assert (np.einsum("ti,ti->t", outward, mesh.corner_normals[:, 0]) > 0).all()


def test_objects_disabled_for_render_are_left_out_and_those_hidden_in_the_viewport_read(addon, reports):
    lamp_scene()
    glass = scenes.glass_material()
    hidden = scenes.add_sphere(0.3, (1.0, 0.0, 0.5), glass, name="NotRendered", segments=8, rings=4)
    hidden.hide_render = True
    in_hidden_collection = scenes.add_sphere(0.3, (-1.0, 0.0, 0.5), glass, name="InHidden", segments=8, rings=4)
    collection = bpy.data.collections.new("Hidden")
    bpy.context.scene.collection.children.link(collection)
    collection.objects.link(in_hidden_collection)
    bpy.context.scene.collection.objects.unlink(in_hidden_collection)
    collection.hide_render = True
    viewport_hidden = scenes.add_sphere(0.3, (0.0, 1.0, 0.5), glass, name="ViewportHidden", segments=8, rings=4)
    viewport_hidden.hide_viewport = True
    eye_hidden = scenes.add_sphere(0.3, (0.0, -1.0, 0.5), glass, name="EyeHidden", segments=8, rings=4)
    eye_hidden.hide_set(True)
    in_viewport_hidden_collection = scenes.add_sphere(0.3, (1.0, 1.0, 0.5), glass, name="InViewportHidden",
                                                      segments=8, rings=4)
    shown_in_render = bpy.data.collections.new("Shown")
    bpy.context.scene.collection.children.link(shown_in_render)
    shown_in_render.objects.link(in_viewport_hidden_collection)
    bpy.context.scene.collection.objects.unlink(in_viewport_hidden_collection)
    shown_in_render.hide_viewport = True
    result = read(addon)
    assert {o.name for o in result.scene.objects} == {"Floor", "ViewportHidden", "EyeHidden", "InViewportHidden"}
    assert not any("hidden" in w for w in result.warnings)
    assert viewport_hidden.hide_viewport and eye_hidden.hide_get() and shown_in_render.hide_viewport


def test_collection_instances_are_read_in_world_space(addon):
    lamp_scene()
    collection = bpy.data.collections.new("Props")
    ball = scenes.add_sphere(0.5, (0.0, 0.0, 0.75), scenes.glass_material(), segments=16, rings=8)
    collection.objects.link(ball)
    bpy.context.scene.collection.objects.unlink(ball)
    empty = bpy.data.objects.new("Placer", None)
    empty.instance_type, empty.instance_collection = 'COLLECTION', collection
    empty.location = (2.0, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(empty)
    result = read(addon)
    instanced = [o for o in result.scene.objects if o.name.startswith("Ball [Placer")]
    assert len(instanced) == 1 and instanced[0].name in result.instanced
    assert np.allclose(instanced[0].mesh.vertices.mean(axis=0), (2.0, 0.0, 0.75), atol=1e-6)
    assert instanced[0].is_transparent


def principled(name, **inputs):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    node = material.node_tree.nodes["Principled BSDF"]
    for socket, value in inputs.items():
        node.inputs[socket].default_value = value
    return material


def test_roles_from_materials_and_overrides(addon):
    floor, _ = lamp_scene()
    floor.data.materials[0] = principled("Painted", **{"Base Color": (0.2, 0.4, 0.6, 1.0)})
    scenes.add_sphere(0.3, (1.0, 0.0, 0.5), principled(
        "Water", **{"Transmission Weight": 1.0, "IOR": 1.33, "Roughness": 0.0}), name="Water", segments=8, rings=4)
    forced = scenes.add_sphere(0.3, (-1.0, 0.0, 0.5), scenes.diffuse_material("Chalk"), name="Forced",
                               segments=8, rings=4)
    forced.caustic.role = 'TRANSPARENT'
    forced.caustic.absorption_from, forced.caustic.absorption = 'COEFFICIENT', (0.5, 1.0, 2.0)
    gem = scenes.add_sphere(0.3, (0.0, 1.0, 0.5), scenes.glass_material("Gem"), name="Gem", segments=8, rings=4)
    gem.caustic.use_ior, gem.caustic.ior = True, 2.42
    ignored = scenes.add_sphere(0.3, (0.0, -1.0, 0.5), scenes.glass_material("Other"), name="Ignored",
                                segments=8, rings=4)
    ignored.caustic.role = 'IGNORE'
    result = read(addon)
    names = {o.name: o.material for o in result.scene.objects}
    assert set(names) == {"Floor", "Water", "Forced", "Gem"}
    assert names["Floor"].receiver and np.allclose(names["Floor"].albedo, (0.2, 0.4, 0.6))
    assert names["Water"].ior == pytest.approx(1.33)
    assert names["Forced"].ior == 1.5 and np.allclose(names["Forced"].absorption, (0.5, 1.0, 2.0))
    assert names["Gem"].ior == pytest.approx(2.42)
    assert result.materials["Water"] == "Water"


def test_a_principled_receiver_keeps_its_layers(addon):
    """Roughness, IOR, Specular IOR Level, Specular Tint, the distribution,
    Metallic up to 0.5 and the coat reach the engine; inputs it does not
    render are named, in one warning; a Diffuse BSDF has no layer."""
    floor, _ = lamp_scene()
    floor.data.materials[0] = principled("Varnish", **{
        "Roughness": 0.3, "IOR": 1.45, "Specular IOR Level": 0.8, "Specular Tint": (1.0, 0.5, 0.25, 1.0),
        "Metallic": 0.3, "Coat Weight": 0.5, "Coat Roughness": 0.1, "Coat IOR": 1.6,
        "Coat Tint": (0.9, 0.7, 0.5, 1.0), "Sheen Weight": 0.2, "Subsurface Weight": 0.1})
    floor.data.materials[0].node_tree.nodes["Principled BSDF"].distribution = 'GGX'
    scenes.add_sphere(0.3, (1.0, 0.0, 0.5), scenes.diffuse_material("Chalk"), name="Chalk", segments=8, rings=4)
    result = read(addon)
    layer = engine_object(result, "Floor").material.specular
    assert (layer.roughness, layer.ior, layer.level, layer.metallic) == pytest.approx((0.3, 1.45, 0.8, 0.3))
    assert layer.tint == pytest.approx([1.0, 0.5, 0.25]) and not layer.multiscatter
    assert (layer.coat.weight, layer.coat.roughness, layer.coat.ior) == pytest.approx((0.5, 0.1, 1.6))
    assert layer.coat.tint == pytest.approx([0.9, 0.7, 0.5])
    assert engine_object(result, "Chalk").material.specular is None
    named = [w for w in result.warnings if "material 'Varnish'" in w]
    assert named == ["material 'Varnish': its Sheen Weight, Subsurface Weight are not rendered; it is rendered as a "
                     "diffuse base under its specular layer, metal and coat"]


def test_a_metal_names_what_it_does_not_render(addon):
    """Metallic above 0.5 renders as a mirror of its Base Color, which has
    no coat."""
    lamp_scene()
    scenes.add_sphere(0.3, (1.0, 0.0, 0.5), principled("Lacquered gold", **{"Metallic": 1.0, "Coat Weight": 1.0}),
                      name="Ring", segments=8, rings=4)
    result = read(addon)
    assert isinstance(engine_object(result, "Ring").material, addon.caustic_addon.Reflector)
    assert [w for w in result.warnings if "Lacquered gold" in w] == [
        "material 'Lacquered gold': its Coat Weight is not rendered; it is rendered as a mirror of its Base Color"]


def test_mirrors_and_metals_read_as_reflectors(addon):
    floor, _ = lamp_scene()
    shapes = {}
    for name, material in (
            ("Chrome", scenes.glossy_material("Chrome", color=(0.9, 0.8, 0.7))),
            ("Brushed", scenes.glossy_material("Brushed", roughness=0.1)),
            ("Gold", principled("Gold", **{"Metallic": 1.0, "Roughness": 0.0, "Base Color": (1.0, 0.8, 0.3, 1.0)})),
            ("Pewter", principled("Pewter", **{"Metallic": 1.0, "Roughness": 0.6})),
            ("Chalk", scenes.diffuse_material("Chalk"))):
        shapes[name] = scenes.add_sphere(0.2, (len(shapes) * 0.5 - 1.0, 0.0, 0.5), material, name=name,
                                         segments=8, rings=4)
    shapes["Chalk"].caustic.role = 'REFLECTOR'
    result = read(addon)
    materials = {o.name: o.material for o in result.scene.objects}
    Reflector = addon.caustic_addon.Reflector
    assert isinstance(materials["Chrome"], Reflector) and np.allclose(materials["Chrome"].color, (0.9, 0.8, 0.7))
    assert materials["Chrome"].roughness == 0.0
    assert isinstance(materials["Brushed"], Reflector) and materials["Brushed"].roughness == pytest.approx(0.1)
    assert isinstance(materials["Gold"], Reflector) and np.allclose(materials["Gold"].color, (1.0, 0.8, 0.3))
    assert isinstance(materials["Pewter"], Reflector) and materials["Pewter"].roughness == pytest.approx(0.6)
    assert materials["Pewter"].multiscatter and materials["Brushed"].multiscatter
    assert isinstance(materials["Chalk"], Reflector) and np.allclose(materials["Chalk"].color, 1.0)
    assert not any("oughness" in w for w in result.warnings)


def test_roughness_and_distribution_of_glass_and_metal(addon):
    """Glass, Refraction, Glossy and Principled BSDFs (transmissive and
    metal) give the engine their Roughness, clamped to 0..1 as Cycles does,
    and whether they are Multiscatter GGX; no warning names roughness."""
    lamp_scene()
    frosted = scenes.glass_material("Frosted")
    frosted.node_tree.nodes["Glass BSDF"].inputs["Roughness"].default_value = 0.3
    plain = scenes.glass_material("Plain GGX")
    plain.node_tree.nodes["Glass BSDF"].inputs["Roughness"].default_value = 0.2
    plain.node_tree.nodes["Glass BSDF"].distribution = 'GGX'
    refraction = bpy.data.materials.new("Refraction")
    if refraction.node_tree is None:
        refraction.use_nodes = True
    nodes = refraction.node_tree.nodes
    nodes.clear()
    node = nodes.new('ShaderNodeBsdfRefraction')
    node.inputs["Roughness"].default_value, node.inputs["IOR"].default_value, node.distribution = 0.25, 1.33, 'GGX'
    refraction.node_tree.links.new(node.outputs[0], nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    cases = {"Frosted": frosted, "Plain GGX": plain, "Refraction": refraction,
             "Principled glass": principled("Principled glass", **{"Transmission Weight": 1.0, "Roughness": 0.5}),
             "Rough metal": principled("Rough metal", **{"Metallic": 1.0, "Roughness": 0.45}),
             "Satin": scenes.glossy_material("Satin", roughness=0.35)}
    cases["Rough metal"].node_tree.nodes["Principled BSDF"].distribution = 'GGX'
    for k, (name, material) in enumerate(cases.items()):
        scenes.add_sphere(0.2, (k * 0.5 - 1.0, 0.0, 0.5), material, name=name, segments=8, rings=4)
    result = read(addon)
    materials = {o.name: o.material for o in result.scene.objects}
    Dielectric, Reflector = addon.caustic_addon.Dielectric, addon.caustic_addon.Reflector
    expected = {"Frosted": (Dielectric, 0.3, True), "Plain GGX": (Dielectric, 0.2, False),
                "Refraction": (Dielectric, 0.25, False), "Principled glass": (Dielectric, 0.5, True),
                "Rough metal": (Reflector, 0.45, False), "Satin": (Reflector, 0.35, True)}
    for name, (kind, roughness, multiscatter) in expected.items():
        assert isinstance(materials[name], kind), name
        assert materials[name].roughness == pytest.approx(roughness), name
        assert materials[name].multiscatter == multiscatter, name
    assert materials["Refraction"].ior == pytest.approx(1.33)
    assert not any("oughness" in w for w in result.warnings)


def test_glass_tints_as_cycles_applies_them(addon):
    """Cycles' svm/closure.h: a Glass BSDF's Color tints its reflections and
    refractions; a Principled BSDF's refractions take the square root of
    its Base Color (clamped to 0..1), its reflections none; a Refraction
    BSDF reflects nothing. A Principled glass's Transmission Weight t
    weighs both (its closure's weight); the base under 1 - t and its
    Specular Tint, which are not rendered, are named."""
    lamp_scene()
    green = (0.2, 0.75, 0.3, 1.0)
    tinted = scenes.glass_material("Tinted")
    tinted.node_tree.nodes["Glass BSDF"].inputs["Color"].default_value = green
    bottle = principled("Bottle", **{"Transmission Weight": 1.0, "Base Color": (0.2, 0.75, 1.4, 1.0),
                                     "Specular Tint": (1.0, 0.5, 0.5, 1.0)})
    partly = principled("Partly", **{"Transmission Weight": 0.8, "Base Color": green})
    refraction = bpy.data.materials.new("Refraction")
    if refraction.node_tree is None:
        refraction.use_nodes = True
    nodes = refraction.node_tree.nodes
    nodes.clear()
    node = nodes.new('ShaderNodeBsdfRefraction')
    node.inputs["Color"].default_value = green
    refraction.node_tree.links.new(node.outputs[0], nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    for k, material in enumerate((tinted, bottle, partly, refraction)):
        scenes.add_sphere(0.2, (k * 0.5 - 0.5, 0.0, 0.5), material, name=material.name, segments=8, rings=4)
    result = read(addon)
    materials = {o.name: o.material for o in result.scene.objects}
    np.testing.assert_allclose(materials["Tinted"].reflection_tint, green[:3])
    np.testing.assert_allclose(materials["Tinted"].transmission_tint, green[:3])
    assert materials["Tinted"].fresnel and materials["Bottle"].fresnel
    np.testing.assert_allclose(materials["Bottle"].reflection_tint, 1.0)
    np.testing.assert_allclose(materials["Bottle"].transmission_tint, np.sqrt((0.2, 0.75, 1.0)), rtol=1e-6)
    np.testing.assert_allclose(materials["Refraction"].reflection_tint, 0.0)
    np.testing.assert_allclose(materials["Refraction"].transmission_tint, green[:3])
    assert not materials["Refraction"].fresnel
    assert "material 'Bottle': its Specular Tint is not rendered on glass; its reflections are white" in result.warnings
    np.testing.assert_allclose(materials["Partly"].reflection_tint, 0.8, rtol=1e-6)
    np.testing.assert_allclose(materials["Partly"].transmission_tint, 0.8 * np.sqrt(green[:3]), rtol=1e-6)
    assert any(w.startswith("material 'Partly': its Transmission Weight 0.8 is rendered as glass of 0.8")
               for w in result.warnings)


def test_approximations_are_named_in_warnings(addon):
    floor, _ = lamp_scene()
    material = floor.data.materials[0]
    texture = material.node_tree.nodes.new('ShaderNodeTexChecker')
    shader = material.node_tree.nodes["Diffuse BSDF"]
    material.node_tree.links.new(texture.outputs['Color'], shader.inputs['Color'])
    rough = scenes.glass_material("Frosted")
    rough.node_tree.nodes["Glass BSDF"].inputs["Roughness"].default_value = 0.3
    rough.node_tree.nodes["Glass BSDF"].distribution = 'BECKMANN'
    scenes.add_sphere(0.3, (1.0, 0.0, 0.5), rough, segments=8, rings=4)
    brushed = scenes.glossy_material("Brushed", roughness=0.2)
    brushed.node_tree.nodes["Glossy BSDF"].inputs["Anisotropy"].default_value = 0.5
    scenes.add_sphere(0.2, (0.0, 1.0, 0.5), brushed, name="Brushed", segments=8, rings=4)
    bpy.ops.curve.primitive_bezier_circle_add()
    curve = bpy.context.object.name
    neon = scenes.add_sphere(0.2, (-1.0, 0.0, 0.5), scenes.diffuse_material("Neon"), name="Neon", segments=8, rings=4)
    nodes = neon.active_material.node_tree.nodes
    emission = nodes.new('ShaderNodeEmission')
    emission.inputs['Strength'].default_value = 5.0
    neon.active_material.node_tree.links.new(emission.outputs[0], nodes['Material Output'].inputs['Surface'])
    result = read(addon)
    warnings = "\n".join(result.warnings)
    assert "Checker" not in warnings, "Cycles bakes it"
    assert engine_object(result, "Floor").material.texture is not None
    assert "material 'Frosted': its Beckmann distribution is rendered as GGX" in warnings
    assert "material 'Brushed': its Anisotropy is not rendered: its microfacets are isotropic" in warnings
    assert f"'{curve}': curve objects are not supported" in warnings
    assert "emits light" not in warnings
    neon_material = next(o.material for o in result.scene.objects if o.name == "Neon")
    assert np.allclose(neon_material.emission, 5.0) and np.allclose(neon_material.albedo, 0.0)
    assert not neon_material.receiver  # it reflects nothing: no bake for its material


def test_lamps_in_blender_units(addon):
    scenes.add_plane(4.0, scenes.diffuse_material())
    scenes.add_camera((0.0, -3.0, 3.0))
    point = scenes.add_point_light((0.0, 0.0, 2.0), 100.0, name="Point")
    point.data.color = (1.0, 0.5, 0.25)
    if hasattr(point.data, "exposure"):
        point.data.exposure = 1.0
    spot = bpy.data.objects.new("Spot", bpy.data.lights.new("Spot", 'SPOT'))
    spot.data.energy, spot.data.spot_size, spot.data.spot_blend = 50.0, math.radians(30.0), 0.2
    spot.location, spot.rotation_euler = (1.0, 0.0, 2.0), (math.radians(90.0), 0.0, 0.0)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.0, math.radians(45.0), 0.0)
    for ob in (spot, sun):
        bpy.context.scene.collection.objects.link(ob)
    lights = {light.name: light for light in read(addon).scene.lights}
    exposure = 2.0 if hasattr(point.data, "exposure") else 1.0
    assert lights["Point"].power == pytest.approx(100.0 * exposure)
    assert np.allclose(lights["Point"].color, (1.0, 0.5, 0.25)) and np.allclose(lights["Point"].position, (0, 0, 2))
    # The spot points along its local -Z: rotated 90 degrees about X, that is +Y.
    assert np.allclose(lights["Spot"].direction, (0.0, 1.0, 0.0), atol=1e-6)
    assert lights["Spot"].spot_size == pytest.approx(math.radians(30.0)) and lights["Spot"].blend == pytest.approx(0.2)
    assert lights["Sun"].strength == 3.0
    assert np.allclose(lights["Sun"].direction, (-math.sqrt(0.5), 0.0, -math.sqrt(0.5)), atol=1e-6)


def test_lamps_with_a_size(addon):
    """Radius and Soft Falloff, a sun's angle, an area lamp's shape, size,
    scale and spread, as the engine's lamps."""
    lamp_scene()
    point = bpy.data.lights["Lamp"]
    point.shadow_soft_size, point.use_soft_falloff = 0.4, False
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.angle = math.radians(12.0)
    area = bpy.data.objects.new("Area", bpy.data.lights.new("Area", 'AREA'))
    area.data.shape, area.data.size, area.data.size_y, area.data.spread = 'ELLIPSE', 2.0, 0.5, math.radians(60.0)
    area.data.energy = 80.0
    area.location, area.scale = (0.0, 0.0, 3.0), (1.5, 1.0, 1.0)
    for ob in (sun, area):
        bpy.context.scene.collection.objects.link(ob)
    lights = {light.name: light for light in read(addon).scene.lights}
    assert (lights["Lamp"].radius, lights["Lamp"].soft_falloff) == (pytest.approx(0.4), False)
    assert lights["Sun"].angle == pytest.approx(math.radians(12.0))
    lamp = lights["Area"]
    assert lamp.shape == "ELLIPSE" and lamp.spread == pytest.approx(math.radians(60.0))
    np.testing.assert_allclose(lamp.axis_x, (1.5, 0.0, 0.0), atol=1e-6)
    np.testing.assert_allclose(lamp.axis_y, (0.0, 0.25, 0.0), atol=1e-6)
    np.testing.assert_allclose(lamp.direction, (0.0, 0.0, -1.0), atol=1e-6)
    assert lamp.area == pytest.approx(math.pi * 1.5 * 0.25) and lamp.power == pytest.approx(80.0)


@pytest.mark.skipif("normalize" not in bpy.types.Light.bl_rna.properties, reason="Normalize is Blender 4.5+")
def test_normalize_off_multiplies_the_power_by_the_lamps_area(addon):
    """Cycles divides a lamp's power by Light.area() only with Normalize on."""
    lamp_scene()
    light = bpy.data.lights["Lamp"]
    light.shadow_soft_size, light.normalize = 0.5, False
    engine = read(addon).scene.lights[0]
    assert engine.power == pytest.approx(light.energy * light.area(matrix_world=bpy.data.objects["Lamp"].matrix_world))


def test_the_world_colour_and_an_environment_image(addon):
    lamp_scene()
    world, _, background = scenes.world_nodes("Sky")
    background.inputs['Color'].default_value = (0.2, 0.4, 0.8, 1.0)
    background.inputs['Strength'].default_value = 2.0
    np.testing.assert_allclose(read(addon).scene.world.color, (0.4, 0.8, 1.6))
    image = bpy.data.images.new("Sky", 8, 4, float_buffer=True)
    pixels = np.zeros((4, 8, 4), dtype=np.float32)
    pixels[..., 0], pixels[..., 3] = np.arange(4)[:, None], 1.0
    image.pixels.foreach_set(pixels.ravel())
    texture = world.node_tree.nodes.new('ShaderNodeTexEnvironment')
    texture.image = image
    world.node_tree.links.new(texture.outputs['Color'], background.inputs['Color'])
    read_world = read(addon).scene.world
    np.testing.assert_allclose(read_world.color, 2.0)
    # row 0 at the top: Blender's last row
    np.testing.assert_allclose(read_world.environment[:, 0, 0], [3.0, 2.0, 1.0, 0.0])
    texture.image = None
    result = read(addon)
    assert result.scene.world.is_black
    assert any("world 'Sky': the Environment Texture" in w for w in result.warnings)


def test_an_unchanged_environment_image_comes_back_as_the_same_array_and_a_changed_one_afresh(addon, tmp_path):
    """The engine keeps a world's sun, sky and sampling tables while the
    same environment array comes back: an HDRI read again, unchanged, is
    that array; painted, or its file saved anew and reloaded, it is read
    again."""
    lamp_scene()
    world, _, background = scenes.world_nodes("Sky")
    image = bpy.data.images.new("Sky", 8, 4, float_buffer=True)
    image.pixels.foreach_set(np.ones(8 * 4 * 4, dtype=np.float32))
    image.filepath_raw, image.file_format = str(tmp_path / "sky.exr"), 'OPEN_EXR'
    image.save()
    sky = bpy.data.images.load(str(tmp_path / "sky.exr"))
    texture = world.node_tree.nodes.new('ShaderNodeTexEnvironment')
    texture.image = sky
    world.node_tree.links.new(texture.outputs['Color'], background.inputs['Color'])
    first = read(addon).scene.world.environment
    assert read(addon).scene.world.environment is first
    painted = np.full(8 * 4 * 4, 2.0, dtype=np.float32)
    sky.pixels.foreach_set(painted)
    assert sky.is_dirty
    changed = read(addon).scene.world.environment
    assert changed is not first and np.all(changed == 2.0)
    # saved to its file and read back: unchanged since, it comes back as one array again
    sky.save()
    sky.reload()
    saved = read(addon).scene.world.environment
    # (an EXR keeps half floats)
    assert saved is not first and np.allclose(saved, 2.0, rtol=1e-3)
    assert read(addon).scene.world.environment is saved


@pytest.mark.skipif("temperature" not in bpy.types.Light.bl_rna.properties, reason="lamp temperature is Blender 4.5+")
def test_lamp_temperature_tints_the_colour(addon):
    lamp_scene()
    light = bpy.data.lights["Lamp"]
    light.use_temperature, light.temperature = True, 3000.0
    color = read(addon).scene.lights[0].color
    assert np.allclose(color, light.temperature_color[:])


def test_camera_at_the_render_resolution(addon):
    lamp_scene()
    camera = bpy.context.scene.camera
    camera.data.sensor_fit, camera.data.lens = 'VERTICAL', 50.0
    camera.data.shift_x = 0.1
    scenes.set_resolution(200, 100)
    bpy.context.scene.render.resolution_percentage = 30
    result = read(addon).scene.camera
    assert (result.pixx, result.pixy) == (60, 30)
    assert result.fov == pytest.approx(2.0 * math.atan(camera.data.sensor_height / (2.0 * 50.0)))
    assert result.sensor_fit == 'VERTICAL' and result.shift_x == pytest.approx(0.1)
    assert np.allclose(result.matrix, np.array(camera.matrix_world), atol=1e-6)


def volume(material, kind='ShaderNodeVolumeAbsorption', **inputs):
    """Connect a new volume shader of `kind` to `material`'s Volume output."""
    nodes = material.node_tree.nodes
    node = nodes.new(kind)
    for socket, value in inputs.items():
        node.inputs[socket].default_value = value
    output = next(n for n in nodes if n.bl_idname == 'ShaderNodeOutputMaterial')
    material.node_tree.links.new(node.outputs[0], output.inputs['Volume'])
    return node


def test_only_principled_bsdf_may_have_dispersion_inputs(addon):
    """Checked on 4.2, 4.5 and 5.3: no Glass or Refraction BSDF has a
    dispersion input (if Blender adds one, export/materials.py should read
    it); a Principled BSDF has OpenPBR's two (5.3) or none (4.2, 4.5)."""
    nodes = scenes.glass_material().node_tree.nodes
    for kind in ('ShaderNodeBsdfGlass', 'ShaderNodeBsdfRefraction'):
        assert not [s.name for s in nodes.new(kind).inputs if "ispersion" in s.name or "Abbe" in s.name]
    principled_inputs = [s.name for s in nodes.new('ShaderNodeBsdfPrincipled').inputs
                         if "ispersion" in s.name or "Abbe" in s.name]
    assert principled_inputs in ([], [addon.export.materials.DISPERSION_SCALE, addon.export.materials.DISPERSION_ABBE])


def test_principled_dispersion_is_the_abbe_number_cycles_renders(addon):
    """Blender 5.3's Principled BSDF disperses by OpenPBR's Transmission
    Dispersion Scale and Abbe Number: Cycles refracts by Cauchy's law with
    the Abbe number abbe / scale (benchmarks/cycles_dispersion.py), none at
    scale 0 or an Abbe number not above 0. The material's dispersion wins
    over the object's Abbe Number, with a warning naming both where they
    differ; the object's stays for glass whose material has none. A linked
    input is read at its own value, with a warning."""
    materials = addon.export.materials
    probe = scenes.glass_material("Probe").node_tree.nodes.new('ShaderNodeBsdfPrincipled')
    if materials.DISPERSION_SCALE not in probe.inputs:
        pytest.skip(f"Blender {bpy.app.version_string}'s Principled BSDF has no {materials.DISPERSION_SCALE}")
    lamp_scene()
    cases = {"Halved": (0.5, 20.0, 0.0), "Clear": (0.0, 20.0, 0.0), "ObjectOnly": (0.0, 20.0, 55.0),
             "Both": (1.0, 30.0, 55.0), "Agree": (1.0, 40.0, 40.0), "Negative": (1.0, -5.0, 0.0),
             "Linked": (0.25, 10.0, 0.0)}
    for k, (name, (scale, abbe, object_abbe)) in enumerate(cases.items()):
        material = principled(name, **{"Transmission Weight": 1.0, "Roughness": 0.0, materials.DISPERSION_SCALE: scale,
                                       materials.DISPERSION_ABBE: abbe})
        ob = scenes.add_sphere(0.1, (0.3 * k - 1.0, 0.0, 0.5), material, name=name, segments=8, rings=4)
        ob.caustic.abbe = object_abbe
    linked = bpy.data.materials["Linked"].node_tree
    linked.links.new(linked.nodes.new('ShaderNodeValue').outputs[0],
                     linked.nodes["Principled BSDF"].inputs[materials.DISPERSION_SCALE])
    result = read(addon)
    abbe = {o.name: o.material.abbe for o in result.scene.objects if o.name in cases}
    assert abbe == {"Halved": 40.0, "Clear": math.inf, "ObjectOnly": 55.0, "Both": 30.0, "Agree": 40.0,
                    "Negative": math.inf, "Linked": 40.0}
    conflicts = [w for w in result.warnings if "differs from the dispersion" in w]
    assert conflicts == ["'Both': its Abbe Number 55 differs from the dispersion of its material 'Both' (Abbe "
                         "Number 30, its Transmission Dispersion Abbe Number over its Scale); the material's is used"]
    assert (f"material 'Linked': its {materials.DISPERSION_SCALE} comes from other nodes; the unconnected value "
            "is used") in result.warnings


def test_volume_absorption_abbe_and_colour_at_distance(addon, reports):
    lamp_scene()
    tinted = scenes.glass_material("Tinted")
    volume(tinted, Color=(0.5, 0.8, 1.0, 1.0), Density=2.0)
    scenes.add_sphere(0.3, (1.0, 0.0, 0.5), tinted, name="Tinted", segments=8, rings=4)
    gem = scenes.add_sphere(0.3, (-1.0, 0.0, 0.5), scenes.glass_material("Gem", ior=2.42), name="Gem",
                            segments=8, rings=4)
    gem.caustic.abbe = 55.0
    gem.caustic.absorption_from = 'COLOR'
    gem.caustic.absorption_color, gem.caustic.absorption_distance = (0.9, 0.6, 0.3), 0.05
    smoke = scenes.glass_material("Smoky")
    volume(smoke, 'ShaderNodeVolumePrincipled')
    scenes.add_sphere(0.3, (0.0, 1.0, 0.5), smoke, name="Smoky", segments=8, rings=4)
    result = read(addon)
    names = {o.name: o.material for o in result.scene.objects}
    # Cycles: sigma_a = density * (1 - colour) per metre
    np.testing.assert_allclose(names["Tinted"].absorption, (1.0, 0.4, 0.0), rtol=1e-6)
    assert names["Tinted"].abbe == math.inf
    assert names["Gem"].abbe == 55.0 and names["Gem"].ior == pytest.approx(2.42)
    np.testing.assert_allclose(np.exp(-names["Gem"].absorption * 0.05), (0.9, 0.6, 0.3), rtol=1e-6)
    np.testing.assert_allclose(names["Smoky"].absorption, 0.0)
    assert any("material 'Smoky': a 'Principled Volume' volume is not understood" in w for w in result.warnings)


def test_ray_visibility_and_holdouts_are_read_as_cycles_reads_them(addon):
    lamp_scene()
    glass = scenes.glass_material()

    def ball(name, x, collection=None):
        ob = scenes.add_sphere(0.2, (x, 0.0, 0.5), glass, name=name, segments=8, rings=4)
        if collection is not None:
            collection.objects.link(ob)
            bpy.context.scene.collection.objects.unlink(ob)
        return ob

    def collection(name):
        made = bpy.data.collections.new(name)
        bpy.context.scene.collection.children.link(made)
        return made, bpy.context.view_layer.layer_collection.children[name]

    shy = ball("Shy", -1.5)
    shy.visible_camera = shy.visible_shadow = shy.visible_diffuse = False
    ball("Held", -1.0).is_holdout = True
    cutouts, cutouts_layer = collection("Cutouts")
    ball("InHoldout", -0.5, cutouts)
    cutouts_layer.holdout = True
    sideline, sideline_layer = collection("Sideline")
    ball("Aside", 0.0, sideline)
    sideline_layer.indirect_only = True
    source, source_layer = collection("Source")
    ball("Piece", 0.5, source)
    source_layer.exclude = True
    instancer = bpy.data.objects.new("Instancer", None)
    instancer.instance_type, instancer.instance_collection = 'COLLECTION', source
    instancer.visible_glossy = False
    bpy.context.scene.collection.objects.link(instancer)
    result = read(addon)
    seen = {result.sources[o.name] if o.name in result.instanced else o.name: o.visibility
            for o in result.scene.objects}
    Visibility = addon.caustic_addon.Visibility
    assert seen == {"Floor": Visibility(), "Shy": Visibility(camera=False, shadow=False),
                    "Held": Visibility(holdout=True), "InHoldout": Visibility(holdout=True),
                    "Aside": Visibility(camera=False), "Piece": Visibility(glossy=False)}
    assert ("'Shy': its Diffuse ray visibility is off, which hides it from Cycles' diffuse bounces and the caustics "
            "they find through it; the caustic render's light goes from the lights, so it still casts its caustic"
            ) in result.warnings


def test_an_instancers_instances_of_one_mesh_are_one_object_with_a_copy_at_each_point(addon):
    lamp_scene()
    holder = scenes.scatter(3, 0.5)
    holder.location, holder.rotation_euler = (1.0, 0.0, 0.5), (0.0, 0.0, math.pi / 2)
    result = read(addon)
    balls = engine_object(result, "Scatter [Scatter]")
    assert balls.copies == 9 and balls.name in result.instanced and balls.is_transparent
    centres = balls.mesh.vertices.reshape(9, -1, 3).mean(axis=1)
    grid = np.stack(np.meshgrid([-0.5, 0.0, 0.5], [-0.5, 0.0, 0.5]), axis=-1).reshape(-1, 2)
    rotated = grid @ np.array([[0.0, 1.0], [-1.0, 0.0]])  # a quarter turn about z
    expected = np.column_stack([rotated + [1.0, 0.0], np.full(9, 0.5)])
    def in_order(points):  # rounded first, so that float32's last digits do not change the order
        return np.sort(np.round(points, 6).view('f8,f8,f8'), axis=0).view(float).reshape(9, 3)

    assert np.allclose(in_order(centres), in_order(expected), atol=1e-6)
    assert np.allclose(balls.instances.transforms[:, :3, 3], centres, atol=1e-6)


def test_instances_scaled_to_0_are_left_out_by_name(addon):
    lamp_scene()
    holder = scenes.scatter(2, 0.5)
    tree = holder.modifiers[0].node_group
    placed = tree.nodes['Instance on Points']
    index = tree.nodes.new('GeometryNodeInputIndex')
    flat = tree.nodes.new('ShaderNodeMath')
    flat.operation = 'GREATER_THAN'
    flat.inputs[1].default_value = 0.5  # the first point's instance gets scale 0
    tree.links.new(index.outputs[0], flat.inputs[0])
    tree.links.new(flat.outputs[0], placed.inputs['Scale'])
    result = read(addon)
    assert engine_object(result, "Scatter [Scatter]").copies == 3
    assert "'Scatter [Scatter]': 1 of its 4 instances are scaled to 0 along an axis: they were left out" \
        in result.warnings


def test_textured_instances_are_read_one_by_one_and_the_others_together(addon):
    lamp_scene()
    scenes.scatter(2, 0.5, name="Gems")
    cubes = scenes.scatter(2, 0.5, 'GeometryNodeMeshCube', name="Cubes")
    cubes.location.z = 1.0
    textured = scenes.diffuse_material("Printed")
    nodes = textured.node_tree.nodes
    image = nodes.new('ShaderNodeTexImage')
    image.image = bpy.data.images.new("Print", 4, 4)
    textured.node_tree.links.new(image.outputs['Color'], nodes['Diffuse BSDF'].inputs['Color'])
    cubes.modifiers[0].node_group.nodes['Set Material'].inputs['Material'].default_value = textured
    result = read(addon)
    assert engine_object(result, "Gems [Gems]").copies == 4
    printed = [o for o in result.scene.objects if o.name.startswith("Cubes [Cubes #")]
    assert len(printed) == 4 and all(o.copies == 1 and o.name in result.instanced for o in printed)


def test_two_meshes_one_instancer_places_are_two_objects(addon):
    lamp_scene()
    holder = scenes.scatter(2, 0.5)
    tree = holder.modifiers[0].node_group
    nodes, links = tree.nodes, tree.links
    cube, chrome, placed, joined = (nodes.new(kind) for kind in (
        'GeometryNodeMeshCube', 'GeometryNodeSetMaterial', 'GeometryNodeInstanceOnPoints', 'GeometryNodeJoinGeometry'))
    chrome.inputs['Material'].default_value = scenes.glossy_material()
    links.new(nodes['Grid'].outputs['Mesh'], placed.inputs['Points'])
    links.new(cube.outputs['Mesh'], chrome.inputs['Geometry'])
    links.new(chrome.outputs['Geometry'], placed.inputs['Instance'])
    links.new(nodes['Instance on Points'].outputs['Instances'], joined.inputs[0])
    links.new(placed.outputs['Instances'], joined.inputs[0])
    links.new(joined.outputs[0], nodes['Group Output'].inputs['Geometry'])
    result = read(addon)
    names = sorted(o.name for o in result.scene.objects if o.name.startswith("Scatter"))
    assert names == ["Scatter [Scatter] #1", "Scatter [Scatter] #2"]
    assert sorted(len(engine_object(result, name).mesh.triangles) // 4 for name in names) == [12, 20]


def test_instanced_receivers_are_one_object_each_for_maps_of_their_own(addon):
    lamp_scene()
    scenes.scatter(2, 0.5, 'GeometryNodeMeshCube', material=scenes.diffuse_material("Pebble"), name="Pebbles")
    result = read(addon)
    pebbles = [o for o in result.scene.objects if o.name.startswith("Pebbles [Pebbles #")]
    assert len(pebbles) == 4 and all(o.is_receiver and o.copies == 1 for o in pebbles)
