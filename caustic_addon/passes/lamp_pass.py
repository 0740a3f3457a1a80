"""What the two passes from the lamps, photons and beams, share: what a job
hands back, the pass's figures, and where a lamp's paths start."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..maps.deposits import Deposits
from ..scene import Light, MeshLight, Scene, SunLight
from ..tracing.accelerator import Accelerator
from ..tracing.hits import MISS


@dataclass
class LampPassStats:
    """lamp_rays: paths traced from the lamps (photons, or beam grid points
    and those refinement added); refined: of them, added by refinement;
    landed: photons or beams that reached a receiver; flux_landed (3,) W."""

    lamp_rays: int = 0
    refined: int = 0
    landed: int = 0
    flux_landed: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def add(self, other: "LampPassStats") -> None:
        self.lamp_rays += other.lamp_rays
        self.refined += other.refined
        self.landed += other.landed
        self.flux_landed = self.flux_landed + other.flux_landed


@dataclass
class JobResult:
    """One job's light for the maps and its figures."""

    deposits: Deposits
    stats: LampPassStats


def deliverer(maps: dict) -> tuple[LampPassStats, Callable[[JobResult], None]]:
    """(the pass's figures, what adds each job's light to `maps` and its
    figures to the pass's), for util.parallel.run_chunks."""
    stats = LampPassStats()

    def deliver(part: JobResult) -> None:
        part.deposits.into(maps)
        stats.add(part.stats)

    return stats, deliver


def lamp_media(accel: Accelerator, light: Light) -> tuple[int, int]:
    """(medium, outer): the closed glass a lamp sits in, where its paths
    start, and the one around that (Accelerator.media_at); MISS for a sun
    (its paths start far upstream) or a lamp in air."""
    if isinstance(light, SunLight):
        return MISS, MISS
    medium, outer = accel.media_at(light.position[None])
    return int(medium[0]), int(outer[0])


def lamps_in_glass(scene: Scene, accel: Accelerator) -> list[str]:
    """A warning for each lamp inside closed glass, which lights what is
    outside only through the glass: shadow rays stop at glass."""
    warnings = []
    for light in scene.lights:
        if isinstance(light, MeshLight):
            continue
        medium, _ = lamp_media(accel, light)
        if medium != MISS and scene.objects[medium].is_transparent:
            warnings.append(f"light '{light.name}' is inside '{scene.objects[medium].body_name}': what is outside "
                            "gets its light only through the glass, as caustics")
    return warnings
