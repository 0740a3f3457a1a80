"""A receiver's box chart (the engine's maps/box_chart.py) in shader nodes:
the chart coordinates of the shading point, from its world position and its
true normal, each point on the face and island the engine puts its triangle
in, so a bake looks its map up where the eye pass does."""

from __future__ import annotations

import math

from ..caustic_addon import ImageFrame


class _Builder:
    """Math nodes in a tree, placed in columns as they are made."""

    def __init__(self, nodes, links):
        self.nodes, self.links, self.count = nodes, links, 0

    def node(self, kind: str):
        node = self.nodes.new(kind)
        node.location = (-1800.0 + 180.0 * (self.count // 8), -160.0 * (self.count % 8))
        self.count += 1
        return node

    def math(self, operation: str, *inputs):
        """The output of a Math node of `operation` on `inputs`, each a
        socket or a number."""
        node = self.node('ShaderNodeMath')
        node.operation = operation
        for socket, value in zip(node.inputs, inputs):
            if isinstance(value, (int, float)):
                socket.default_value = value
            else:
                self.links.new(value, socket)
        return node.outputs[0]

    def pick(self, weights, values):
        """sum_k weights[k] * values[k]: the value of the chosen axis."""
        total = self.math('MULTIPLY', weights[2], values[2])
        for k in (1, 0):
            total = self.math('MULTIPLY_ADD', weights[k], values[k], total)
        return total


def box_chart_vector(nodes, links, frame: ImageFrame):
    """(the Geometry node, a Vector socket): the chart coordinates (x, y,
    0) in metres of the shading point, for the 'BOX' `frame`. The true
    normal is turned back to the triangle's winding where the render shows
    a back face (Cycles and EEVEE turn it toward the viewer)."""
    build = _Builder(nodes, links)
    geometry = build.node('ShaderNodeNewGeometry')
    sign = build.math('MULTIPLY_ADD', geometry.outputs['Backfacing'], -2.0, 1.0)
    turned = build.node('ShaderNodeVectorMath')
    turned.operation = 'SCALE'
    links.new(geometry.outputs['True Normal'], turned.inputs[0])
    links.new(sign, turned.inputs['Scale'])
    normal, position = build.node('ShaderNodeSeparateXYZ'), build.node('ShaderNodeSeparateXYZ')
    links.new(turned.outputs['Vector'], normal.inputs[0])
    links.new(geometry.outputs['Position'], position.inputs[0])
    n, p = normal.outputs, position.outputs
    bias = frame.islands[0].bias
    weighted = [build.math('MULTIPLY', build.math('ABSOLUTE', n[k]), bias[k]) for k in range(3)]
    # the largest weighted component, the first of equals, as numpy's argmax
    is_z = build.math('MULTIPLY', build.math('GREATER_THAN', weighted[2], weighted[0]),
                      build.math('GREATER_THAN', weighted[2], weighted[1]))
    not_z = build.math('SUBTRACT', 1.0, is_z)
    is_y = build.math('MULTIPLY', not_z, build.math('GREATER_THAN', weighted[1], weighted[0]))
    chosen = [build.math('SUBTRACT', not_z, is_y), is_y, is_z]
    # an axis no island uses gets no shift below: its plane does not matter
    planes = {island.axis: island.plane for island in frame.islands}
    planes = [planes.get(k, (0, 1)) for k in range(3)]
    u = build.pick(chosen, [p[planes[k][0]] for k in range(3)])
    v = build.pick(chosen, [p[planes[k][1]] for k in range(3)])
    depth = build.pick(chosen, [p[k] for k in range(3)])
    negative = build.math('LESS_THAN', build.pick(chosen, [n[k] for k in range(3)]), 0.0)
    face = build.math('MULTIPLY_ADD', build.math('MULTIPLY_ADD', is_z, 2.0, is_y), 2.0, negative)
    for island in frame.islands:
        mine = build.math('COMPARE', face, 2.0 * island.axis + island.negative, 0.25)
        if math.isfinite(island.depth_lo):
            mine = build.math('MULTIPLY', mine, build.math('GREATER_THAN', depth, island.depth_lo))
        if math.isfinite(island.depth_hi):
            mine = build.math('MULTIPLY', mine, build.math('LESS_THAN', depth, island.depth_hi))
        u = build.math('MULTIPLY_ADD', mine, float(island.shift[0]), u)
        v = build.math('MULTIPLY_ADD', mine, float(island.shift[1]), v)
    combine = build.node('ShaderNodeCombineXYZ')
    links.new(u, combine.inputs[0])
    links.new(v, combine.inputs[1])
    return geometry, combine.outputs[0]
