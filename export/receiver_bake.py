"""A receiver's colour that only Cycles can evaluate (a Noise, Checker or
Voronoi texture, a Box projection, any node `textures.py` does not read)
baked to an image on the object's active UV map, which the engine then
reads as an Image Texture.

The bake is Cycles' own (`bpy.ops.object.bake`, type Emit) of a copy of the
object, in a scene of its own, whose material copy sends the colour input's
nodes to an Emission shader of strength 1: the image holds the colour
itself, unlit and unshaded. The user's object, mesh and material are not
touched; the copies, the scene and the image are removed after. A bake is
kept while the material's nodes and the object's texture frame stay as
they are."""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from contextlib import ExitStack

import bpy
import numpy as np

from .cycles_still import cycles_enabled
from .node_fingerprint import fingerprint
from .pixels import image_pixels

# Texels along each side: a Checker of scale 5 keeps 200 texels a square.
BAKE_SIZE = 1024
# Jittered samples per texel, to average a procedural's detail within it.
BAKE_SAMPLES = 4
# Texels the bake extends each island by, so that linear look-ups at its
# seams find its own colour.
BAKE_MARGIN = 8
# Bakes kept: a receiver's colour is 16 MiB of float RGBA.
KEPT_BAKES = 8

# (object, material, node, input) -> (what it depends on, (h, w, 4) float32, row 0 at v = 0)
_bakes: OrderedDict[tuple, tuple[tuple, np.ndarray]] = OrderedDict()


class CannotBake(Exception):
    """Why a colour cannot be baked, with what to do: the message ends a
    sentence that names the node."""


def _frame_digest(frame) -> bytes:
    digest = hashlib.sha1()
    for array in (frame.corner_uvs[""], frame.to_object, frame.texspace_location, frame.texspace_size):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).data)
    return digest.digest()


def _check_uv_map(corner_uvs: np.ndarray, name: str) -> None:
    """CannotBake where UV map `name`'s triangles `corner_uvs (n,3,2)` leave
    the unit square or overlap (their areas sum past it), where one texel
    would hold two places."""
    if corner_uvs.size and (corner_uvs.min() < -1e-4 or corner_uvs.max() > 1.0 + 1e-4):
        raise CannotBake(f"which Cycles can bake only onto a UV map inside the 0-1 square, and UV map '{name}' "
                         "leaves it: unwrap the object without overlaps")
    edges = corner_uvs[:, 1:] - corner_uvs[:, :1]
    area = 0.5 * np.abs(edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]).sum()
    if area > 1.0 + 1e-3:
        raise CannotBake(f"which Cycles can bake only onto a UV map whose faces do not overlap, and UV map "
                         f"'{name}''s do: unwrap the object without overlaps")


def _emitting_copy(material, node_name: str, identifier: str, image):
    """A copy of `material` whose surface is an Emission of what drives
    input `identifier` of node `node_name`, baked into `image`."""
    copy = material.copy()
    tree = copy.node_tree
    socket = next(s for s in tree.nodes[node_name].inputs if s.identifier == identifier)
    emission = tree.nodes.new('ShaderNodeEmission')
    emission.inputs['Strength'].default_value = 1.0
    tree.links.new(socket.links[0].from_socket, emission.inputs['Color'])
    tree.links.new(emission.outputs['Emission'], tree.get_output_node('CYCLES').inputs['Surface'])
    target = tree.nodes.new('ShaderNodeTexImage')
    target.image = image
    tree.nodes.active = target
    return copy


def _discarding_copy(image):
    """A black material that bakes into `image`, for the object's other
    materials, whose faces may share the UV map's square."""
    copy = bpy.data.materials.new("Caustics: not baked")
    if bpy.app.version < (5, 0, 0):
        copy.use_nodes = True
    tree = copy.node_tree
    tree.nodes.clear()
    output, emission = tree.nodes.new('ShaderNodeOutputMaterial'), tree.nodes.new('ShaderNodeEmission')
    emission.inputs['Strength'].default_value = 0.0
    tree.links.new(emission.outputs['Emission'], output.inputs['Surface'])
    target = tree.nodes.new('ShaderNodeTexImage')
    target.image = image
    tree.nodes.active = target
    return copy


def _bake(owner, material, node_name: str, identifier: str) -> np.ndarray:
    """(BAKE_SIZE, BAKE_SIZE, 4) float32, row 0 at v = 0: the colour Cycles
    evaluates at each texel of `owner`'s active UV map, where `material`
    is on its faces."""
    with ExitStack() as cleanup:
        scene = bpy.data.scenes.new(f"Caustics: baking the color of '{owner.name}'")
        cleanup.callback(bpy.data.scenes.remove, scene)
        images = [bpy.data.images.new(f"{scene.name} {i}", size, size, float_buffer=True, alpha=False)
                  for i, size in enumerate((BAKE_SIZE, 8))]
        for image in images:
            cleanup.callback(bpy.data.images.remove, image)
        baked, discarded = _emitting_copy(material, node_name, identifier, images[0]), _discarding_copy(images[1])
        for copy in (baked, discarded):
            cleanup.callback(bpy.data.materials.remove, copy)
        mesh = owner.data.copy()
        cleanup.callback(bpy.data.meshes.remove, mesh)
        copy = owner.copy()
        copy.data = mesh
        cleanup.callback(bpy.data.objects.remove, copy)
        copy.parent = None
        copy.matrix_world = owner.matrix_world
        for slot in copy.material_slots:
            slot.material = baked if slot.material == material else discarded
        scene.collection.objects.link(copy)
        scene.render.engine = 'CYCLES'
        scene.cycles.device, scene.cycles.samples = 'CPU', BAKE_SAMPLES
        view_layer = scene.view_layers[0]
        view_layer.objects.active = copy
        copy.select_set(True, view_layer=view_layer)
        with bpy.context.temp_override(scene=scene, view_layer=view_layer, active_object=copy, object=copy,
                                       selected_objects=[copy], selected_editable_objects=[copy]):
            result = bpy.ops.object.bake(type='EMIT', margin=BAKE_MARGIN, margin_type='EXTEND', use_clear=True,
                                         target='IMAGE_TEXTURES')
        if 'FINISHED' not in result:
            raise CannotBake("which Cycles failed to bake")
        return np.ascontiguousarray(image_pixels(images[0])[::-1], dtype=np.float32)


def baked_color(frame, material_name: str, node_name: str, identifier: str) -> np.ndarray:
    """(h, w, 4) float32, row 0 at v = 0: what drives input `identifier` of
    node `node_name` of material `material_name`, baked by Cycles on the
    active UV map of the object `frame.owner`, or kept from an earlier bake
    of the same nodes and frame. CannotBake says why not."""
    owner = frame.owner
    material = bpy.data.materials.get(material_name)
    if owner is None or owner.type != 'MESH' or material is None:
        raise CannotBake("which Cycles can bake only on a mesh object")
    if "" not in frame.corner_uvs:
        raise CannotBake("which Cycles bakes onto a UV map, and the mesh has none: add one (UV > Unwrap)")
    key = (owner.name, material_name, node_name, identifier)
    depends = (fingerprint(material.node_tree), _frame_digest(frame))
    kept = _bakes.get(key)
    if kept is not None and kept[0] == depends:
        _bakes.move_to_end(key)
        return kept[1]
    active = owner.data.uv_layers.active
    _check_uv_map(frame.corner_uvs[""], active.name if active is not None else "")
    if not cycles_enabled():
        raise CannotBake("which needs Cycles to bake it, and the Cycles add-on is disabled")
    if bpy.app.is_job_running('RENDER'):
        raise CannotBake("which needs a Cycles bake, and none can run while Blender renders")
    pixels = _bake(owner, material, node_name, identifier)
    _bakes[key] = (depends, pixels)
    while len(_bakes) > KEPT_BAKES:
        _bakes.popitem(last=False)
    return pixels
