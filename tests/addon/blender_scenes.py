"""Test scenes built with bpy: a diffuse plane, a smooth glass sphere, lamps and a camera."""

import os
import time

import bpy
import numpy as np
from mathutils import Vector


def _material(name):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    material.node_tree.nodes.clear()
    return material


def _shader(material, kind):
    nodes = material.node_tree.nodes
    output = nodes.new('ShaderNodeOutputMaterial')
    shader = nodes.new(kind)
    material.node_tree.links.new(shader.outputs[0], output.inputs['Surface'])
    return shader


def diffuse_material(name="Floor", color=(0.8, 0.8, 0.8)):
    material = _material(name)
    _shader(material, 'ShaderNodeBsdfDiffuse').inputs['Color'].default_value = (*color, 1.0)
    return material


def principled_material(name="Floor", color=(0.8, 0.8, 0.8), roughness=0.3, level=0.5):
    material = _material(name)
    shader = _shader(material, 'ShaderNodeBsdfPrincipled')
    shader.inputs['Base Color'].default_value = (*color, 1.0)
    shader.inputs['Roughness'].default_value = roughness
    shader.inputs['Specular IOR Level'].default_value = level
    return material


def glass_material(name="Glass", ior=1.5):
    material = _material(name)
    shader = _shader(material, 'ShaderNodeBsdfGlass')
    shader.inputs['IOR'].default_value = ior
    shader.inputs['Roughness'].default_value = 0.0
    return material


def emission_material(name="Emission", strength=10.0, color=(1.0, 1.0, 1.0)):
    material = _material(name)
    shader = _shader(material, 'ShaderNodeEmission')
    shader.inputs['Color'].default_value = (*color, 1.0)
    shader.inputs['Strength'].default_value = strength
    return material


def glossy_material(name="Mirror", color=(0.9, 0.9, 0.9), roughness=0.0):
    material = _material(name)
    shader = _shader(material, 'ShaderNodeBsdfGlossy')
    shader.inputs['Color'].default_value = (*color, 1.0)
    shader.inputs['Roughness'].default_value = roughness
    return material


def add_plane(size, material, name="Floor"):
    bpy.ops.mesh.primitive_plane_add(size=size, location=(0.0, 0.0, 0.0))
    plane = bpy.context.object
    plane.name = name
    plane.data.materials.append(material)
    return plane


def add_sphere(radius, location, material, name="Ball", segments=64, rings=32):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=radius, location=location)
    sphere = bpy.context.object
    sphere.name = name
    sphere.data.shade_smooth()
    sphere.data.materials.append(material)
    return sphere


def add_point_light(location, power, name="Lamp"):
    light = bpy.data.lights.new(name, 'POINT')
    light.energy = power
    light.shadow_soft_size = 0.0
    lamp = bpy.data.objects.new(name, light)
    lamp.location = location
    bpy.context.scene.collection.objects.link(lamp)
    return lamp


def add_camera(location, target=(0.0, 0.0, 0.0), lens=35.0, name="Camera"):
    camera = bpy.data.objects.new(name, bpy.data.cameras.new(name))
    camera.data.lens = lens
    camera.location = location
    camera.rotation_euler = (Vector(target) - Vector(location)).to_track_quat('-Z', 'Y').to_euler()
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    return camera


def scatter(count, spacing, mesh_node='GeometryNodeMeshIcoSphere', material=None, name="Scatter", size=0.2):
    """A plane whose Geometry Nodes put an instance of one `mesh_node` mesh
    (radius or half size `size`, `material` set on it) on each point of a
    count x count grid `spacing` apart: the grid's centre at the plane's origin."""
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    holder = bpy.context.object
    holder.name = name
    tree = bpy.data.node_groups.new(name, 'GeometryNodeTree')
    tree.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    nodes, links = tree.nodes, tree.links
    points = nodes.new('GeometryNodeMeshGrid')
    points.inputs['Size X'].default_value = points.inputs['Size Y'].default_value = spacing * (count - 1)
    points.inputs['Vertices X'].default_value = points.inputs['Vertices Y'].default_value = count
    shape = nodes.new(mesh_node)
    extent = next(s for s in shape.inputs if s.name in ("Radius", "Size"))
    extent.default_value = size if extent.type == 'VALUE' else (2 * size,) * 3
    coloured = nodes.new('GeometryNodeSetMaterial')
    coloured.inputs['Material'].default_value = material or glass_material()
    placed = nodes.new('GeometryNodeInstanceOnPoints')
    output = nodes.new('NodeGroupOutput')
    links.new(shape.outputs['Mesh'], coloured.inputs['Geometry'])
    links.new(points.outputs['Mesh'], placed.inputs['Points'])
    links.new(coloured.outputs['Geometry'], placed.inputs['Instance'])
    links.new(placed.outputs['Instances'], output.inputs['Geometry'])
    holder.modifiers.new(name, 'NODES').node_group = tree
    return holder


def world_nodes(name="World"):
    """A new world `name` of the scene, its node tree and Background node."""
    world = bpy.data.worlds.new(name)
    bpy.context.scene.world = world
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    return world, tree, next(n for n in tree.nodes if n.bl_idname == 'ShaderNodeBackground')


def set_resolution(width, height):
    render = bpy.context.scene.render
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100


def ball_lens_scene(width=160, height=120, lamp_rays=100_000, segments=64, rings=32):
    """The ball lens of the engine's reference, at half scale: a glass sphere
    (radius 0.5, IOR 1.5) centred 0.75 above a 6 m diffuse floor, lit by a
    point lamp straight above at 3 m, seen obliquely."""
    scene = bpy.context.scene
    floor = add_plane(6.0, diffuse_material())
    ball = add_sphere(0.5, (0.0, 0.0, 0.75), glass_material(), segments=segments, rings=rings)
    lamp = add_point_light((0.0, 0.0, 3.0), 1000.0)
    camera = add_camera((0.0, -4.5, 3.5), target=(0.0, 0.3, 0.0))
    set_resolution(width, height)
    scene.caustic.lamp_rays = lamp_rays
    scene.caustic.density = 'ADAPTIVE'
    return dict(floor=floor, ball=ball, lamp=lamp, camera=camera)


def ring_scene(width=64, height=48, lamp_rays=200_000):
    """A coffee cup without its coffee: an open Glossy ring (radius 0.5,
    height 0.3) on a 4 m diffuse floor, a 100 W point lamp inside it at
    (0.3, 0, 1), seen from above. The ring's nephroid caustic has its cusp at
    x = -R d / (2d + R) = -0.136 on the floor."""
    scene = bpy.context.scene
    floor = add_plane(4.0, diffuse_material())
    bpy.ops.mesh.primitive_cylinder_add(vertices=256, radius=0.5, depth=0.3, end_fill_type='NOTHING',
                                        location=(0.0, 0.0, 0.15))
    ring = bpy.context.object
    ring.name = "Ring"
    ring.data.shade_smooth()
    ring.data.materials.append(glossy_material("Chrome"))
    lamp = add_point_light((0.3, 0.0, 1.0), 100.0)
    camera = add_camera((0.0, -0.6, 2.5), target=(0.0, 0.0, 0.0))
    set_resolution(width, height)
    scene.caustic.lamp_rays = lamp_rays
    scene.caustic.density = 'ADAPTIVE'
    return dict(floor=floor, ring=ring, lamp=lamp, camera=camera)


def glass_ball_under_a_softbox(width=80, height=60):
    """A smooth glass ball (radius 0.5) in a black world, a 0.5 m square
    lamp of 200 W up and to the front left, seen from the front."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    add_plane(0.01, diffuse_material()).location = (0.0, 0.0, -30.0)
    add_sphere(0.5, (0.0, 0.0, 0.5), glass_material(), segments=96, rings=48)
    bpy.ops.object.shade_smooth()
    light = bpy.data.lights.new("Softbox", 'AREA')
    light.energy, light.size = 200.0, 0.5
    lamp = bpy.data.objects.new("Softbox", light)
    lamp.location = (-1.0, -1.0, 2.0)
    lamp.rotation_euler = Vector((-1.0, -1.0, 1.5)).normalized().to_track_quat('Z', 'Y').to_euler()
    bpy.context.scene.collection.objects.link(lamp)
    add_camera((0.0, -3.0, 1.6), target=(0.0, 0.0, 0.45), lens=50.0)
    set_resolution(width, height)
    return lamp


def glass_ball_under_an_emitting_plane(width=80, height=60, strength=12.0):
    """A product shot: a smooth glass ball (radius 0.5) on a white floor in
    a black world, under a 1 m plane of Emission `strength` (a softbox
    built as a mesh) up and behind to the left, facing the ball, which
    throws its caustic forward; seen from the front. Returns the plane."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    add_plane(10.0, diffuse_material())
    add_sphere(0.5, (0.0, 0.0, 0.5), glass_material(), segments=96, rings=48)
    bpy.ops.object.shade_smooth()
    softbox = add_plane(1.0, emission_material(strength=strength), name="Softbox")
    softbox.location = (-0.7, 1.0, 2.0)
    softbox.rotation_euler = Vector((-0.7, 1.0, 1.5)).normalized().to_track_quat('Z', 'Y').to_euler()
    add_camera((0.0, -3.5, 1.8), target=(0.0, 0.0, 0.35), lens=40.0)
    set_resolution(width, height)
    return softbox


def glossy_floor_under_a_softbox(width=160, height=120, roughness=0.1):
    """A dark Principled floor of `roughness` in a black world, a 1 m
    square lamp of 200 W 1.5 m above it, tilted toward the camera, whose
    highlight the floor shows; seen from the front. Returns the lamp."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    add_plane(10.0, principled_material(color=(0.1, 0.1, 0.1), roughness=roughness))
    light = bpy.data.lights.new("Softbox", 'AREA')
    light.energy, light.size = 200.0, 1.0
    lamp = bpy.data.objects.new("Softbox", light)
    lamp.location = (0.0, 1.5, 1.5)
    lamp.rotation_euler = Vector((0.0, 1.0, 2.0)).normalized().to_track_quat('Z', 'Y').to_euler()
    bpy.context.scene.collection.objects.link(lamp)
    add_camera((0.0, -3.0, 1.2), target=(0.0, 0.8, 0.0), lens=35.0)
    set_resolution(width, height)
    return lamp


def pixels_of(name):
    """(h, w, 4) float32 pixels of image `name`, row 0 at the top."""
    image = bpy.data.images[name]
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(h, w, 4)[::-1]


def warm_caustic_render() -> tuple[np.ndarray, np.ndarray, float]:
    """(image, caustic pass (h,w,3) float64, seconds) of Render run twice:
    the second, with kernels and BVH warm, is timed."""
    assert bpy.ops.caustic.render() == {'FINISHED'}
    clock = time.perf_counter()
    assert bpy.ops.caustic.render() == {'FINISHED'}
    seconds = time.perf_counter() - clock
    return (pixels_of("Caustic Render")[..., :3].astype(np.float64),
            pixels_of("Caustic Render Caustic")[..., :3].astype(np.float64), seconds)


def cycles_render(folder, samples=512, specular_bounces=0) -> np.ndarray:
    """(h, w, 4) float64 RGBA, row 0 at the top: the scene rendered by Cycles
    on the CPU with no diffuse bounces (direct light only, what a Whitted eye
    pass computes) and up to `specular_bounces` glossy and transmission
    bounces, box-filtered over each pixel, neither denoised nor adaptive."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.use_denoising = 'CPU', samples, False
    cycles.max_bounces, cycles.diffuse_bounces = specular_bounces, 0
    cycles.glossy_bounces = cycles.transmission_bounces = specular_bounces
    cycles.pixel_filter_type, cycles.filter_width = 'BOX', 1.0
    if hasattr(cycles, "use_adaptive_sampling"):
        cycles.use_adaptive_sampling = False
    return rendered_pixels(folder)


def cycles_caustics(folder, samples: int, seed: int, specular_bounces: int = 8, diffuse_bounces: int = 1) -> np.ndarray:
    """(h, w, 3) float64 RGB, row 0 at the top: the scene rendered by Cycles
    on the CPU with what a caustic needs, one diffuse bounce (the floor's
    light through glass; 0: direct light only, which Cycles converges on),
    `specular_bounces` glossy and transmission bounces, refractive and
    reflective caustics on and no clamp, box-filtered over each pixel,
    neither denoised nor adaptive."""
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    settings = scene.cycles
    settings.device, settings.samples, settings.seed, settings.use_denoising = 'CPU', samples, seed, False
    settings.max_bounces, settings.diffuse_bounces = specular_bounces + diffuse_bounces, diffuse_bounces
    settings.glossy_bounces = settings.transmission_bounces = specular_bounces
    settings.caustics_refractive = settings.caustics_reflective = True
    settings.sample_clamp_indirect, settings.blur_glossy = 0.0, 0.0
    settings.pixel_filter_type, settings.filter_width = 'BOX', 1.0
    settings.use_adaptive_sampling = False
    return rendered_pixels(folder)[..., :3]


def timed_cycles_caustics(folder, samples: int, seed: int, specular_bounces: int = 8,
                          diffuse_bounces: int = 1) -> tuple[np.ndarray, float]:
    """(cycles_caustics' image, the seconds it took)."""
    clock = time.perf_counter()
    image = cycles_caustics(folder, samples, seed, specular_bounces, diffuse_bounces)
    return image, time.perf_counter() - clock


def pixel_rays(pixx: int, pixy: int) -> tuple[np.ndarray, np.ndarray]:
    """(origin (3,), dirs (pixy, pixx, 3)) of the scene camera's rays
    through each pixel's centre, row 0 at the top, dirs not normalized."""
    scene = bpy.context.scene
    camera = scene.camera
    top_right, bottom_right, bottom_left, top_left = (np.array(c) for c in camera.data.view_frame(scene=scene))
    u = ((np.arange(pixx) + 0.5) / pixx)[None, :, None]
    v = ((np.arange(pixy) + 0.5) / pixy)[:, None, None]
    local = (1 - v) * ((1 - u) * top_left + u * top_right) + v * ((1 - u) * bottom_left + u * bottom_right)
    matrix = np.array(camera.matrix_world)
    return matrix[:3, 3], local @ matrix[:3, :3].T


def rendered_pixels(folder) -> np.ndarray:
    """(h, w, 4) float64 RGBA, row 0 at the top: the scene rendered as it is
    set up, through a float EXR in `folder`."""
    scene = bpy.context.scene
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = 'OPEN_EXR', '32'
    scene.render.filepath, scene.render.use_file_extension = os.path.join(folder, "cycles.exr"), False
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(h, w, 4)[::-1].astype(np.float64)


def compositor_tree(scene, name):
    """An empty compositor node tree, `name`, that renders use: Blender 5.3
    keeps it in a compositor effect, 5.0-5.2 in compositing_node_group, 4.x
    in scene.node_tree."""
    if hasattr(scene, "compositor_effects"):
        effect = scene.compositor_effects.new(name=name)
        effect.node_group = bpy.data.node_groups.new(name, 'CompositorNodeTree')
        return effect.node_group
    if bpy.app.version >= (5, 0, 0):
        scene.compositing_node_group = bpy.data.node_groups.new(name, 'CompositorNodeTree')
        return scene.compositing_node_group
    scene.use_nodes = True
    scene.node_tree.nodes.clear()
    return scene.node_tree
