"""A surface's colour from nodes, as Cycles evaluates Blender's shader
nodes: an Image Texture on a UV map or on Generated or Object coordinates,
through a Mapping node, and the simple nodes artists chain after it (RGB,
Mix Color, Math, Color Ramp). Each node's `evaluate(at)` gives its output at
the shading points `at`: (n,3) for a colour, (n,) for a value; where one is
given for the other, Cycles' conversions apply (a colour's value is its
Rec.709 luminance, a value's colour is grey)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Union

import numpy as np

from ..util.image_lookup import EXTENSIONS, INTERPOLATIONS, lookup
from ..util.jit import inline, kernel
from ..util.rows import contiguous

__all__ = ["EXTENSIONS", "INTERPOLATIONS", "MATH", "MIX_BLENDS", "ColorRamp", "Constant", "ImageTexture", "MathNode",
           "MixColor", "Node", "SurfacePoints", "as_color", "as_value", "srgb_to_linear"]

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@dataclass
class SurfacePoints:
    """Where a surface is shaded: `points (n,3)` world, `triangle (n,)` the
    index of the triangle in its object's mesh, `u, v (n,)` Embree's
    barycentrics (p = (1-u-v) p0 + u p1 + v p2)."""

    points: np.ndarray
    triangle: np.ndarray
    u: np.ndarray
    v: np.ndarray


def srgb_to_linear(encoded: np.ndarray) -> np.ndarray:
    """The sRGB transfer function's inverse (IEC 61966-2-1)."""
    return np.where(encoded <= 0.04045, encoded / 12.92, ((np.maximum(encoded, 0.04045) + 0.055) / 1.055) ** 2.4)


def as_color(value: np.ndarray) -> np.ndarray:
    """(n,3) of a node output, a value turned grey."""
    return value if value.ndim == 2 else np.repeat(value[:, None], 3, axis=1)


def as_value(value: np.ndarray) -> np.ndarray:
    """(n,) of a node output, a colour turned into its luminance."""
    return value @ LUMINANCE if value.ndim == 2 else value


@dataclass
class Constant:
    """An unlinked input or an RGB node: `value` a float or (3,) colour."""

    value: Union[float, np.ndarray]

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        value = np.asarray(self.value, dtype=np.float64)
        return np.broadcast_to(value, (len(at.points),) + value.shape).copy()


@dataclass
class ImageTexture:
    """Blender's Image Texture node with flat projection.

    pixels         (h,w,c) row 0 at v = 0 (Blender's order): float32, or
                   uint8 for an 8-bit image (its bytes, a quarter of the memory)
    coordinates    'UV', 'GENERATED' or 'OBJECT': the vector it looks up
    corner_uvs     (nt,3,2) the UV map's coordinates at each triangle's corners (UV)
    to_object      (4,4) world to object space (GENERATED, OBJECT)
    texspace_location, texspace_size  (3,) the mesh's texture space, centre
                   and half-size: Generated = (p_object - location) / (2 size) + 1/2
    mapping        (4,4) a Mapping node's affine map of the vector
    interpolation  'Closest', 'Linear', 'Cubic' or 'Smart' (Cubic)
    extension      'REPEAT', 'EXTEND', 'CLIP' or 'MIRROR'
    alpha          the Alpha output instead of the Color
    srgb           the pixels are sRGB-encoded (an 8-bit sRGB image), decoded
                   after the look-up, as Cycles does (NODE_IMAGE_COMPRESS_AS_SRGB
                   in kernel/svm/image.h): interpolating the encoded values
                   gives a darker blend than interpolating linear ones
    """

    pixels: np.ndarray
    coordinates: str = "UV"
    corner_uvs: Optional[np.ndarray] = None
    to_object: np.ndarray = field(default_factory=lambda: np.eye(4))
    texspace_location: np.ndarray = field(default_factory=lambda: np.zeros(3))
    texspace_size: np.ndarray = field(default_factory=lambda: np.ones(3))
    mapping: np.ndarray = field(default_factory=lambda: np.eye(4))
    interpolation: str = "Linear"
    extension: str = "REPEAT"
    alpha: bool = False
    srgb: bool = False

    def __post_init__(self):
        self.pixels = np.ascontiguousarray(self.pixels)

    def vectors(self, at: SurfacePoints) -> np.ndarray:
        """(n,3) the texture coordinates the node looks up, after mapping."""
        out = np.empty((len(at.points), 3))
        uvs = contiguous(self.corner_uvs, np.float64) if self.coordinates == "UV" else _NO_UVS
        _mapped_vectors(out, contiguous(at.points, np.float64), contiguous(at.triangle, np.int64),
                        contiguous(at.u, np.float64), contiguous(at.v, np.float64), uvs,
                        contiguous(self.to_object, np.float64), contiguous(self.texspace_location, np.float64),
                        contiguous(self.texspace_size, np.float64), contiguous(self.mapping, np.float64),
                        _COORDINATES.index(self.coordinates))
        return out

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        texel = lookup(self.pixels, self.vectors(at)[:, :2], self.interpolation, self.extension)
        if self.pixels.dtype == np.uint8:
            texel = texel / 255.0
        if self.alpha:
            return texel[:, 3] if self.pixels.shape[2] == 4 else np.ones(len(texel))
        return srgb_to_linear(texel[:, :3]) if self.srgb else texel[:, :3]


_COORDINATES = ("UV", "OBJECT", "GENERATED")
_UV, _OBJECT, _GENERATED = range(3)
_NO_UVS = np.zeros((0, 3, 2))


@inline
def affine1(m, p):
    """The 3-tuple m[:3, :3] p + m[:3, 3] of the (4,4) affine map `m` at the 3-tuple `p`."""
    return (m[0, 0] * p[0] + m[0, 1] * p[1] + m[0, 2] * p[2] + m[0, 3],
            m[1, 0] * p[0] + m[1, 1] * p[1] + m[1, 2] * p[2] + m[1, 3],
            m[2, 0] * p[0] + m[2, 1] * p[1] + m[2, 2] * p[2] + m[2, 3])


@kernel("void(f8[:, ::1], f8[:, ::1], i8[::1], f8[::1], f8[::1], f8[:, :, ::1], f8[:, ::1], f8[::1], f8[::1], "
        "f8[:, ::1], i8)")
def _mapped_vectors(out, points, triangle, u, v, corner_uvs, to_object, location, size, mapping, coordinates):
    """out (n,3) the Mapping node's `mapping` of each point's vector: UV the
    corners' UVs at barycentrics (1-u-v, u, v), z = 0; Object the point
    in object space, to_object p; Generated (p_object - location) / (2 size) + 1/2."""
    for n in range(len(out)):
        if coordinates == _UV:
            corners = corner_uvs[triangle[n]]
            w0 = 1.0 - u[n] - v[n]
            vector = (w0 * corners[0, 0] + u[n] * corners[1, 0] + v[n] * corners[2, 0],
                      w0 * corners[0, 1] + u[n] * corners[1, 1] + v[n] * corners[2, 1], 0.0)
        else:
            vector = affine1(to_object, (points[n, 0], points[n, 1], points[n, 2]))
            if coordinates == _GENERATED:
                vector = ((vector[0] - location[0]) / (2.0 * size[0]) + 0.5,
                          (vector[1] - location[1]) / (2.0 * size[1]) + 0.5,
                          (vector[2] - location[2]) / (2.0 * size[2]) + 0.5)
        mapped = affine1(mapping, vector)
        out[n, 0], out[n, 1], out[n, 2] = mapped


def _mix(blend: str, t: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cycles' svm_mix (kernel/svm/color_util.h) for factor `t (n,1)`."""
    s = 1.0 - t
    if blend == "MIX":
        return s * a + t * b
    if blend == "ADD":
        return a + t * b
    if blend == "MULTIPLY":
        return a * (s + t * b)
    if blend == "SUBTRACT":
        return a - t * b
    if blend == "SCREEN":
        return 1.0 - (s + t * (1.0 - b)) * (1.0 - a)
    if blend == "DIVIDE":
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(b != 0.0, s * a + t * a / b, a)
    if blend == "DIFFERENCE":
        return s * a + t * np.abs(a - b)
    if blend == "DARKEN":
        return s * a + t * np.minimum(a, b)
    if blend == "LIGHTEN":
        return s * a + t * np.maximum(a, b)
    # OVERLAY
    return np.where(a < 0.5, a * (s + 2.0 * t * b), 1.0 - (s + 2.0 * t * (1.0 - b)) * (1.0 - a))


MIX_BLENDS = ("MIX", "ADD", "MULTIPLY", "SUBTRACT", "SCREEN", "DIVIDE", "DIFFERENCE", "DARKEN", "LIGHTEN",
              "OVERLAY")


@dataclass
class MixColor:
    """The Mix node on colours (and the older MixRGB): `blend` one of
    MIX_BLENDS, the factor clamped to 0..1 as the node does by default."""

    blend: str
    factor: "Node"
    a: "Node"
    b: "Node"
    clamp_factor: bool = True
    clamp_result: bool = False

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        t = as_value(self.factor.evaluate(at))
        if self.clamp_factor:
            t = np.clip(t, 0.0, 1.0)
        out = _mix(self.blend, t[:, None], as_color(self.a.evaluate(at)), as_color(self.b.evaluate(at)))
        return np.clip(out, 0.0, 1.0) if self.clamp_result else out


def _safe_divide(a, b):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(b != 0.0, a / np.where(b != 0.0, b, 1.0), 0.0)


def _safe_power(a, b):
    """Cycles' safe_powf: 0 for a negative base with a fractional exponent."""
    with np.errstate(invalid="ignore"):
        out = np.power(np.abs(a), b) * np.where((a < 0) & (np.mod(b, 2.0) == 1.0), -1.0, 1.0)
    return np.where((a < 0) & (b != np.floor(b)), 0.0, out)


# Cycles' svm_math (kernel/svm/math_util.h), for the operations read
MATH = {
    "ADD": lambda a, b, c: a + b,
    "SUBTRACT": lambda a, b, c: a - b,
    "MULTIPLY": lambda a, b, c: a * b,
    "DIVIDE": lambda a, b, c: _safe_divide(a, b),
    "MULTIPLY_ADD": lambda a, b, c: a * b + c,
    "POWER": lambda a, b, c: _safe_power(a, b),
    "MINIMUM": lambda a, b, c: np.minimum(a, b),
    "MAXIMUM": lambda a, b, c: np.maximum(a, b),
    "ABSOLUTE": lambda a, b, c: np.abs(a),
    "SQRT": lambda a, b, c: np.sqrt(np.maximum(a, 0.0)),
    "LESS_THAN": lambda a, b, c: (a < b).astype(np.float64),
    "GREATER_THAN": lambda a, b, c: (a > b).astype(np.float64),
}


@dataclass
class MathNode:
    """The Math node on values: `operation` one of MATH, `inputs` its three
    value inputs, the result clamped to 0..1 if `clamp`."""

    operation: str
    inputs: tuple["Node", "Node", "Node"]
    clamp: bool = False

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        a, b, c = (as_value(node.evaluate(at)) for node in self.inputs)
        out = MATH[self.operation](a, b, c)
        return np.clip(out, 0.0, 1.0) if self.clamp else out


@dataclass
class ColorRamp:
    """The Color Ramp node: `positions (k,)` ascending in 0..1 with their
    `colors (k,3)`, interpolated 'LINEAR', 'EASE' (smoothstep between
    stops) or 'CONSTANT' (the stop at or below), clamped outside."""

    factor: "Node"
    positions: np.ndarray
    colors: np.ndarray
    interpolation: str = "LINEAR"

    def evaluate(self, at: SurfacePoints) -> np.ndarray:
        t = np.clip(as_value(self.factor.evaluate(at)), 0.0, 1.0)
        positions = np.asarray(self.positions, dtype=np.float64)
        colors = np.asarray(self.colors, dtype=np.float64)
        upper = np.clip(np.searchsorted(positions, t, side="right"), 1, len(positions) - 1) if len(positions) > 1 \
            else np.zeros(len(t), dtype=np.int64)
        lower = np.maximum(upper - 1, 0)
        if len(positions) == 1 or self.interpolation == "CONSTANT":
            stop = np.where(t >= positions[upper], upper, lower)
            return colors[np.where(t < positions[0], 0, stop)]
        span = positions[upper] - positions[lower]
        f = np.clip(_safe_divide(t - positions[lower], span), 0.0, 1.0)
        if self.interpolation == "EASE":
            f = f * f * (3.0 - 2.0 * f)
        return colors[lower] * (1.0 - f)[:, None] + colors[upper] * f[:, None]


Node = Union[Constant, ImageTexture, MixColor, MathNode, ColorRamp]
