"""The engine's scene model: plain dataclasses of numpy arrays, in world space.

Units follow Blender: metres, radians, watts. Colours are linear Rec.709 RGB,
shape (3,). Everything here is plain data; nothing refers to Blender.

The paper's names are kept where they exist: the camera's FOV, pixx, pixy and
screen size S (`Camera.from_paper`), the lamp's energy (`RenderSettings.energy`),
the number of lamp rays (`RenderSettings.photons`) and the map scale
(`RenderSettings.map_scale`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Optional, Union

import numpy as np

RGB = np.ndarray  # (3,) float64, linear


def rgb(value) -> RGB:
    """A colour from a scalar or a 3-sequence, as a (3,) float64 array."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(3, float(arr))
    if arr.shape != (3,):
        raise ValueError(f"a colour has 3 components, got shape {arr.shape}")
    return arr


@dataclass
class Mesh:
    """A triangle mesh in world space.

    vertices       (nv,3) float64, world space
    triangles      (nt,3) int64, indices into vertices; counter-clockwise seen
                   from outside, as Blender stores them
    corner_normals (nt,3,3) float64 unit normals per triangle corner (smooth or
                   custom shading), or None for flat shading
    corner_uvs     (nt,3,2) float64 texture coordinates per corner, or None
    """

    vertices: np.ndarray
    triangles: np.ndarray
    corner_normals: Optional[np.ndarray] = None
    corner_uvs: Optional[np.ndarray] = None

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        if self.corner_normals is not None:
            self.corner_normals = np.ascontiguousarray(self.corner_normals, dtype=np.float64).reshape(-1, 3, 3)
        if self.corner_uvs is not None:
            self.corner_uvs = np.ascontiguousarray(self.corner_uvs, dtype=np.float64).reshape(-1, 3, 2)

    @property
    def corners(self) -> np.ndarray:
        """(nt,3,3) world positions of each triangle's corners."""
        return np.take(self.vertices, self.triangles, axis=0)

    def transformed(self, matrix: np.ndarray) -> "Mesh":
        """This mesh under a (4,4) affine matrix; normals go by its inverse transpose."""
        m = np.asarray(matrix, dtype=np.float64)
        verts = self.vertices @ m[:3, :3].T + m[:3, 3]
        normals = None
        if self.corner_normals is not None:
            nmat = np.linalg.inv(m[:3, :3]).T
            normals = self.corner_normals @ nmat.T
            normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
        tris = self.triangles if np.linalg.det(m[:3, :3]) > 0 else self.triangles[:, ::-1]
        if normals is not None and tris is not self.triangles:
            normals = normals[:, ::-1]
        uvs = None
        if self.corner_uvs is not None:
            uvs = self.corner_uvs if tris is self.triangles else self.corner_uvs[:, ::-1]
        return Mesh(verts, tris, normals, uvs)


@dataclass
class Dielectric:
    """Clear or coloured glass, water, gems: refracts and reflects (Fresnel).

    ior           index of refraction relative to the surrounding medium: 1.33
                  water, 1.5 glass, 1.9 cubic zirconia, 2.41 diamond; below 1 for
                  an air bubble in water (1/1.33)
    color         tint applied at every reflection and refraction, as the
                  colour of Blender's Glass BSDF
    absorption    (3,) Beer-Lambert absorption coefficient, per metre, inside
                  (optics.absorption_from_color turns a colour at a distance
                  into one)
    abbe          Abbe number V_d: the IOR follows Cauchy's law through `ior`
                  at 587.6 nm with this dispersion (optics.cauchy_ior); 55
                  diamond, 58 crown glass, 33 cubic zirconia; inf for none
    """

    ior: float = 1.5
    color: RGB = field(default_factory=lambda: np.ones(3))
    absorption: RGB = field(default_factory=lambda: np.zeros(3))
    abbe: float = math.inf

    def __post_init__(self):
        self.color = rgb(self.color)
        self.absorption = rgb(self.absorption)


@dataclass
class Diffuse:
    """An opaque Lambertian surface with an optional Blinn-Phong highlight.

    albedo        (3,) diffuse reflectance
    specular      (3,) specular colour (0 for none)
    exponent      Blinn-Phong exponent
    receiver      whether it collects caustics into an illumination map
    """

    albedo: RGB = field(default_factory=lambda: np.full(3, 0.8))
    specular: RGB = field(default_factory=lambda: np.zeros(3))
    exponent: float = 50.0
    receiver: bool = True

    def __post_init__(self):
        self.albedo = rgb(self.albedo)
        self.specular = rgb(self.specular)


@dataclass
class Reflector:
    """A specular mirror or polished metal: every ray reflects, r = d - 2 (d.n) n
    about the shading normal, and its colour is multiplied by `color`.

    color         (3,) reflectance, the same at every angle (a metal's
                  Schlick/F82 rise toward grazing incidence is ignored)

    It is perfectly smooth: the add-on names glossy materials with a
    roughness above 0 in a warning, as it does rough glass.
    """

    color: RGB = field(default_factory=lambda: np.full(3, 0.9))

    def __post_init__(self):
        self.color = rgb(self.color)


Material = Union[Dielectric, Diffuse, Reflector]


@dataclass
class Object:
    name: str
    mesh: Mesh
    material: Material

    @property
    def is_transparent(self) -> bool:
        return isinstance(self.material, Dielectric)

    @property
    def is_reflector(self) -> bool:
        return isinstance(self.material, Reflector)

    @property
    def is_caster(self) -> bool:
        """Casts caustics: a specular surface, transparent or reflecting."""
        return isinstance(self.material, (Dielectric, Reflector))

    @property
    def is_receiver(self) -> bool:
        return isinstance(self.material, Diffuse) and self.material.receiver


@dataclass
class PointLight:
    """Blender's point lamp of radius 0: power in W, radiant intensity
    I = color * power / (4 pi) W/sr in every direction (see units.py)."""

    position: np.ndarray
    power: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Point"

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        self.color = rgb(self.color)


@dataclass
class SpotLight:
    """Blender's spot lamp: a point lamp masked to a cone.

    direction     unit axis of the cone, pointing where the light goes
    spot_size     full cone angle, radians (Blender's Spot Size)
    blend         softness of the cone's edge, 0..1 (Blender's Blend)
    """

    position: np.ndarray
    direction: np.ndarray
    power: float
    spot_size: float = math.radians(45.0)
    blend: float = 0.15
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Spot"

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        d = np.asarray(self.direction, dtype=np.float64).reshape(3)
        self.direction = d / np.linalg.norm(d)
        self.color = rgb(self.color)


@dataclass
class SunLight:
    """Blender's sun: parallel light of irradiance `strength` W/m^2 on a
    surface facing it.

    direction     unit vector the light travels along (Blender's -Z of the lamp)
    """

    direction: np.ndarray
    strength: float
    color: RGB = field(default_factory=lambda: np.ones(3))
    name: str = "Sun"

    def __post_init__(self):
        d = np.asarray(self.direction, dtype=np.float64).reshape(3)
        self.direction = d / np.linalg.norm(d)
        self.color = rgb(self.color)


Light = Union[PointLight, SpotLight, SunLight]


@dataclass
class Camera:
    """A camera as Blender's: it looks down its local -Z with +Y up.

    matrix        (4,4) camera-to-world, rotation and translation only
    kind          'PERSP' (pinhole) or 'ORTHO'
    fov           full field of view along the sensor-fit axis, radians
    ortho_scale   width of the view along the sensor-fit axis, metres
    sensor_fit    'AUTO' (the larger image side), 'HORIZONTAL' or 'VERTICAL'
    shift_x/y     lens shift, in units of the sensor-fit side, as Blender's
    pixx, pixy    image width and height in pixels (the paper's names)
    """

    matrix: np.ndarray
    pixx: int = 640
    pixy: int = 480
    kind: Literal["PERSP", "ORTHO"] = "PERSP"
    fov: float = math.radians(39.6)
    ortho_scale: float = 6.0
    sensor_fit: Literal["AUTO", "HORIZONTAL", "VERTICAL"] = "AUTO"
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 1e-3
    clip_end: float = 1e30

    def __post_init__(self):
        self.matrix = np.asarray(self.matrix, dtype=np.float64).reshape(4, 4)

    @property
    def position(self) -> np.ndarray:
        return self.matrix[:3, 3]

    @staticmethod
    def look_at(eye, target, up=(0.0, 0.0, 1.0), **kwargs) -> "Camera":
        """A camera at `eye` looking at `target`, with `up` as near to its +Y as possible."""
        eye = np.asarray(eye, dtype=np.float64)
        back = eye - np.asarray(target, dtype=np.float64)
        if not np.linalg.norm(back) > 0:
            raise ValueError("camera: the eye and the point it looks at must differ")
        back /= np.linalg.norm(back)
        right = np.cross(np.asarray(up, dtype=np.float64), back)
        if np.linalg.norm(right) < 1e-9:
            right = np.cross(np.array([0.0, 1.0, 0.0]), back)
        right /= np.linalg.norm(right)
        matrix = np.eye(4)
        matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = right, np.cross(back, right), back, eye
        return Camera(matrix=matrix, **kwargs)

    @staticmethod
    def from_paper(FOV, pixx, pixy, S, eye, target, up=(0.0, 0.0, 1.0)) -> "Camera":
        """The paper's camera: FOV in degrees across the width, an image of
        pixx x pixy pixels and a screen of width S world units.

        The screen sits at distance S / (2 tan(FOV/2)) from the eye, so S
        scales the screen and its distance together; for a pinhole the image
        does not depend on it.
        """
        if S <= 0:
            raise ValueError("screen size S must be positive")
        return Camera.look_at(eye, target, up, pixx=int(pixx), pixy=int(pixy), fov=math.radians(FOV),
                              sensor_fit="HORIZONTAL")


@dataclass
class Scene:
    objects: list[Object]
    lights: list[Light]
    camera: Camera
    ambient: RGB = field(default_factory=lambda: np.zeros(3))
    background: RGB = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        self.ambient = rgb(self.ambient)
        self.background = rgb(self.background)

    @property
    def transparent(self) -> list[Object]:
        return [o for o in self.objects if o.is_transparent]

    @property
    def casters(self) -> list[Object]:
        """The objects that cast caustics: dielectrics and reflectors."""
        return [o for o in self.objects if o.is_caster]

    @property
    def receivers(self) -> list[Object]:
        return [o for o in self.objects if o.is_receiver]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (3,), hi (3,)) of all geometry."""
        pts = np.concatenate([o.mesh.vertices for o in self.objects]) if self.objects else np.zeros((1, 3))
        return pts.min(axis=0), pts.max(axis=0)

    def extent(self) -> float:
        """Diagonal of the geometry's bounding box: the length the epsilons scale with."""
        lo, hi = self.bounds()
        return float(max(np.linalg.norm(hi - lo), 1e-12))


# Each level of beam refinement can quadruple a diverging cell's paths.
MAX_BEAM_REFINEMENT = 5


@dataclass
class RenderSettings:
    """What the user tunes. Defaults are the ones the accuracy benchmark chose.

    photons       lamp rays per lamp (the paper's "jumlah sinar lampu"; it used 40,000)
    emission      'targeted': only toward the casters (transparent and
                  reflecting objects); 'sphere': the
                  paper's eq. (1) over the whole sphere of directions
    energy        multiplier on every lamp's power (the paper's lamp energy)
    map_scale     edge of one illumination-map cell in millimetres of world
                  space (the paper's map scale, 5 or 40), or None for the
                  adaptive estimate that needs no tuning
    density       'splat' (the paper's bilinear map), 'adaptive' (k nearest
                  photons, on the map's grid) or 'beam' (photons on a grid
                  whose neighbours bound beams: no noise; beams.py)
    beam_refinement  times a beam grid cell is split in four where its
                  paths diverge (0 for a plain grid)
    max_depth     specular bounces per photon and per eye ray
    spp           eye samples per pixel
    bands         wavelength bands traced when a material disperses
                  (spectrum.py); one band, and no cost, when none does
    """

    photons: int = 40_000
    emission: Literal["targeted", "sphere"] = "targeted"
    energy: float = 1.0
    map_scale: Optional[float] = None
    density: Literal["splat", "adaptive", "beam"] = "beam"
    k_nearest: int = 64
    beam_refinement: int = 1
    max_depth: int = 12
    spp: int = 4
    seed: int = 0
    chunk_size: int = 1 << 17
    threads: int = 2
    map_resolution_limit: int = 1024
    bands: int = 6

    def validate(self) -> None:
        """Raise ValueError naming the field that is out of range."""
        checks = [
            ("photons", self.photons >= 0, "must be >= 0"),
            ("seed", self.seed >= 0, "must be >= 0"),
            ("emission", self.emission in ("targeted", "sphere"), "must be 'targeted' or 'sphere'"),
            ("energy", math.isfinite(self.energy) and self.energy >= 0, "must be a finite number >= 0"),
            ("map_scale", self.map_scale is None or (math.isfinite(self.map_scale) and self.map_scale > 0),
             "must be a positive number of millimetres"),
            ("density", self.density in ("splat", "adaptive", "beam"), "must be 'splat', 'adaptive' or 'beam'"),
            ("k_nearest", self.k_nearest >= 1, "must be >= 1"),
            ("beam_refinement", 0 <= self.beam_refinement <= MAX_BEAM_REFINEMENT,
             f"must be in 0..{MAX_BEAM_REFINEMENT}"),
            ("max_depth", self.max_depth >= 1, "must be >= 1"),
            ("spp", self.spp >= 1, "must be >= 1"),
            ("chunk_size", self.chunk_size >= 1, "must be >= 1"),
            ("threads", self.threads >= 1, "must be >= 1"),
            ("bands", 1 <= self.bands <= 64, "must be in 1..64"),
        ]
        for name, ok, why in checks:
            if not ok:
                raise ValueError(f"{name} {why} (got {getattr(self, name)!r})")
