"""The nodes that drive a surface's colour, read as the engine's texture
nodes (caustic_addon/scene/textures.py): an Image Texture on a UV map, or
on Generated or Object coordinates, through a Mapping node; RGB, Value,
Mix Color (and the older MixRGB), Math and Color Ramp after it; reroutes
anywhere. Anything else Cycles bakes to an image on the object's UV map
(`receiver_bake.py`); what it cannot bake, and an image that cannot be
read, is named in a warning, and the socket's own value is used instead.

A reading is a recipe: a function of the object it is on (`ObjectFrame`),
since UV maps, object space and texture space are the object's."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import bpy
import numpy as np
from mathutils import Euler, Matrix

from ..caustic_addon import textures as nodes
from .pixels import can_read, image_pixels, is_srgb_encoded
from .receiver_bake import CannotBake, baked_color


@dataclass
class ObjectFrame:
    """What a texture needs of the object it is on.

    corner_uvs     UV map name -> (nt,3,2) its coordinates at each triangle's
                   corners; "" is the active map
    to_object      (4,4) world to object space
    texspace_location, texspace_size  (3,) the mesh's texture space
    owner          the Blender object, which Cycles bakes what is not read
    """

    corner_uvs: dict[str, np.ndarray]
    to_object: np.ndarray
    texspace_location: np.ndarray
    texspace_size: np.ndarray
    owner: Optional[bpy.types.Object] = None


# ObjectFrame by name: typing keeps every alias it makes, and one that held the class would hold this module's
# globals, and bpy through them, past the point where Blender 4.2's bpy module must be freed to shut Blender down
# (it crashes at exit otherwise).
Recipe = Callable[["ObjectFrame"], nodes.Node]


class NotRead(Exception):
    """A node the reader does not take, which Cycles bakes; the message
    names it."""


class Unreadable(NotRead):
    """A node that gives Cycles nothing to bake either (an image that cannot
    be read); the message names it."""


def _constant(value) -> Recipe:
    node = nodes.Constant(np.array(value[:3], dtype=np.float64) if hasattr(value, "__len__") else float(value))
    return lambda frame: node


def _input(node, identifier: str, images: dict) -> Recipe:
    """The recipe of one of `node`'s inputs, by identifier: what is linked
    to it, or its own value."""
    socket = next(s for s in node.inputs if s.identifier == identifier)
    if not socket.is_linked:
        return _constant(socket.default_value)
    link = socket.links[0]
    return _output(link.from_node, link.from_socket, images)


def _output(node, socket, images: dict) -> Recipe:
    """The recipe of `node`'s output `socket`."""
    kind = node.bl_idname
    if kind == 'NodeReroute':
        return _input(node, node.inputs[0].identifier, images)
    if kind in ('ShaderNodeRGB', 'ShaderNodeValue'):
        return _constant(socket.default_value)
    if kind == 'ShaderNodeTexImage':
        return _image(node, socket, images)
    if kind == 'ShaderNodeMix' and node.data_type in ('RGBA', 'FLOAT'):
        suffix = "Color" if node.data_type == 'RGBA' else "Float"
        return _mix(node, node.blend_type, "Factor_Float", f"A_{suffix}", f"B_{suffix}", node.clamp_factor,
                    node.clamp_result, images)
    if kind == 'ShaderNodeMixRGB':
        return _mix(node, node.blend_type, "Fac", "Color1", "Color2", True, node.use_clamp, images)
    if kind == 'ShaderNodeMath':
        if node.operation not in nodes.MATH:
            raise NotRead(f"'{node.name}', a Math node doing {node.operation.lower().replace('_', ' ')}")
        operands = [_input(node, s.identifier, images) for s in list(node.inputs)[:3]]
        operands += [_constant(0.0)] * (3 - len(operands))
        operation, clamp = node.operation, node.use_clamp
        return lambda frame: nodes.MathNode(operation, tuple(r(frame) for r in operands), clamp)
    if kind == 'ShaderNodeValToRGB' and socket.identifier == 'Color':
        return _ramp(node, images)
    raise NotRead(f"'{node.name}', a {node.bl_label} node")


def _mix(node, blend: str, factor: str, a: str, b: str, clamp_factor: bool, clamp_result: bool,
         images: dict) -> Recipe:
    if blend not in nodes.MIX_BLENDS:
        raise NotRead(f"'{node.name}', a Mix node blending by {blend.lower().replace('_', ' ')}")
    t, first, second = (_input(node, name, images) for name in (factor, a, b))
    return lambda frame: nodes.MixColor(blend, t(frame), first(frame), second(frame), clamp_factor, clamp_result)


def _ramp(node, images: dict) -> Recipe:
    ramp = node.color_ramp
    if ramp.color_mode != 'RGB' or ramp.interpolation not in ('LINEAR', 'EASE', 'CONSTANT'):
        raise NotRead(f"'{node.name}', a Color Ramp interpolating {ramp.interpolation.lower()} in "
                      f"{ramp.color_mode}")
    positions = np.array([e.position for e in ramp.elements], dtype=np.float64)
    colors = np.array([e.color[:3] for e in ramp.elements], dtype=np.float64)
    order = np.argsort(positions, kind="stable")
    factor, interpolation = _input(node, "Fac", images), ramp.interpolation
    return lambda frame: nodes.ColorRamp(factor(frame), positions[order], colors[order], interpolation)


def _mapping_matrix(node) -> np.ndarray:
    """(4,4) the Mapping node's map of a vector, as Cycles' svm_mapping:
    Point: T R S v; Texture: its inverse; Vector: R S v; Normal: the
    normalized inverse transpose of R S."""
    for name in ("Location", "Rotation", "Scale"):
        if name in node.inputs and node.inputs[name].is_linked:
            raise NotRead(f"'{node.name}', a Mapping node whose {name} is linked")
    kind = node.vector_type
    location = node.inputs["Location"].default_value if "Location" in node.inputs else (0.0, 0.0, 0.0)
    rotation = Euler(node.inputs["Rotation"].default_value, 'XYZ').to_matrix().to_4x4()
    scale = Matrix.Diagonal((*node.inputs["Scale"].default_value, 1.0))
    if kind == 'POINT':
        return np.array(Matrix.Translation(location) @ rotation @ scale)
    if kind == 'TEXTURE':
        return np.array((Matrix.Translation(location) @ rotation @ scale).inverted_safe())
    if kind == 'VECTOR':
        return np.array(rotation @ scale)
    raise NotRead(f"'{node.name}', a Mapping node of type Normal")


def _coordinates(node, images: dict) -> tuple[str, str, np.ndarray]:
    """(coordinates 'UV', 'GENERATED' or 'OBJECT', UV map name, (4,4)
    mapping) of what drives an Image Texture's Vector."""
    socket = node.inputs["Vector"]
    mapping = np.eye(4)
    while socket.is_linked:
        link = socket.links[0]
        source = link.from_node
        if source.bl_idname == 'NodeReroute':
            socket = source.inputs[0]
        elif source.bl_idname == 'ShaderNodeMapping':
            mapping = mapping @ _mapping_matrix(source)
            socket = source.inputs["Vector"]
        elif source.bl_idname == 'ShaderNodeUVMap':
            return "UV", source.uv_map, mapping
        elif source.bl_idname == 'ShaderNodeTexCoord' and link.from_socket.identifier in ("UV", "Generated",
                                                                                           "Object"):
            if link.from_socket.identifier == "Object" and source.object is not None:
                raise NotRead(f"'{source.name}', Texture Coordinates of another object ('{source.object.name}')")
            return link.from_socket.identifier.upper(), "", mapping
        else:
            raise NotRead(f"'{source.name}', a {source.bl_label} node's {link.from_socket.name} as coordinates")
    return "UV", "", mapping


def _image(node, socket, images: dict) -> Recipe:
    image = node.image
    if image is None:
        raise Unreadable(f"'{node.name}', an Image Texture with no image")
    if image.source not in ('FILE', 'GENERATED') or not can_read(image):
        raise Unreadable(f"'{node.name}', whose image '{image.name}' cannot be read")
    if node.projection != 'FLAT':
        raise NotRead(f"'{node.name}', an Image Texture with {node.projection.lower()} projection")
    if node.interpolation not in nodes.INTERPOLATIONS or node.extension not in nodes.EXTENSIONS:
        raise NotRead(f"'{node.name}', an Image Texture with {node.interpolation} interpolation and "
                      f"{node.extension.lower()} extension")
    if image.name not in images:
        # row 0 at v = 0, as the engine looks textures up; sRGB stays encoded, as Cycles keeps it
        pixels = image_pixels(image)
        if pixels.shape[2] < 3:
            pixels = np.concatenate([np.repeat(pixels[..., :1], 3, axis=2), pixels[..., 1:]], axis=2)
        if pixels.shape[2] < 4:
            pixels = np.concatenate([pixels[..., :3], np.ones(pixels.shape[:2] + (1,), dtype=np.float32)], axis=2)
        pixels = pixels[::-1] if image.is_float else np.round(pixels[::-1] * 255.0).astype(np.uint8)
        images[image.name] = np.ascontiguousarray(pixels, dtype=np.float32 if image.is_float else np.uint8)
    pixels, srgb = images[image.name], is_srgb_encoded(image)
    coordinates, uv_map, mapping = _coordinates(node, images)
    interpolation, extension, alpha = node.interpolation, node.extension, socket.identifier == "Alpha"

    def bind(frame: ObjectFrame) -> nodes.Node:
        if coordinates == "UV" and uv_map not in frame.corner_uvs:
            raise Unreadable(f"'{node.name}', whose UV map '{uv_map or 'active'}' the mesh does not have")
        return nodes.ImageTexture(pixels, coordinates, frame.corner_uvs.get(uv_map), frame.to_object,
                            frame.texspace_location, frame.texspace_size, mapping, interpolation, extension, alpha,
                            srgb)

    return bind


def _baked(material_name: str, socket, reason: str) -> Recipe:
    """The recipe of a colour input whose nodes Cycles bakes on each object."""
    node_name, identifier = socket.node.name, socket.identifier

    def bind(frame: ObjectFrame) -> nodes.Node:
        try:
            pixels = baked_color(frame, material_name, node_name, identifier)
        except CannotBake as exc:
            raise Unreadable(f"{reason}, {exc}") from None
        return nodes.ImageTexture(pixels, "UV", frame.corner_uvs[""], interpolation="Linear", extension="EXTEND")

    return bind


def color_recipe(material_name: str, socket, what: str, warnings: list[str]) -> Optional[Recipe]:
    """The recipe of what drives the colour input `socket` of material
    `material_name`, or None when nothing does or a node in the way gives
    nothing to read (with a warning naming it: the socket's own value is
    used). Nodes the reader does not take are baked by Cycles."""
    if not socket.is_linked:
        return None
    link = socket.links[0]
    try:
        return _output(link.from_node, link.from_socket, {})
    except Unreadable as exc:
        warnings.append(f"{what}: its {socket.name} comes from {exc}, which the caustic render does not read; "
                        "the unconnected value is used")
        return None
    except NotRead as exc:
        return _baked(material_name, socket, str(exc))


def bind(recipe: Recipe, frame: ObjectFrame, what: str, warnings: list[str]) -> Optional[nodes.Node]:
    """The engine node of `recipe` on an object, or None (with a warning
    naming what is missing)."""
    try:
        return recipe(frame)
    except NotRead as exc:
        warnings.append(f"{what}: its color comes from {exc}; the unconnected value is used")
        return None
