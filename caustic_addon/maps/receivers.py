"""An empty illumination map for each receiver that can hold one, sized
from the map scale or from the receiver."""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..scene import Object, RenderSettings, Scene
from ..tracing.topology import triangle_normals
from ..util.vectors import DIVISION_FLOOR
from .beam_map import BeamMap
from .box_chart import BoxChart
from .charts import Chart, PlaneChart, UVChart
from .illumination_map import IlluminationMap, MapEstimate, auto_cell_size
from .screen_layer import ImageView, ScreenLayer


# Cells between a box chart's islands: beyond the adaptive estimate's
# widest window (16 cells) and a bilinear cell, so that no estimate borrows
# light from another part of the receiver, and room for the beams across a
# seam that the beam pass copies into both islands (passes/beam.py): the
# longer ones, glancing, fall back to photons, which show the seam.
GUTTER_CELLS = 40


def build_maps(scene: Scene, settings: RenderSettings, warnings: list[str],
               view: Optional[ImageView]) -> dict[int, IlluminationMap]:
    """Receiver object index -> its empty map, a flat receiver's beam map
    with a screen layer for the camera `view` (None: no eye pass reads the
    maps, and beam maps keep nothing finer than their cells); a warning for each receiver
    that gets none, a coarser cell than the map scale asks for, or an
    automatic chart whose parts overlap."""
    estimate = MapEstimate(settings.k_nearest if settings.density in ("adaptive", "beam") else None)
    maps = {}
    for index, obj in enumerate(scene.objects):
        if not obj.is_receiver:
            continue
        chart = make_chart(obj)
        if chart is None:
            warnings.append(f"'{obj.name}' has no area: it receives no caustics")
            continue
        if isinstance(chart, BoxChart):
            if chart.overlaps:
                warnings.append(f"'{obj.name}' has no UV map, and in its automatic chart parts facing "
                                f"{', '.join(chart.overlaps)} overlap: their caustics mix there; a UV map "
                                "would keep them apart")
            # the gutter grows the chart, and with it an automatic cell
            for _ in range(3):
                chart.lay_out(GUTTER_CELLS * _cell_size(obj.name, chart, settings, []))
        if isinstance(chart, PlaneChart):
            chart.front = facing_casters(chart, scene.casters)
        cell = _cell_size(obj.name, chart, settings, warnings)
        if settings.density != "beam":
            maps[index] = IlluminationMap(obj.name, chart, cell, estimate)
            continue
        screen = None
        if isinstance(chart, PlaneChart) and view is not None:
            receiver = chart.plane_coords(obj.mesh.corners.reshape(-1, 3)).reshape(-1, 3, 2)
            screen = ScreenLayer(view, chart, np.ascontiguousarray(receiver))
        maps[index] = BeamMap(obj.name, chart, cell, estimate, threads=settings.threads, screen=screen,
                              sub_cell=view is not None)
    return maps


def facing_casters(chart: PlaneChart, casters: list[Object]) -> Optional[np.ndarray]:
    """The unit normal of the side of a flat receiver's plane that the
    `casters` are on, each by the share of its bounding box on that side
    times the box's diagonal; None where they are as much on either side,
    or there are none."""
    weight = 0.0
    for caster in casters:
        lo, hi = caster.mesh.bounds
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            continue
        centre = float((0.5 * (lo + hi) - chart.point) @ chart.normal)
        reach = float(0.5 * np.abs(hi - lo) @ np.abs(chart.normal))
        above = float(np.clip(0.5 + centre / (2.0 * reach), 0.0, 1.0)) if reach > 0 else float(centre > 0)
        weight += (2.0 * above - 1.0) * float(np.linalg.norm(hi - lo))
    return None if weight == 0.0 else np.sign(weight) * chart.normal


def _cell_size(name: str, chart: Chart, settings: RenderSettings, warnings: list[str]) -> float:
    """The map cell (m): the map scale, or automatic, and no finer than the
    resolution limit allows, with a warning if that coarsens the map scale."""
    limit = settings.map_resolution_limit
    cell = auto_cell_size(chart, limit) if settings.map_scale is None else settings.map_scale / 1000.0
    if chart.size.max() / cell > limit:
        coarser = auto_cell_size(chart, limit)
        warnings.append(f"'{name}': a map scale of {cell * 1000:.4g} mm needs more than {limit} cells "
                        f"across; using {coarser * 1000:.4g} mm")
        cell = coarser
    return cell


def make_chart(obj: Object, planarity_tolerance: float = 1e-6) -> Optional[Chart]:
    """The chart of a receiver: its plane if it is flat, else its UV map,
    else its box projection; None if it has no area."""
    mesh = obj.mesh
    normals, areas = triangle_normals(mesh.corners)
    if areas.sum() <= 0:
        return None
    normal = (normals * areas[:, None]).sum(axis=0)
    if np.linalg.norm(normal) > 0:
        normal /= np.linalg.norm(normal)
        center = mesh.vertices.mean(axis=0)
        size = np.ptp(mesh.vertices, axis=0).max()
        if np.abs((mesh.vertices - center) @ normal).max() <= planarity_tolerance * max(size, DIVISION_FLOOR):
            return PlaneChart(center, normal, mesh.vertices)
    if mesh.corner_uvs is not None:
        return UVChart(mesh, areas)
    return BoxChart(mesh)
