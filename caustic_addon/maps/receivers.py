"""An empty illumination map for each receiver that can hold one, sized
from the map scale or from the receiver."""

from __future__ import annotations

from ..scene import RenderSettings, Scene
from .beam_map import BeamMap
from .charts import make_chart
from .illumination_map import IlluminationMap, MapEstimate, auto_cell_size


def build_maps(scene: Scene, settings: RenderSettings, warnings: list[str]) -> dict[int, IlluminationMap]:
    """Receiver object index -> its empty map; a warning for each receiver
    that gets none, or a coarser cell than the map scale asks for."""
    estimate = MapEstimate(settings.k_nearest if settings.density in ("adaptive", "beam") else None)
    limit = settings.map_resolution_limit
    maps = {}
    for index, obj in enumerate(scene.objects):
        if not obj.is_receiver:
            continue
        chart = make_chart(obj)
        if chart is None:
            warnings.append(f"'{obj.name}' is curved and has no UV map: it receives no caustics")
            continue
        cell = auto_cell_size(chart, limit) if settings.map_scale is None else settings.map_scale / 1000.0
        if chart.size.max() / cell > limit:
            coarser = auto_cell_size(chart, limit)
            warnings.append(f"'{obj.name}': a map scale of {cell * 1000:.4g} mm needs more than {limit} cells "
                            f"across; using {coarser * 1000:.4g} mm")
            cell = coarser
        maps[index] = (BeamMap(obj.name, chart, cell, estimate, threads=settings.threads)
                       if settings.density == "beam" else IlluminationMap(obj.name, chart, cell, estimate))
    return maps
