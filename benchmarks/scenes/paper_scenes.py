"""The paper's experiments (section 4) as scenes, presets and caustic measures.

The objects, floor, lamp and camera are caustic_addon.shapes' paper layout,
which the add-on's caustic.add_paper_scene builds too. An object's `height`
is the gap (m) between its lowest point and the floor above the 1 mm that
keeps the glass off the plane: 0 rests it on the floor.

The measures read the floor's illumination map at the centres of its cells
(a grid of floor points as fine as the map), inside the box of cells that
caught any light. The floor's chart coordinates are world x, y. Lengths are
metres, irradiance W/m^2.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from caustic_addon import Mesh, RenderSettings, Scene, paper
from benchmarks.references import reference
from caustic_addon.maps.illumination_map import IlluminationMap

GLASS_IOR = 1.5
# m: enough for the caustics of resting objects, for the 5 mm maps
RESTING_FLOOR = 8.0
# mm: the cells the shape and height sweeps measure on, over paper.FLOOR_SIZE
SHAPE_MAP_SCALE = 10.0
GALLERY_PIXELS = (320, 240)

# The paper's experiments: the values each table varies, and the defaults
# (its 40,000 lamp rays, energy 10, map scale 5 mm on the bilinear map).
PAPER_DEFAULTS = {"ior": GLASS_IOR, "height": 0.0, "lamp_rays": paper.LAMP_RAYS, "energy": paper.ENERGY,
                  "map_scale": paper.MAP_SCALE, "density": "splat"}
PAPER_SWEEPS = {
    "ior": tuple(paper.INDICES.values()),
    "lamp_rays": (10_000, 40_000, 160_000, 1_000_000, 10_000_000),
    "energy": (10.0, 20.0),
    "map_scale": (5.0, 40.0),
    "height": (0.0, paper.RAISED),
}
# The paper's table for each experiment: tables 1-3 are the index of
# refraction for the round, flat and pointed base.
PAPER_TABLES = {"ior_round": 1, "ior_flat": 2, "ior_pointed": 3, "lamp_rays": 4, "energy": 5, "map_scale": 6,
                "height": 7}


def paper_scene(shape: str, ior: float = GLASS_IOR, height: float = 0.0, pixels: tuple[int, int] = GALLERY_PIXELS,
                floor: float = paper.FLOOR_SIZE) -> Scene:
    """The paper's scene (caustic_addon.paper), by default of glass at the
    benchmarks' gallery size."""
    return paper.scene(shape, ior, height, pixels, floor)


def splat_settings(scene: Scene, map_scale: float, **kwargs) -> RenderSettings:
    """RenderSettings for the paper's bilinear map with cells of `map_scale`
    mm over the whole floor (the resolution limit raised to fit), and `kwargs`."""
    floor = np.ptp(scene.objects[0].mesh.vertices[:, :2], axis=0).max()
    cells = int(math.ceil(floor / (map_scale / 1000.0)))
    return RenderSettings(density="splat", map_scale=map_scale, map_resolution_limit=max(cells, 1024), **kwargs)


def volume_centroid(mesh: Mesh) -> np.ndarray:
    """(3,) centre of mass of the solid a closed, outward-wound mesh bounds:
    the volume-weighted mean of the tetrahedra (origin, triangle)."""
    a, b, c = (mesh.corners[:, k] for k in range(3))
    volumes = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    return (volumes[:, None] * (a + b + c) / 4.0).sum(axis=0) / volumes.sum()


def shadow_centre(scene: Scene) -> np.ndarray:
    """(2,) floor x, y where the line from the lamp through the glass's volume centroid meets z = 0."""
    lamp = scene.lights[0].position
    centroid = volume_centroid(scene.objects[1].mesh)
    t = lamp[2] / (lamp[2] - centroid[2])
    return (lamp + t * (centroid - lamp))[:2]


def unobstructed_irradiance(scene: Scene, energy: float, xy: np.ndarray) -> np.ndarray:
    """(n,) W/m^2 the lamp alone gives the floor at `xy (n,2)`: I cos(theta) / d^2 = I z / d^3."""
    lamp = scene.lights[0]
    intensity = lamp.power * energy / (4.0 * math.pi)
    d2 = ((xy - lamp.position[:2]) ** 2).sum(axis=1) + lamp.position[2] ** 2
    return intensity * lamp.position[2] / d2 ** 1.5


def cell_centres(imap: IlluminationMap, rows: slice, cols: slice) -> np.ndarray:
    """(h,w,2) chart x, y of the centres of the map's cells [rows, cols]."""
    i = np.arange(imap.shape[0])[rows]
    j = np.arange(imap.shape[1])[cols]
    y = imap.chart.origin[1] + (i + 0.5) * imap.cell
    x = imap.chart.origin[0] + (j + 0.5) * imap.cell
    return np.stack(np.meshgrid(x, y), axis=-1)


def caustic_samples(imap: IlluminationMap) -> tuple[np.ndarray, np.ndarray]:
    """The caustic on a grid of floor points: (xy (n,2), irradiance (n,)
    W/m^2, red channel), at the cell centres inside the box of cells that
    caught light, widened by the adaptive estimate's 16-cell reach. Each
    point stands for one cell of area imap.cell^2."""
    rows, cols = np.nonzero(imap.count > 0)
    if len(rows) == 0:
        return np.zeros((0, 2)), np.zeros(0)
    pad = 16
    box = (slice(max(rows.min() - pad, 0), rows.max() + pad + 1), slice(max(cols.min() - pad, 0), cols.max() + pad + 1))
    xy = cell_centres(imap, *box).reshape(-1, 2)
    return xy, imap.irradiance_at(xy)[:, 0]


def flux_centroid(xy: np.ndarray, irradiance: np.ndarray) -> np.ndarray:
    """(2,) irradiance-weighted mean of the grid points `xy (n,2)`."""
    return (irradiance[:, None] * xy).sum(axis=0) / irradiance.sum()


def flux_radius(xy: np.ndarray, irradiance: np.ndarray, centre: np.ndarray, fraction: float = 0.5) -> float:
    """Radius (m) of the disc about `centre (2,)` that holds `fraction` of the caustic flux on the grid."""
    r = np.linalg.norm(xy - centre, axis=1)
    order = np.argsort(r)
    held = np.cumsum(irradiance[order])
    return float(r[order][np.searchsorted(held, fraction * held[-1])])


@dataclass(frozen=True)
class Caustic:
    """What the paper's readers saw in its tables, measured.

    flux        W landing on the floor after at least one specular event
    peak        W/m^2, the brightest point of the caustic
    whiteness   peak over the lamp's unobstructed irradiance at that point:
                how many times brighter than plain lamp light (the paper's
                "whiter": a display clips it to white sooner)
    r50         m, radius about the flux centroid holding half the flux
    centroid    (2,) m, the flux centroid's floor x, y
    offset      m, the flux centroid's distance from the shadow centre
    """

    flux: float
    peak: float
    whiteness: float
    r50: float
    centroid: tuple[float, float]
    offset: float

    def as_dict(self) -> dict:
        return asdict(self)


def measure(imap: IlluminationMap, scene: Scene, energy: float) -> Caustic:
    """The caustic in the floor map `imap` of `scene` rendered at lamp `energy`."""
    xy, irradiance = caustic_samples(imap)
    top = int(np.argmax(irradiance))
    centroid = flux_centroid(xy, irradiance)
    return Caustic(
        flux=float(irradiance.sum() * imap.cell ** 2),
        peak=float(irradiance[top]),
        whiteness=float(irradiance[top] / unobstructed_irradiance(scene, energy, xy[top:top + 1])[0]),
        r50=flux_radius(xy, irradiance, centroid),
        centroid=(float(centroid[0]), float(centroid[1])),
        offset=float(np.linalg.norm(centroid - shadow_centre(scene))),
    )


def flat_patch(scene: Scene) -> tuple[np.ndarray, float]:
    """(centre (2,), radius m) of a disc of even caustic light under the
    resting cylinder: radius 0.3 paper.RADIUS, centred 0.4 paper.RADIUS from the base's
    centre toward the lamp, clear of the crescent that total internal
    reflection at the far wall folds back and of the base's rim."""
    toward = scene.lights[0].position[:2] / np.linalg.norm(scene.lights[0].position[:2])
    return 0.4 * paper.RADIUS * toward, 0.3 * paper.RADIUS


def noise(imap: IlluminationMap, centre: np.ndarray, radius: float) -> float:
    """Relative noise of the splat map in the disc of `radius` m about
    `centre (2,)`: the standard deviation of its cells' irradiance about the
    least-squares plane through them, over their mean. On even light the
    plane takes out the lamp's slow fall-off and what is left is the
    estimator's noise."""
    xy = cell_centres(imap, slice(None), slice(None))
    inside = np.linalg.norm(xy - centre, axis=-1) < radius
    irradiance = imap.flux[..., 0][inside] / imap.cell ** 2
    basis = np.column_stack([np.ones(inside.sum()), xy[inside]])
    coef, *_ = np.linalg.lstsq(basis, irradiance, rcond=None)
    return float(np.std(irradiance - basis @ coef) / irradiance.mean())


def paraxial_image_distance(scene: Scene) -> float:
    """Distance (m) from the round glass's centre to its paraxial image of
    the lamp, along the lamp's axis: 1 / (1/f - 1/s), f = n R / (2 (n - 1))
    the ball lens's focal length from its centre (both principal planes pass
    through it), s the lamp's distance from the centre."""
    glass = scene.objects[1]
    n = glass.material.ior
    f = n * paper.RADIUS / (2.0 * (n - 1.0))
    s = float(np.linalg.norm(scene.lights[0].position - volume_centroid(glass.mesh)))
    return 1.0 / (1.0 / f - 1.0 / s)


def floor_distance(scene: Scene) -> float:
    """Distance (m) from the glass's volume centroid to the floor along the line from the lamp through it."""
    lamp = scene.lights[0].position
    centroid = volume_centroid(scene.objects[1].mesh)
    return float(np.linalg.norm(centroid - lamp) * centroid[2] / (lamp[2] - centroid[2]))


def reference_r50(scene: Scene, step: float = 1e-3) -> float:
    """r50 (m) of the exact caustic (benchmarks/references/reference.py) of the round
    glass in `scene`, turned so that the lamp sits on the axis: the same
    lamp and floor distances along the line from the lamp through the
    centre, the floor square to it. Annuli `step` m wide out to the floor's
    half-width."""
    glass = scene.objects[1]
    centre_z = floor_distance(scene)
    lamp_distance = float(np.linalg.norm(scene.lights[0].position - volume_centroid(glass.mesh)))
    half = 0.5 * np.ptp(scene.objects[0].mesh.vertices[:, 0])
    edges = np.linspace(0.0, half, int(round(half / step)) + 1)
    exact = reference.ball_lens_irradiance(paper.RADIUS, glass.material.ior, centre_z, centre_z + lamp_distance, 1.0, edges)
    held = np.cumsum(exact.caustic * reference.annulus_areas(edges))
    return float(np.interp(0.5 * held[-1], held, edges[1:]))
