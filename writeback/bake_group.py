"""The node group a bake adds to a receiver's material: the illumination map
looked up at the shading point and added to the material's own shader as
emission of radiance E * albedo / pi, the albedo from the material's own
colour nodes where it has them, so EEVEE and the Cycles viewport show the
caustic. Under a Principled BSDF's layers the albedo is times the share
of the diffuse base they leave toward the eye, as the eye pass
shades it: a Color Ramp of it over Layer Weight's Facing, 1 - |cos|, which
the ramp interpolates linearly between SHARE_STOPS view cosines. `unwire`
takes out exactly what `wire` put in."""

from __future__ import annotations

import math
import re

import bpy
import numpy as np
from mathutils import Matrix

from ..caustic_addon import ImageFrame
from ..export.materials import BAKE_TAG as TAG
from .box_chart_nodes import box_chart_vector

NODE_NAME = "Caustic Bake"
# A Color Ramp's most elements.
SHARE_STOPS = 32


def _chart_coordinates(nodes, links, frame: ImageFrame, uv_layer: str):
    """A Mapping node that turns the shading point into the [0,1]^2
    coordinates of the image that `frame` places: from the world position,
    from the UV map `uv_layer`, or from the box chart the engine made for a
    curved receiver without one, as the frame says."""
    mapping = nodes.new('ShaderNodeMapping')
    mapping.vector_type = 'TEXTURE'
    if frame.coordinates == 'POSITION':
        source = nodes.new('ShaderNodeNewGeometry')
        links.new(source.outputs['Position'], mapping.inputs['Vector'])
    elif frame.coordinates == 'BOX':
        source, chart = box_chart_vector(nodes, links, frame)
        links.new(chart, mapping.inputs['Vector'])
    else:
        source = nodes.new('ShaderNodeUVMap')
        source.uv_map = uv_layer
        links.new(source.outputs['UV'], mapping.inputs['Vector'])
    mapping.inputs['Location'].default_value = frame.location.tolist()
    mapping.inputs['Rotation'].default_value = Matrix(frame.rotation.tolist()).to_euler('XYZ')
    mapping.inputs['Scale'].default_value = frame.scale.tolist()
    return source, mapping


def _view_share(nodes, links, share):
    """A Color Ramp node giving the diffuse share `share(cos_v (k,)) -> (k,3)`
    at each shading point, from Layer Weight's Facing (blend 0.5: 1 - |cos_v|,
    Cycles' svm_node_layer_weight)."""
    facing = nodes.new('ShaderNodeLayerWeight')
    facing.inputs['Blend'].default_value = 0.5
    ramp = nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.interpolation = 'LINEAR'
    positions = np.linspace(0.0, 1.0, SHARE_STOPS)
    values = share(1.0 - positions)
    elements = ramp.color_ramp.elements
    elements[0].position, elements[-1].position = 0.0, 1.0
    for position in positions[1:-1]:
        elements.new(float(position))
    for element, value in zip(sorted(elements, key=lambda e: e.position), values):
        element.color = (*(float(c) for c in value), 1.0)
    links.new(facing.outputs['Facing'], ramp.inputs['Fac'])
    return facing, ramp


def _selected(nodes, links, selector: tuple[str, int]):
    """A Math node that is 1 on objects whose custom property selector[0]
    is selector[1], else 0 (an Attribute node of the object)."""
    attribute, compare = nodes.new('ShaderNodeAttribute'), nodes.new('ShaderNodeMath')
    attribute.attribute_type, attribute.attribute_name = 'OBJECT', selector[0]
    compare.operation = 'COMPARE'
    compare.inputs[1].default_value, compare.inputs[2].default_value = float(selector[1]), 0.5
    links.new(attribute.outputs['Fac'], compare.inputs[0])
    return attribute, compare


def make_group(name: str, image, imap, albedo: np.ndarray, uv_layer: str, share=None, selector=None):
    """A shader node group: Shader and Albedo in, Shader out = in + emission
    of the map `image` (irradiance, W/m^2) times Albedo / pi; Albedo is
    `albedo (3,)` unless `wire` links the material's own colour to it, and
    is times `share(cos_v (k,)) -> (k,3)` toward the eye if given (a
    Principled BSDF's diffuse share under its layers). With a
    `selector` (custom property, number) the emission shows only on the
    objects whose property is that number."""
    group = bpy.data.node_groups.new(name, 'ShaderNodeTree')
    group[TAG] = True
    group.interface.new_socket(name="Shader", in_out='INPUT', socket_type='NodeSocketShader')
    colour = group.interface.new_socket(name="Albedo", in_out='INPUT', socket_type='NodeSocketColor')
    colour.default_value = (*np.asarray(albedo, dtype=float).tolist(), 1.0)
    group.interface.new_socket(name="Shader", in_out='OUTPUT', socket_type='NodeSocketShader')
    nodes, links = group.nodes, group.links
    inputs, outputs = nodes.new('NodeGroupInput'), nodes.new('NodeGroupOutput')
    source, mapping = _chart_coordinates(nodes, links, imap.image_frame(), uv_layer)
    texture = nodes.new('ShaderNodeTexImage')
    texture.image, texture.interpolation, texture.extension = image, 'Linear', 'CLIP'
    shaded, radiance = nodes.new('ShaderNodeVectorMath'), nodes.new('ShaderNodeVectorMath')
    shaded.operation, radiance.operation = 'MULTIPLY', 'SCALE'
    radiance.inputs['Scale'].default_value = 1.0 / math.pi
    emission, add = nodes.new('ShaderNodeEmission'), nodes.new('ShaderNodeAddShader')
    links.new(mapping.outputs['Vector'], texture.inputs['Vector'])
    links.new(texture.outputs['Color'], shaded.inputs[0])
    links.new(inputs.outputs['Albedo'], shaded.inputs[1])
    if share is None:
        links.new(shaded.outputs['Vector'], radiance.inputs[0])
    else:
        facing, ramp = _view_share(nodes, links, share)
        viewed = nodes.new('ShaderNodeVectorMath')
        viewed.operation = 'MULTIPLY'
        links.new(shaded.outputs['Vector'], viewed.inputs[0])
        links.new(ramp.outputs['Color'], viewed.inputs[1])
        links.new(viewed.outputs['Vector'], radiance.inputs[0])
        facing.location, ramp.location, viewed.location = (220.0, -400.0), (440.0, -400.0), (660.0, -400.0)
    if selector is None:
        links.new(radiance.outputs['Vector'], emission.inputs['Color'])
    else:
        attribute, compare = _selected(nodes, links, selector)
        only = nodes.new('ShaderNodeVectorMath')
        only.operation = 'SCALE'
        links.new(radiance.outputs['Vector'], only.inputs[0])
        links.new(compare.outputs['Value'], only.inputs['Scale'])
        links.new(only.outputs['Vector'], emission.inputs['Color'])
        attribute.location, compare.location, only.location = (660.0, 250.0), (880.0, 250.0), (1100.0, 250.0)
    links.new(inputs.outputs['Shader'], add.inputs[0])
    links.new(emission.outputs['Emission'], add.inputs[1])
    links.new(add.outputs['Shader'], outputs.inputs[0])
    for column, node in enumerate((source, mapping, texture, shaded, radiance, emission, add, outputs)):
        node.location = (220.0 * column, 0.0)
    inputs.location = (440.0, -200.0)
    return group


def _texture_node(group):
    """The Image Texture node of a bake's node group."""
    return next(node for node in group.nodes if node.bl_idname == 'ShaderNodeTexImage')


def _group_image(group):
    """The map image a bake's node group shows."""
    return _texture_node(group).image


def follow_frames(group, first: int, count: int) -> None:
    """Make the group's image, a sequence of `count` files numbered by
    frame from `first`, show the file of the current frame: Blender reads
    file number (frame - frame_start + 1 + frame_offset), held at the ends."""
    user = _texture_node(group).image_user
    user.frame_start, user.frame_offset, user.frame_duration = first, first - 1, count
    user.use_cyclic, user.use_auto_refresh = False, True


def files_on_disk(material) -> list[str]:
    """The files (absolute) of the image sequences that the material's baked
    nodes show: the first file's number, the last digits of its name, counted
    on by the sequence's length with the same padding."""
    files = []
    for node in baked_nodes(material):
        texture = _texture_node(node.node_tree)
        if texture.image is None or texture.image.source != 'SEQUENCE':
            continue
        head, digits, tail = re.match(r"(.*?)(\d+)(\D*)$", bpy.path.abspath(texture.image.filepath)).groups()
        user = texture.image_user
        files += [f"{head}{number:0{len(digits)}d}{tail}"
                  for number in range(int(digits), int(digits) + user.frame_duration)]
    return files


def material_output(material):
    """The output node that Cycles uses, or None."""
    return material.node_tree.get_output_node('CYCLES')


def wire(material, group, albedo_socket=None) -> None:
    """Put a node of `group` between the material's surface shader and its
    output; what drives `albedo_socket` (the shader's colour), if anything,
    drives the group's Albedo too, so a texture shades the caustic."""
    tree = material.node_tree
    output = material_output(material)
    node = tree.nodes.new('ShaderNodeGroup')
    node.node_tree, node.name, node.label = group, NODE_NAME, NODE_NAME
    node.location = (output.location.x, output.location.y + 200.0)
    surface = output.inputs['Surface']
    if surface.is_linked:
        link = surface.links[0]
        source = link.from_socket
        tree.links.remove(link)
        tree.links.new(source, node.inputs['Shader'])
    if albedo_socket is not None and albedo_socket.is_linked:
        tree.links.new(albedo_socket.links[0].from_socket, node.inputs['Albedo'])
    tree.links.new(node.outputs['Shader'], surface)


def baked_nodes(material) -> list:
    """The material's nodes that a bake added."""
    if material.node_tree is None:
        return []
    return [node for node in material.node_tree.nodes
            if node.bl_idname == 'ShaderNodeGroup' and node.node_tree is not None and TAG in node.node_tree]


def unwire(material) -> int:
    """Remove the bake's nodes from `material`, reconnect what they sat
    between, and delete their node groups and images once unused. Returns how
    many nodes were removed."""
    tree = material.node_tree
    removed = baked_nodes(material)
    for node in removed:
        group = node.node_tree
        source = node.inputs['Shader'].links[0].from_socket if node.inputs['Shader'].is_linked else None
        targets = [link.to_socket for link in node.outputs[0].links]
        tree.nodes.remove(node)
        if source is not None:
            for target in targets:
                tree.links.new(source, target)
        if _unused(group):
            image = _group_image(group)
            bpy.data.node_groups.remove(group)
            if image is not None and image.users == 0:
                bpy.data.images.remove(image)
    return len(removed)


def _unused(group) -> bool:
    """No data-block refers to node `group`, whatever its user count says:
    Blender 4.2's Full Copy of a scene leaves a bake's group one user too many."""
    return not group.use_fake_user and not bpy.data.user_map(subset=[group])[group]
