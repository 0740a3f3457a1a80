"""Which caustics Cycles can render, and how. Its path tracer reaches a lamp
with a size (an area lamp, a point or spot lamp with a Radius, a sun with
an Angle) and the world through glass and off mirrors; it cannot reach a
lamp of no size through a smooth caster, whose caustic only MNEE (shadow
caustics) renders: by refraction only, inside the caster's shadow, through
a few casters, and short of the light at bright peaks. Through a rough
caster Cycles samples such a lamp at the caster's last bounce, so its
caustic is path-traced too."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..caustic_addon import AreaLight, PointLight, SpotLight, SunLight


def _no_size(light) -> str | None:
    """The setting that makes `light` a point (Blender's words), or None if it has a size."""
    if isinstance(light, (PointLight, SpotLight)) and light.radius == 0.0:
        return "Radius 0"
    if isinstance(light, SunLight) and light.angle == 0.0:
        return "Angle 0"
    if isinstance(light, AreaLight) and light.area == 0.0:
        return "Size 0"
    return None


def _power(light) -> float:
    return float(np.max(light.color)) * (light.strength if isinstance(light, SunLight) else light.power)


@dataclass
class CausticSources:
    """Blender object names: `point_lamps` the lamps of no size that light
    (with why, in Blender's words), `smooth_glass` and `smooth_mirrors` the
    smooth casters. Cycles path-traces every caustic unless a lamp of no size
    meets a smooth caster; then `mnee` is True and its reference holds only
    MNEE's part of that lamp's caustic."""

    point_lamps: dict[str, str]
    smooth_glass: list[str]
    smooth_mirrors: list[str]

    @property
    def mnee(self) -> bool:
        return bool(self.point_lamps) and bool(self.smooth_glass or self.smooth_mirrors)

    def lacking(self) -> str:
        """Why Cycles' reference lacks part of the caustic, naming the lamps and casters."""
        lamps = ", ".join(f"'{name}' ({why})" for name, why in self.point_lamps.items())
        parts = []
        if self.smooth_glass:
            parts.append("through " + ", ".join(f"'{n}'" for n in self.smooth_glass) + " its reference has only "
                         "MNEE's shadow caustics (refraction only, inside the shadow, through at most about 6 "
                         "casters, short of the light at bright peaks)")
        if self.smooth_mirrors:
            parts.append("off the smooth reflectors " + ", ".join(f"'{n}'" for n in self.smooth_mirrors) +
                         " it has none (MNEE cannot solve for mirrors)")
        return f"Cycles cannot path-trace the caustics of lamps without a size, {lamps}: " + "; ".join(parts)


def caustic_sources(read) -> CausticSources:
    """The caustic sources of `read` (an export.SceneRead)."""
    point_lamps = {}
    for light in read.scene.lights:
        why = _no_size(light)
        if why is not None and _power(light) > 0.0:
            point_lamps.setdefault(read.sources[light.name], why)
    smooth = [o for o in read.scene.objects if o.is_caster and o.material.smooth]
    glass = list(dict.fromkeys(read.sources[o.name] for o in smooth if o.is_transparent))
    mirrors = list(dict.fromkeys(read.sources[o.name] for o in smooth if o.is_reflector))
    return CausticSources(point_lamps, glass, mirrors)
