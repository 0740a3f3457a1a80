"""What a render needs in memory, told before it starts, so that one that
cannot fit is refused with the number rather than failing halfway.

Every pass streams its work in chunks of `chunk_size` rays (photons, eye
samples; beam grid points a quarter of it), so the need does not grow with
the lamp rays: it is the pixels, the maps' cells, the triangles and the
chunks in flight.
The bytes per item were measured with benchmarks/beams_at_scale.py
(VmHWM on the ball lens at chunk 131,072: 0.9 GB from 1M to 10M lamp
rays, 1.1 GB at 50M) and are rounded up.
"""

from __future__ import annotations

import os
from typing import Optional

from .maps.beam_map import BeamMap
from .passes.beam import BAND_SHARE
from .scene import RenderSettings, Scene

_BASE = 200e6                  # numpy, Embree and the engine's own tables
_PER_TRIANGLE = 400.0          # Embree's BVH and the accelerator's normals, owners and charts
_PER_COPY = 600.0              # an instance: its transforms, Embree's and the accelerator's
_PER_PIXEL = 200.0             # pass buffers (float64) and the image and passes (float32)
_PER_CELL = 250.0              # a map's cells, their tables, and the beam layers over them
_PER_FINE_CELL = 72.0          # the fine beam layer: 3 channels, buffer, values and tables
_PER_LAMP_RAY_IN_FLIGHT = 3.5e3   # a beam grid point or a photon in a chunk, through every bounce
_PER_EYE_SAMPLE_IN_FLIGHT = 3.0e3  # an eye sample in a chunk, with its shadow rays
_PER_PENDING_BEAM = 250.0      # a beam waiting to be rasterised, and its share of the layers
_PER_SCREEN_PIXEL = 48.0       # a flat receiver's screen layer: 3 channels, its values, the receiver's coverage
_PER_KEPT_BEAM = 72.0          # a beam kept for another camera's screen layer
# What to lower, for the part that needs the most.
_REMEDY = {"the scene's triangles": "simplify the meshes", "the image": "lower the resolution",
           "the illumination maps": "lower the map resolution limit or the receivers",
           "the rays in flight": "lower the chunk size", "the engine": "close other programs"}


def needed_bytes(scene: Scene, settings: RenderSettings) -> dict[str, float]:
    """What the render of `scene` with `settings` needs, in bytes, by part."""
    cam = scene.camera
    pixels = cam.pixx * cam.pixy
    cells = len(scene.receivers) * settings.map_resolution_limit ** 2
    in_flight = settings.threads  # a result waiting its turn holds only its deposits
    lamp_chunk = min(settings.chunk_size // (BAND_SHARE if settings.density == "beam" else 1), settings.lamp_rays)
    eye_chunk = min(settings.chunk_size, pixels * settings.spp)
    parts = {
        "the scene's triangles": sum(_PER_TRIANGLE * o.mesh.triangle_count if o.copies == 1 else
                                     _PER_TRIANGLE * len(o.instances.mesh.triangles) + _PER_COPY * o.copies
                                     for o in scene.objects),
        "the image": _PER_PIXEL * pixels,
        "the illumination maps": _PER_CELL * cells,
        "the rays in flight": max(_PER_LAMP_RAY_IN_FLIGHT * lamp_chunk, _PER_EYE_SAMPLE_IN_FLIGHT * eye_chunk)
        * in_flight,
        "the engine": _BASE,
    }
    if settings.density == "beam":
        fine_cells = (BeamMap.FINE_LIMIT * (1.0 + 2.0 * BeamMap.FINE_PAD)) ** 2
        parts["the illumination maps"] += (len(scene.receivers) * (_PER_FINE_CELL * fine_cells
                                                                   + _PER_SCREEN_PIXEL * pixels
                                                                   + _PER_KEPT_BEAM * BeamMap.KEPT_BEAMS)
                                           + _PER_PENDING_BEAM * BeamMap.FLUSH_BEAMS)
    return parts


def physical_memory() -> Optional[float]:
    """This machine's memory in bytes, or None where the OS does not say."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def memory_limit() -> tuple[Optional[float], str]:
    """(bytes, whose) this process may still take: the machine's memory, or
    less where a container's memory limit (cgroup v2 memory.max) or an
    address-space limit (ulimit -v, less what the process has mapped
    already) says so; (None, "") where nothing says."""
    limits = []
    memory = physical_memory()
    if memory is not None:
        limits.append((memory, "this machine's"))
    try:
        text = open("/sys/fs/cgroup/memory.max", encoding="ascii").read().strip()
        if text != "max":
            limits.append((float(text), "this container's"))
    except (OSError, ValueError):
        pass
    try:
        import resource
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            mapped = next((float(line.split()[1]) * 1024.0 for line in open("/proc/self/status", encoding="ascii")
                           if line.startswith("VmSize:")), 0.0)
            limits.append((max(float(soft) - mapped, 0.0), "the address space left under this process's limit"))
    except (ImportError, OSError, ValueError):
        pass
    return min(limits, key=lambda limit: limit[0]) if limits else (None, "")


def refusal(scene: Scene, settings: RenderSettings, memory: Optional[float] = None,
            besides: Optional[dict[str, tuple[float, str]]] = None) -> Optional[str]:
    """Why the render cannot fit in `memory` bytes (memory_limit()'s by
    default), naming what it needs and what takes most, and what to lower;
    None if it fits. `besides`: what the caller holds too, by part, in
    bytes with what to lower for it (the add-on's images of the render)."""
    whose = "the given"
    if memory is None:
        memory, whose = memory_limit()
    parts = needed_bytes(scene, settings)
    remedy = dict(_REMEDY)
    for name, (size, lower) in (besides or {}).items():
        parts[name], remedy[name] = size, lower
    total = sum(parts.values())
    if memory is None or total <= memory:
        return None
    largest = max(parts, key=parts.get)
    return (f"this render needs about {total / 1e9:,.1f} GB of memory, more than {whose} "
            f"{memory / 1e9:,.1f} GB; {parts[largest] / 1e9:,.1f} GB of it for {largest}: {remedy[largest]}")
