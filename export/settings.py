"""Scene.caustic turned into the engine's RenderSettings."""

import os
from dataclasses import replace

from ..caustic_addon import RenderSettings
from .errors import InputError


def render_settings(props, spp: int | None = None) -> RenderSettings:
    """The engine settings of Scene.caustic `props`; `spp` overrides its samples."""
    if props.lamp_rays == 0:
        raise InputError("Light Rays is 0: the caustics need at least one light ray (Caustics > Illumination Map)")
    return RenderSettings(
        lamp_rays=props.lamp_rays,
        emission=props.emission.lower(),
        energy=props.energy,
        # the engine's map scale is in millimetres of world space; Blender
        # stores lengths in scene units, whatever the unit scale shows
        map_scale=None if props.use_auto_map_scale else props.map_scale * 1000.0,
        density=props.density.lower(),
        beam_refinement=props.beam_refinement,
        max_depth=props.max_depth,
        bands=props.bands,
        spp=props.spp if spp is None else spp,
        edge_samples=props.edge_samples,
        lamp_samples=props.lamp_samples,
        world_samples=props.world_samples,
        threads=max(1, os.cpu_count() or 1),
    )


def bake_settings(props) -> RenderSettings:
    """The engine settings of a bake or a Live update: the maps alone."""
    return replace(render_settings(props), spp=1, eye_pass=False)
