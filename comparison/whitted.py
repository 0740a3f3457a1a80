"""Cycles set up to render the light the caustic render computes: the lamps'
and the world's direct light, specular paths from the eye, and caustics (a
diffuse surface lit through glass or off a mirror), but no light from one
diffuse surface to another, which a Whitted pass with caustic maps has not.

A diffuse receiver lit through glass takes the caustic on the path's first
diffuse bounce, so Cycles needs one diffuse bounce; the diffuse materials
are black to the paths that already bounced off a diffuse surface (Light
Path's Diffuse Depth above 0), so that bounce brings back no other diffuse
surface's light. Filter Glossy is 0 (it would roughen smooth glass for the
paths from a diffuse bounce) and nothing is clamped."""

from __future__ import annotations

from typing import Callable

from ..export.overrides import Overrides


def whitted_settings(overrides: Overrides, scene, max_depth: int, caustics: bool = True) -> None:
    """Cycles' light paths on `overrides`: one diffuse bounce, `max_depth`
    specular bounces (the caustic render's Max Depth) on each side of it,
    caustics through glass and off mirrors (path-traced: from lamps with a
    size and the world; MNEE for the lamps it is asked for) or, without
    `caustics`, none at all."""
    cycles = scene.cycles
    for name, value in (("max_bounces", 2 * max_depth + 1), ("diffuse_bounces", 1),
                        ("glossy_bounces", 2 * max_depth), ("transmission_bounces", 2 * max_depth),
                        ("caustics_reflective", caustics), ("caustics_refractive", caustics), ("blur_glossy", 0.0),
                        ("sample_clamp_direct", 0.0), ("sample_clamp_indirect", 0.0)):
        overrides.set(cycles, name, value)


def black_after_a_diffuse_bounce(material) -> Callable[[], None] | None:
    """Make `material` black to the paths that bounced off a diffuse surface
    (Light Path's Diffuse Depth above 0) between its Cycles output and its
    surface; returns the call that takes the nodes out again, or None when
    its surface is not a node link it can cut in on."""
    tree = material.node_tree
    output = tree.get_output_node('CYCLES') if tree is not None else None
    if output is None or not output.inputs["Surface"].is_linked:
        return None
    surface = output.inputs["Surface"].links[0].from_socket
    output_name, from_name, from_socket = output.name, surface.node.name, surface.identifier
    active = tree.nodes.active.name if tree.nodes.active is not None else None
    depth, above = tree.nodes.new('ShaderNodeLightPath'), tree.nodes.new('ShaderNodeMath')
    mix, black = tree.nodes.new('ShaderNodeMixShader'), tree.nodes.new('ShaderNodeEmission')
    added = [node.name for node in (depth, above, mix, black)]
    above.operation, above.inputs[1].default_value = 'GREATER_THAN', 0.5
    black.inputs["Strength"].default_value = 0.0
    tree.links.new(depth.outputs["Diffuse Depth"], above.inputs[0])
    tree.links.new(above.outputs[0], mix.inputs[0])
    tree.links.new(surface, mix.inputs[1])
    tree.links.new(black.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], output.inputs["Surface"])

    def take_out() -> None:
        nodes = tree.nodes
        for name in added:
            if name in nodes:
                nodes.remove(nodes[name])
        if output_name in nodes and from_name in nodes:
            source = next(s for s in nodes[from_name].outputs if s.identifier == from_socket)
            tree.links.new(source, nodes[output_name].inputs["Surface"])
        nodes.active = nodes.get(active) if active is not None else None

    return take_out
