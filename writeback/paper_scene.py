"""Blender data for the paper's scene, built from the engine's own meshes: a
mesh that reads back as the engine built it, and a one-shader node material."""

import bpy
import numpy as np

from ..caustic_addon import Mesh


def blender_mesh(name: str, mesh: Mesh, origin: np.ndarray):
    """A new Blender mesh of the engine's `mesh` moved by -`origin (3,)`:
    corners at one position welded into one vertex, the engine's corner
    normals as custom normals and its corner UVs as the UV map, so the
    add-on reads back the triangles and normals the engine built."""
    _, first, weld = np.unique(np.round(mesh.vertices, 9), axis=0, return_index=True, return_inverse=True)
    data = bpy.data.meshes.new(name)
    data.from_pydata(mesh.vertices[first] - origin, [], weld.reshape(-1)[mesh.triangles])
    data.shade_smooth()
    data.normals_split_custom_set(mesh.corner_normals.reshape(-1, 3))
    if mesh.corner_uvs is not None:
        data.uv_layers.new(name="UVMap").data.foreach_set("uv", mesh.corner_uvs.reshape(-1))
    return data


def node_material(name: str, kind: str, **inputs):
    """A new node material: one `kind` shader with `inputs` into the output."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    shader = nodes.new(kind)
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    output = nodes.new('ShaderNodeOutputMaterial')
    output.location = (300.0, 0.0)
    material.node_tree.links.new(shader.outputs[0], output.inputs['Surface'])
    return material
