"""Textured receivers: image look-ups as Cycles' (interpolation and
extension), the coordinates a texture reads, the nodes chained after it,
and a textured floor's pixels, whose radiance is its texel times the light."""

import numpy as np
import pytest

from caustic_addon import Diffuse, Object, RenderSettings, Scene, World, render, shapes
from caustic_addon.scene.textures import ColorRamp, Constant, ImageTexture, MathNode, MixColor, SurfacePoints
from caustic_addon.util.image_lookup import lookup

from scenes import top_camera


def ramp_image(w=8, h=4) -> np.ndarray:
    """(h, w, 1): the value at pixel (row j, column i) is i + 10 j."""
    return (np.arange(w)[None, :] + 10.0 * np.arange(h)[:, None])[..., None]


@pytest.mark.parametrize("interpolation", ["Linear", "Cubic"])
def test_linear_and_cubic_look_ups_reproduce_a_linear_image(interpolation):
    """Both the tent and the uniform cubic B-spline reproduce linear
    functions exactly away from the edges: at u, the column coordinate is
    u w - 1/2."""
    uv = np.array([[0.31, 0.42], [0.5, 0.5], [0.66, 0.61]])
    expected = (uv[:, 0] * 8 - 0.5) + 10.0 * (uv[:, 1] * 4 - 0.5)
    np.testing.assert_allclose(lookup(ramp_image(), uv, interpolation, "EXTEND")[:, 0], expected, atol=1e-12)


def test_closest_and_the_extension_modes():
    image = ramp_image()
    inside = np.array([[0.99 / 8, 0.5 / 4]])
    assert lookup(image, inside, "Closest")[0, 0] == 0.0 + 10.0 * 0
    left = np.array([[-0.3 / 8, 0.1]])          # a third of a pixel left of the image
    assert lookup(image, left, "Closest", "REPEAT")[0, 0] == 7.0
    assert lookup(image, left, "Closest", "EXTEND")[0, 0] == 0.0
    assert lookup(image, left, "Closest", "CLIP")[0, 0] == 0.0
    assert lookup(image + 1.0, left, "Closest", "CLIP")[0, 0] == 0.0
    assert lookup(image, np.array([[-1.5 / 8, 0.1]]), "Closest", "MIRROR")[0, 0] == 1.0
    np.testing.assert_allclose(lookup(image, np.array([[0.3, 0.6]]) + 1.0, "Linear", "REPEAT"),
                               lookup(image, np.array([[0.3, 0.6]]), "Linear", "REPEAT"))


@pytest.mark.parametrize("interpolation", ["Closest", "Linear", "Cubic"])
def test_byte_float32_and_float64_images_look_up_alike(interpolation):
    """The look-up reads each pixel type as its value (bytes 0..255, not
    scaled), the same for every extension pair; a constant image stays
    constant wherever every tap lies inside it (the weights sum to one)."""
    values = np.random.default_rng(3).integers(0, 256, (5, 7, 4))
    uv = np.random.default_rng(4).uniform(-2.0, 3.0, (200, 2))
    for along_u in ("REPEAT", "EXTEND", "CLIP", "MIRROR"):
        for along_v in ("REPEAT", "EXTEND", "CLIP", "MIRROR"):
            looked_up = [lookup(values.astype(dtype), uv, interpolation, (along_u, along_v))
                         for dtype in (np.uint8, np.float32, np.float64)]
            np.testing.assert_array_equal(looked_up[0], looked_up[2])
            np.testing.assert_array_equal(looked_up[1], looked_up[2])
    np.testing.assert_allclose(lookup(np.full((5, 7, 3), 0.25), uv, interpolation, "MIRROR"), 0.25, rtol=1e-14)


def points_on_unit_square(uv: np.ndarray) -> SurfacePoints:
    """Points of the two-triangle square [0,1]^2 at z = 0 (shapes.plane(1.0)
    moved by +1/2), where u, v are barycentrics of triangle 0."""
    points = np.concatenate([uv, np.zeros((len(uv), 1))], axis=1)
    return SurfacePoints(points, np.zeros(len(uv), dtype=np.int64), uv[:, 0], uv[:, 1])


def test_coordinates_and_mapping():
    """UV is interpolated over the triangle; Object is the point in object
    space; Generated maps the texture space to 0..1; a Mapping node's
    scale of 2 tiles the image twice."""
    image = np.zeros((2, 2, 3))
    image[0, 1] = 1.0  # row 0 is v = 0: the lower right quarter
    at = points_on_unit_square(np.array([[0.75, 0.25]]))
    uv_texture = ImageTexture(image, "UV", corner_uvs=np.array([[[0, 0], [1, 0], [0, 1]]], dtype=float),
                              interpolation="Closest")
    assert uv_texture.evaluate(at)[0, 0] == 1.0
    moved = np.eye(4)
    moved[:3, 3] = (0.5, 0.5, 0.0)
    assert ImageTexture(image, "OBJECT", to_object=moved, interpolation="Closest").evaluate(at)[0, 0] == 0.0
    generated = ImageTexture(image, "GENERATED", texspace_location=np.zeros(3), texspace_size=np.full(3, 1.0),
                             interpolation="Closest")
    np.testing.assert_allclose(generated.vectors(at), [[0.875, 0.625, 0.5]])
    tiled = ImageTexture(image, "UV", corner_uvs=uv_texture.corner_uvs, mapping=np.diag([2.0, 2.0, 1.0, 1.0]),
                         interpolation="Closest")
    assert tiled.evaluate(points_on_unit_square(np.array([[0.25 + 0.125, 0.125]])))[0, 0] == 1.0


def test_an_srgb_image_is_decoded_after_its_look_up_as_cycles_does():
    """Halfway between an encoded 0 and 1, Cycles decodes 0.5: 0.214, not
    the linear mean 0.5 of the decoded values. An 8-bit image's bytes look
    up as their values."""
    image = np.array([[[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]]], dtype=np.float32)
    corner_uvs = np.array([[[0, 0], [1, 0], [0, 1]]], dtype=float)
    at = points_on_unit_square(np.array([[0.5, 0.5]]))
    encoded = ImageTexture(image, "UV", corner_uvs=corner_uvs, extension="EXTEND", srgb=True)
    np.testing.assert_allclose(encoded.evaluate(at), [[((0.5 + 0.055) / 1.055) ** 2.4] * 3])
    linear = ImageTexture(image, "UV", corner_uvs=corner_uvs, extension="EXTEND")
    np.testing.assert_allclose(linear.evaluate(at), [[0.5] * 3])
    as_bytes = (image * 255).astype(np.uint8)
    for interpolation in ("Closest", "Linear", "Cubic"):
        np.testing.assert_allclose(
            ImageTexture(as_bytes, "UV", corner_uvs=corner_uvs, interpolation=interpolation, srgb=True).evaluate(at),
            ImageTexture(image, "UV", corner_uvs=corner_uvs, interpolation=interpolation, srgb=True).evaluate(at))


def test_mix_math_and_color_ramp_as_cycles():
    at = points_on_unit_square(np.array([[0.1, 0.1]]))
    a, b = Constant(np.array([0.2, 0.4, 0.8])), Constant(np.array([0.5, 0.5, 0.5]))
    np.testing.assert_allclose(MixColor("MULTIPLY", Constant(0.5), a, b).evaluate(at), [[0.15, 0.3, 0.6]])
    np.testing.assert_allclose(MixColor("MIX", Constant(1.7), a, b).evaluate(at), [[0.5, 0.5, 0.5]])
    np.testing.assert_allclose(MixColor("SCREEN", Constant(1.0), a, b).evaluate(at), [[0.6, 0.7, 0.9]])
    luminance = 0.2126 * 0.2 + 0.7152 * 0.4 + 0.0722 * 0.8
    np.testing.assert_allclose(MathNode("MULTIPLY", (a, Constant(2.0), Constant(0.0))).evaluate(at), [2 * luminance])
    assert MathNode("DIVIDE", (a, Constant(0.0), Constant(0.0))).evaluate(at)[0] == 0.0
    ramp = ColorRamp(Constant(0.75), np.array([0.0, 0.5, 1.0]), np.array([[0, 0, 0], [1, 0, 0], [1, 1, 1]], float))
    np.testing.assert_allclose(ramp.evaluate(at), [[1.0, 0.5, 0.5]])
    ramp.interpolation = "CONSTANT"
    np.testing.assert_allclose(ramp.evaluate(at), [[1.0, 0.0, 0.0]])
    ramp.interpolation = "EASE"
    np.testing.assert_allclose(ramp.evaluate(at), [[1.0, 0.5, 0.5]])


def test_a_textured_floor_shows_each_texel_times_the_light():
    """Under a uniform world of radiance L, an open floor's radiance is
    albedo x L at every point: with a 4 x 4 checker on its UV map, each
    pixel of a camera that sees 4 x 4 pixels of it is its texel's colour."""
    floor = shapes.plane(2.0)
    corners = floor.vertices[floor.triangles]
    uvs = (corners[..., :2] + 1.0) / 2.0
    checker = np.zeros((4, 4, 3))
    checker[..., 1] = 0.2
    checker[(np.arange(4)[:, None] + np.arange(4)[None, :]) % 2 == 0, 0] = 0.9
    texture = ImageTexture(checker.astype(np.float32), "UV", corner_uvs=uvs, interpolation="Closest")
    scene = Scene([Object("Floor", floor, Diffuse(albedo=0.5, texture=texture))], [], top_camera(1.0, 4),
                  world=World(2.0))
    ambient = render(scene, RenderSettings(spp=1, world_samples=4)).passes["ambient"]
    # image row 0 is the top (+y), texture row 0 is v = 0 (-y)
    np.testing.assert_allclose(ambient, 2.0 * checker[::-1], rtol=1e-6)
