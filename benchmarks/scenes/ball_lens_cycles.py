"""The ball lens (ball_lens.scene()) built in Blender for Cycles, with the
settings that make Cycles' pixels comparable to the engine's exact
reference, and one Cycles render read back as linear radiance: shared by
cycles_accuracy.py, sized_lamps.py and rough_glass.py. Needs bpy.

The very triangles of ball_lens.scene() (the sphere's unit vertex normals
as custom normals, to Blender's precision of 3e-4), the same floor, lamp
and camera. The floor is white (albedo 1) to camera rays and black to
every other ray, so that a pixel in the shadow disc is the caustic alone;
the world is black; Cycles runs on the CPU with a box pixel filter one
pixel wide, no denoiser, no clamping, no adaptive sampling and 16
transmission bounces, into a 32-bit EXR.
"""

from __future__ import annotations

import os
import time

import bpy
import numpy as np
from mathutils import Matrix

from benchmarks.scenes import ball_lens


def _floor_material():
    """Diffuse BSDF of colour 1 for camera rays, black for all others."""
    material = bpy.data.materials.new("Floor")
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    white, black = nodes.new('ShaderNodeBsdfDiffuse'), nodes.new('ShaderNodeBsdfDiffuse')
    white.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1.0)
    black.inputs['Color'].default_value = (0.0, 0.0, 0.0, 1.0)
    mix, path = nodes.new('ShaderNodeMixShader'), nodes.new('ShaderNodeLightPath')
    links.new(path.outputs['Is Camera Ray'], mix.inputs['Fac'])
    links.new(black.outputs[0], mix.inputs[1])
    links.new(white.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    return material


def _glass_material():
    """Glass BSDF, IOR 1.5, roughness 0 (Cycles renders it as the ideal
    specular interface that Blender's old 'Sharp' distribution was)."""
    material = bpy.data.materials.new("Glass")
    nodes = material.node_tree.nodes
    nodes.clear()
    glass = nodes.new('ShaderNodeBsdfGlass')
    glass.inputs['IOR'].default_value = ball_lens.IOR
    glass.inputs['Roughness'].default_value = 0.0
    material.node_tree.links.new(glass.outputs[0], nodes.new('ShaderNodeOutputMaterial').inputs['Surface'])
    return material


def _add_mesh(ob, material):
    """A bpy object of the engine's Object `ob` (world-space triangles), its
    smooth normals set to the engine's vertex normals."""
    mesh = bpy.data.meshes.new(ob.name)
    mesh.from_pydata(ob.mesh.vertices.tolist(), [], ob.mesh.triangles.tolist())
    if ob.mesh.corner_normals is not None:
        normals = np.zeros_like(ob.mesh.vertices)
        normals[ob.mesh.triangles.ravel()] = ob.mesh.corner_normals.reshape(-1, 3)
        mesh.shade_smooth()
        mesh.normals_split_custom_set_from_vertices(normals.tolist())
    mesh.materials.append(material)
    obj = bpy.data.objects.new(ob.name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _add_lamp(light):
    """A point lamp of the engine's PointLight `light`: W, radius 0."""
    data = bpy.data.lights.new("Lamp", 'POINT')
    data.energy = light.power
    data.shadow_soft_size = 0.0
    lamp = bpy.data.objects.new("Lamp", data)
    lamp.location = tuple(light.position)
    bpy.context.scene.collection.objects.link(lamp)
    return lamp


def _add_camera(camera):
    """Blender's camera for the engine's `camera`: same matrix, FOV across the width."""
    data = bpy.data.cameras.new("Camera")
    data.sensor_fit = 'HORIZONTAL'
    data.angle = camera.fov
    data.clip_start = camera.clip_start
    obj = bpy.data.objects.new("Camera", data)
    obj.matrix_world = Matrix(camera.matrix.tolist())
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _black_world():
    """A world that sends no light (a new one's Background node is grey)."""
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    world.node_tree.nodes['Background'].inputs['Color'].default_value = (0.0, 0.0, 0.0, 1.0)
    return world


def _cycles_settings(scene, width: int, height: int) -> None:
    """Cycles on the CPU, `width` x `height` px, into a 32-bit float EXR (raw
    scene-linear values: the view transform does not touch it)."""
    render, cycles = scene.render, scene.cycles
    render.engine = 'CYCLES'
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100
    render.use_file_extension = False
    render.image_settings.file_format = 'OPEN_EXR'
    render.image_settings.color_depth = '32'
    scene.view_settings.view_transform = 'Standard'
    cycles.device = 'CPU'
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.pixel_filter_type = 'BOX'
    cycles.filter_width = 1.0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.caustics_refractive = True
    cycles.caustics_reflective = True
    cycles.max_bounces = cycles.transmission_bounces = 16


def build_scene():
    """Empty the file and build ball_lens.scene() in it: returns (engine
    scene, {'Floor', 'Glass', 'Lamp'}: bpy objects)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ours = ball_lens.scene()
    scene = bpy.context.scene
    floor_ob, glass_ob = ours.objects
    objects = dict(Floor=_add_mesh(floor_ob, _floor_material()), Glass=_add_mesh(glass_ob, _glass_material()),
                   Lamp=_add_lamp(ours.lights[0]))
    scene.camera = _add_camera(ours.camera)
    scene.world = _black_world()
    _cycles_settings(scene, ours.camera.pixx, ours.camera.pixy)
    return ours, objects


def set_mnee(objects: dict, on: bool) -> None:
    """MNEE caster, receiver and caustics light, all on or all off."""
    objects["Glass"].cycles.is_caustics_caster = on
    objects["Floor"].cycles.is_caustics_receiver = on
    objects["Lamp"].data.cycles.is_caustics_light = on


def render(samples: int, folder: str) -> tuple[np.ndarray, float]:
    """((h,w,3) linear radiance W/(m^2 sr), top row first; seconds of the
    render, its write to an EXR included)."""
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.render.filepath = os.path.join(folder, f"cycles-{samples}.exr")
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - start
    image = bpy.data.images.load(scene.render.filepath)
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    os.remove(scene.render.filepath)
    return pixels.reshape(height, width, 4)[::-1, :, :3], seconds
