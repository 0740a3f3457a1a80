"""Which rays see an object or a lamp."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Visibility:
    """Which rays see an object, as Blender's Object > Visibility > Ray
    Visibility and Holdout, read the way Cycles reads them (its PATH_RAY_*
    flags, kernel/types.h; path_state_ray_visibility, after a refraction
    only the transmission flag counts): `camera` eye rays before any
    specular event, `glossy` eye rays after a reflection, `transmission` eye
    rays after a refraction, `shadow` the shadow rays toward lamps and the
    world. Where a camera ray meets a `holdout` object its pixel is cut out,
    colour and alpha 0; every other ray sees the object as usual. The pass
    from the lamps sees every object, as light does in Cycles. A lamp
    reads `camera`, `glossy` and `transmission` only."""

    camera: bool = True
    glossy: bool = True
    transmission: bool = True
    shadow: bool = True
    holdout: bool = False


# Blender's lamps are seen by glossy and transmission rays, and by the
# camera only once their Camera box is ticked.
LAMP_VISIBILITY = Visibility(camera=False)
