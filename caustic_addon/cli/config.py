"""The CLI's scene file: the paper's inputs in TOML, checked and turned into
a `Config`, which becomes a `Scene` once the mesh is read.

Every table and key, with its unit; [default], and no default means required.
Colours are linear RGB, a number (grey) or [r, g, b]. Positions are metres.

[camera]       the paper's eye, a pinhole
  FOV          degrees across the image width, 0 < FOV < 180
  pixx         image width, pixels >= 1
  pixy         image height, pixels >= 1
  S            screen width, world units > 0 [1.0]; a pinhole image does not
               depend on it
  eye          [x, y, z], the eye's position
  look_at      [x, y, z], the point at the image's centre
  up           [x, y, z], the direction that appears up [[0, 0, 1]]

[plane]        the diffuse floor that receives the caustics: a square
               centred under the origin, facing +z
  size         edge length, metres > 0 [10.0]
  height       z of the plane, metres [0.0]
  albedo       diffuse reflectance, 0..1 [0.8]

[lamp]         one lamp, as Blender's; the keys depend on its type
  type         "point" | "spot" | "sun" | "area" ["point"]
  position     [x, y, z] (point, spot, area: its centre; required)
  power        watts >= 0, as Blender's Power (point, spot, area; required)
  direction    [x, y, z], the way the light travels (spot, sun, area: the
               way it faces; required)
  radius       metres >= 0, Blender's Radius (point, spot) [0.0]
  soft_falloff true: the lamp is a disc facing each point it lights;
               false: a sphere (point, spot) [true]
  spot_size    full cone angle, degrees, 0 < spot_size <= 180 (spot) [45.0]
  blend        softness of the cone's edge, 0..1 (spot) [0.15]
  strength     W/m^2 >= 0 on a surface facing the sun, as Blender's Strength
               (sun; required)
  angle        degrees the sun's disc spans, 0..180 (sun) [0.0]
  shape        "square" | "rectangle" | "disk" | "ellipse" (area) ["square"]
  size         metres > 0, the edge or diameter along the lamp's x (area)
               [1.0]
  size_y       metres > 0 along its y (area: rectangle, ellipse) [size]
  up           [x, y, z], the way the lamp's y points, made square to
               direction (area) [[0, 1, 0], or [1, 0, 0] facing along y]
  spread       degrees of the cone it emits into, 0..180 (area) [180.0]
  color        colour >= 0 [1.0]
  visible_camera, visible_glossy, visible_transmission
               whether the camera, reflections and refractions see the lamp
               itself (point, spot and area with a size, sun with an
               angle), as Blender's Ray Visibility [false, true, true]

[photons]      the paper's photon pass
  lamp_rays    rays traced from the lamp, integer >= 0; the paper used
               40,000 [40000]
  energy       the paper's lamp energy (10 and 20 in its experiments): a
               multiplier >= 0 on the lamp's power or strength [1.0]
  map_scale    millimetres per illumination-map cell, > 0 (the paper's 5
               and 40), or "auto" for the adaptive estimate ["auto"]
  density      "splat" (the paper's bilinear map) | "adaptive" (the k
               nearest photons) | "beam" (lamp rays on a grid bound beams:
               no noise) ["beam", as the engine and the add-on]
  k_nearest    photons per adaptive estimate, integer >= 1 [64]
  beam_refinement  times a beam cell is split where its paths diverge,
               integer in 0..5 [1]
  emission     "targeted" (only toward the object) | "sphere" (the paper's
               eq. 1, every direction) ["targeted"]
  bands        wavelength bands traced when the object disperses (abbe),
               integer 1..64 [6]

[object]       the caster: scaled about its origin, then moved
  material     "glass" (refracts and reflects) | "reflector" (a perfect
               mirror or polished metal) ["glass"]
  ior          index of refraction > 0: 1.33 water, 1.5 glass, 1.9 cubic
               zirconia, 2.41 diamond (glass) [1.5]
  position     [x, y, z] where the mesh's origin goes; the paper's object
               height is its z [[0, 0, 0]]
  scale        a number > 0 or [x, y, z] of them [1.0]
  color        glass: tint at each reflection and refraction; reflector:
               its reflectance, the same at every angle; 0..1 [1.0]
  absorption   Beer-Lambert coefficient inside, per metre, >= 0 (glass) [0.0]
  absorption_color     instead of absorption: the colour white light takes
               after absorption_distance inside, each in (0, 1] (glass)
  absorption_distance  metres > 0 at which absorption_color is reached [1.0]
  abbe         Abbe number V_d > 0, dispersion around the IOR (given at
               587.6 nm): 55 diamond, 58 crown glass, 33 cubic zirconia;
               inf for none (glass) [inf]
  roughness    Blender's Roughness, 0..1: GGX microfacets of width
               roughness^2 (Multiscatter GGX) blur the caustic [0.0]

[render]
  spp          eye samples per pixel, integer >= 1 [4]
  max_depth    specular bounces per photon and eye ray, integer >= 1 [12]
  ambient      ambient light: diffuse surfaces add ambient * albedo to
               their radiance, W/(m^2 sr), colour >= 0 [0.0]
  world        the world's radiance, W/(m^2 sr): eye rays that leave the
               scene see it, and it lights the surfaces, as Cycles' world;
               colour >= 0 [0.0]
  seed         random seed, integer >= 0 [0]
  threads      worker threads, integer >= 1 [2]
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from ..optics.media import absorption_from_color
from ..scene import (AreaLight, Camera, Dielectric, Diffuse, Light, Mesh, Object, PointLight, Reflector,
                     RenderSettings, Scene, SpotLight, SunLight, Visibility, World, shapes)
from ..scene.color import RGB
from ..scene.settings import MAX_BEAM_REFINEMENT

_REQUIRED = object()


class ConfigError(ValueError):
    """The scene file cannot be used; the message names the file and the
    field as table.key."""


@dataclass(frozen=True)
class Field:
    """One key: `parse` returns its value or raises ValueError; `must` says
    what a valid value is, for messages."""

    parse: Callable[[Any], Any]
    must: str
    default: Any = _REQUIRED


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _require(ok: bool) -> None:
    if not ok:
        raise ValueError


def integer(minimum: int, default=_REQUIRED, maximum: Optional[int] = None) -> Field:
    def parse(value):
        _require(isinstance(value, int) and not isinstance(value, bool) and value >= minimum
                 and (maximum is None or value <= maximum))
        return value
    bounds = f">= {minimum}" if maximum is None else f"in {minimum}..{maximum}"
    return Field(parse, f"must be an integer {bounds}", default)


def number(condition: str = "", test: Callable[[float], bool] = lambda x: True, default=_REQUIRED) -> Field:
    """A finite number; `condition` describes `test` in messages, e.g. '> 0'."""
    def parse(value):
        _require(_is_number(value) and test(value))
        return float(value)
    return Field(parse, f"must be a number {condition}".rstrip(), default)


def vector(nonzero: bool = False, default=_REQUIRED) -> Field:
    def parse(value):
        _require(isinstance(value, list) and len(value) == 3 and all(map(_is_number, value)))
        array = np.array(value, dtype=np.float64)
        _require(not nonzero or np.any(array != 0))
        return array
    return Field(parse, "must be a non-zero [x, y, z]" if nonzero else "must be [x, y, z], 3 numbers", default)


def triple(condition: str, test: Callable[[float], bool], default=_REQUIRED) -> Field:
    """A number or [a, b, c], each passing `test`, as a (3,) array."""
    def parse(value):
        values = value if isinstance(value, list) and len(value) == 3 else [value]
        _require(all(_is_number(v) and test(v) for v in values))
        return np.broadcast_to(np.array(values, dtype=np.float64), 3).copy()
    return Field(parse, f"must be a number {condition} or a list of 3 of them", default)


def boolean(default=_REQUIRED) -> Field:
    def parse(value):
        _require(isinstance(value, bool))
        return value
    return Field(parse, "must be true or false", default)


def choice(*options: str, default=_REQUIRED) -> Field:
    def parse(value):
        _require(value in options)
        return value
    return Field(parse, "must be " + " or ".join(f'"{o}"' for o in options), default)


def map_scale(default=_REQUIRED) -> Field:
    """Millimetres per cell, or "auto" (None)."""
    def parse(value):
        if value == "auto":
            return None
        _require(_is_number(value) and value > 0)
        return float(value)
    return Field(parse, 'must be a number of millimetres > 0 or "auto"', default)


def abbe_number(default=_REQUIRED) -> Field:
    """A number > 0; inf (no dispersion) allowed."""
    def parse(value):
        _require(isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0)
        return float(value)
    return Field(parse, "must be a number > 0, or inf for no dispersion", default)


def _positive(x):
    return x > 0


def _non_negative(x):
    return x >= 0


def _unit(x):
    return 0 <= x <= 1


SCHEMA: dict[str, dict[str, Field]] = {
    "camera": {
        "FOV": number("> 0 and < 180", lambda x: 0 < x < 180),
        "pixx": integer(1),
        "pixy": integer(1),
        "S": number("> 0", _positive, 1.0),
        "eye": vector(),
        "look_at": vector(),
        "up": vector(nonzero=True, default=np.array([0.0, 0.0, 1.0])),
    },
    "plane": {
        "size": number("> 0", _positive, 10.0),
        "height": number(default=0.0),
        "albedo": triple("in 0..1", _unit, np.full(3, 0.8)),
    },
    "lamp": {
        "type": choice("point", "spot", "sun", "area", default="point"),
        "position": vector(),
        "power": number(">= 0", _non_negative),
        "direction": vector(nonzero=True),
        "radius": number(">= 0", _non_negative, 0.0),
        "soft_falloff": boolean(True),
        "spot_size": number("> 0 and <= 180", lambda x: 0 < x <= 180, 45.0),
        "blend": number("in 0..1", _unit, 0.15),
        "strength": number(">= 0", _non_negative),
        "angle": number("in 0..180", lambda x: 0 <= x <= 180, 0.0),
        "shape": choice("square", "rectangle", "disk", "ellipse", default="square"),
        "size": number("> 0", _positive, 1.0),
        "size_y": number("> 0", _positive, None),
        "up": vector(nonzero=True, default=None),
        "spread": number("in 0..180", lambda x: 0 <= x <= 180, 180.0),
        "color": triple(">= 0", _non_negative, np.ones(3)),
        "visible_camera": boolean(False),
        "visible_glossy": boolean(True),
        "visible_transmission": boolean(True),
    },
    "photons": {
        "lamp_rays": integer(0, RenderSettings.lamp_rays),
        "energy": number(">= 0", _non_negative, 1.0),
        "map_scale": map_scale(None),
        "density": choice("splat", "adaptive", "beam", default=RenderSettings.density),
        "k_nearest": integer(1, 64),
        "beam_refinement": integer(0, 1, MAX_BEAM_REFINEMENT),
        "emission": choice("targeted", "sphere", default="targeted"),
        "bands": integer(1, 6, maximum=64),
    },
    "object": {
        "material": choice("glass", "reflector", default="glass"),
        "ior": number("> 0", _positive, 1.5),
        "position": vector(default=np.zeros(3)),
        "scale": triple("> 0", _positive, np.ones(3)),
        "color": triple("in 0..1", _unit, np.ones(3)),
        "absorption": triple(">= 0", _non_negative, np.zeros(3)),
        "absorption_color": triple("in (0, 1]", lambda x: 0 < x <= 1, None),
        "absorption_distance": number("> 0", _positive, 1.0),
        "abbe": abbe_number(math.inf),
        "roughness": number("in 0..1", _unit, 0.0),
    },
    "render": {
        "spp": integer(1, 4),
        "max_depth": integer(1, 12),
        "ambient": triple(">= 0", _non_negative, np.zeros(3)),
        "world": triple(">= 0", _non_negative, np.zeros(3)),
        "seed": integer(0, 0),
        "threads": integer(1, 2),
    },
}

# The keys each object material takes.
# Keys of earlier versions: (table, old key) -> the key that took its place.
RENAMED = {("photons", "count"): "photons.lamp_rays", ("render", "background"): "render.world"}

OBJECT_KEYS = {
    "glass": ("material", "ior", "position", "scale", "color", "absorption", "absorption_color",
              "absorption_distance", "abbe", "roughness"),
    "reflector": ("material", "position", "scale", "color", "roughness"),
}

# The keys each lamp type takes.
LAMP_VISIBILITY_KEYS = ("visible_camera", "visible_glossy", "visible_transmission")
LAMP_KEYS = {
    "point": ("type", "position", "power", "radius", "soft_falloff", "color", *LAMP_VISIBILITY_KEYS),
    "spot": ("type", "position", "direction", "power", "radius", "soft_falloff", "spot_size", "blend", "color",
             *LAMP_VISIBILITY_KEYS),
    "sun": ("type", "direction", "strength", "angle", "color", *LAMP_VISIBILITY_KEYS),
    "area": ("type", "position", "direction", "power", "shape", "size", "size_y", "up", "spread", "color",
             *LAMP_VISIBILITY_KEYS),
}


@dataclass
class Config:
    """A checked scene file: everything but the mesh.

    placement   (4,4) mesh-to-world matrix: scale, then translate
    """

    camera: Camera
    floor: Object
    lamp: Light
    material: Dielectric | Reflector
    placement: np.ndarray
    ambient: RGB
    world: RGB
    settings: RenderSettings

    def scene(self, mesh: Mesh, name: str = "Object") -> Scene:
        """The scene with `mesh`, given in its own coordinates, as the object."""
        glass = Object(name, mesh.transformed(self.placement), self.material)
        return Scene([self.floor, glass], [self.lamp], self.camera, self.ambient, World(self.world))


def load(path) -> Config:
    """The scene file at `path`; raises ConfigError naming the file and the
    line (for TOML syntax) or the field."""
    try:
        text = Path(path).read_bytes().decode("utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the scene file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: the scene file is not UTF-8 text ({exc.reason})") from None
    return parse(text, str(path))


def parse(text: str, name: str = "<config>") -> Config:
    """The scene in TOML `text`; `name` is the file named in errors."""
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{name}: {exc}") from None
    for key, value in document.items():
        if key not in SCHEMA:
            what = f"table [{key}]" if isinstance(value, dict) else f"key {key}"
            raise ConfigError(f"{name}: unknown {what} (the tables are {', '.join(f'[{t}]' for t in SCHEMA)})")
    tables = {table: _table(document, table, name) for table in SCHEMA}
    camera, plane, lamp, photons = tables["camera"], tables["plane"], tables["lamp"], tables["photons"]
    obj, render = tables["object"], tables["render"]

    if np.array_equal(camera["eye"], camera["look_at"]):
        raise ConfigError(f"{name}: camera.look_at must differ from camera.eye")
    settings = RenderSettings(
        lamp_rays=photons["lamp_rays"], emission=photons["emission"], energy=photons["energy"],
        map_scale=photons["map_scale"], density=photons["density"], k_nearest=photons["k_nearest"],
        beam_refinement=photons["beam_refinement"],
        max_depth=render["max_depth"], spp=render["spp"], seed=render["seed"], threads=render["threads"],
        bands=photons["bands"])
    placement = np.diag(np.append(obj["scale"], 1.0))
    placement[:3, 3] = obj["position"]
    return Config(
        camera=Camera.from_paper(camera["FOV"], camera["pixx"], camera["pixy"], camera["S"], camera["eye"],
                                 camera["look_at"], camera["up"]),
        floor=Object("Plane", shapes.plane(plane["size"], (0.0, 0.0, plane["height"])), Diffuse(plane["albedo"])),
        lamp=_lamp(lamp, name),
        material=(Reflector(obj["color"], obj["roughness"]) if obj["material"] == "reflector"
                  else Dielectric(obj["ior"], reflection_tint=obj["color"], transmission_tint=obj["color"],
                                  absorption=_glass_absorption(obj, document, name), abbe=obj["abbe"],
                                  roughness=obj["roughness"])),
        placement=placement,
        ambient=render["ambient"],
        world=render["world"],
        settings=settings,
    )


def _glass_absorption(obj: dict, document: dict, name: str) -> np.ndarray:
    """(3,) per metre: object.absorption, or converted from
    object.absorption_color at absorption_distance; not both."""
    if obj["absorption_color"] is None:
        return obj["absorption"]
    if "absorption" in document.get("object", {}):
        raise ConfigError(f"{name}: object.absorption and object.absorption_color both set the absorption: "
                          "give one")
    return absorption_from_color(obj["absorption_color"], obj["absorption_distance"])


def _table(document: dict, table: str, name: str) -> dict:
    """The checked values of `table`, defaults filled in. A lamp takes only
    the keys of its type, an object those of its material."""
    raw = document.get(table, {})
    if not isinstance(raw, dict):
        raise ConfigError(f"{name}: {table} must be a table, [{table}]")
    fields, owner = SCHEMA[table], f"[{table}]"
    if table == "lamp":
        kind = _value(fields["type"], raw, "lamp", "type", name)
        fields, owner = {key: fields[key] for key in LAMP_KEYS[kind]}, f"a {kind} lamp"
    if table == "object":
        kind = _value(fields["material"], raw, "object", "material", name)
        fields, owner = {key: fields[key] for key in OBJECT_KEYS[kind]}, f"a {kind} object"
    for key in raw:
        if (table, key) in RENAMED:
            raise ConfigError(f"{name}: {table}.{key} is now {RENAMED[table, key]}: rename the key")
        if key not in fields:
            raise ConfigError(f"{name}: unknown key {table}.{key} (the keys of {owner} are {', '.join(fields)})")
    return {key: _value(field, raw, table, key, name) for key, field in fields.items()}


def _value(field: Field, raw: dict, table: str, key: str, name: str) -> Any:
    if key not in raw:
        if field.default is _REQUIRED:
            raise ConfigError(f"{name}: {table}.{key} is missing: it {field.must}")
        return field.default.copy() if isinstance(field.default, np.ndarray) else field.default
    try:
        return field.parse(raw[key])
    except ValueError:
        got = json.dumps(raw[key], default=str)
        raise ConfigError(f"{name}: {table}.{key} {field.must} (got {got})") from None


def _lamp(lamp: dict, name: str) -> Light:
    seen = Visibility(camera=lamp["visible_camera"], glossy=lamp["visible_glossy"],
                      transmission=lamp["visible_transmission"])
    return replace(_lamp_of_type(lamp, name), visibility=seen)


def _lamp_of_type(lamp: dict, name: str) -> Light:
    if lamp["type"] == "point":
        return PointLight(lamp["position"], lamp["power"], lamp["color"], radius=lamp["radius"],
                          soft_falloff=lamp["soft_falloff"])
    if lamp["type"] == "spot":
        return SpotLight(lamp["position"], lamp["direction"], lamp["power"], math.radians(lamp["spot_size"]),
                         lamp["blend"], lamp["color"], radius=lamp["radius"], soft_falloff=lamp["soft_falloff"])
    if lamp["type"] == "sun":
        return SunLight(lamp["direction"], lamp["strength"], lamp["color"], angle=math.radians(lamp["angle"]))
    return _area_lamp(lamp, name)


def _area_lamp(lamp: dict, name: str) -> AreaLight:
    """The area lamp of `lamp`'s keys: its x square to `up` and `direction`."""
    normal = lamp["direction"] / np.linalg.norm(lamp["direction"])
    up = lamp["up"]
    if up is None:
        up = np.array([1.0, 0.0, 0.0]) if abs(normal[1]) > 0.9 else np.array([0.0, 1.0, 0.0])
    along_y = up - (up @ normal) * normal
    if np.linalg.norm(along_y) < 1e-6 * np.linalg.norm(up):
        raise ConfigError(f"{name}: lamp.up must not be parallel to lamp.direction")
    along_y /= np.linalg.norm(along_y)
    along_x = np.cross(normal, along_y)
    size_y = lamp["size"] if lamp["size_y"] is None or lamp["shape"] in ("square", "disk") else lamp["size_y"]
    return AreaLight(lamp["position"], 0.5 * lamp["size"] * along_x, 0.5 * size_y * along_y, normal, lamp["power"],
                     "RECTANGLE" if lamp["shape"] in ("square", "rectangle") else "ELLIPSE",
                     math.radians(lamp["spread"]), lamp["color"])
