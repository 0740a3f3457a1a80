"""Checks on a scene before anything is traced: errors name what is wrong,
warnings name what will render, but perhaps not as the user expects."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..optics.dispersion import cauchy_ior
from ..optics.layers import LAYERINGS
from ..optics.spectrum import VISIBLE_NM
from .lights import AreaLight, SpotLight, SunLight, World
from .materials import Dielectric, Diffuse, Reflector
from .scene import Scene


# The tracing offsets rays by a share of the whole scene's size (tracing.accelerator.EPSILON_FRACTION,
# 2e-6), so an object that makes the scene far larger than the rest of it moves light on the rest: on the
# ball lens (2 m) over a floor made larger, direct light moved 1% at 1e3 times and 7% at 1e4 times the
# ball's size, and went black by 1e6.
_SCALE_WARNING, _SCALE_ERROR = 1e3, 1e4
# Embree's triangle test multiplies two of a triangle's edges: coordinates past this (m) overflow float32.
_MAX_COORDINATE = 1e18
# A lamp's power (W; a sun's strength, W/m^2) past this overflows the float32 images; the Sun gives 3.8e26 W.
_MAX_POWER = 1e30


def _finite(name: str, what: str, array) -> None:
    if not np.all(np.isfinite(np.asarray(array, dtype=np.float64))):
        raise SceneError(f"{name}: {what} contains NaN or infinite values")


def _material_finite(name: str, material) -> None:
    if isinstance(material, Dielectric):
        parts = [("its reflection tint", material.reflection_tint),
                 ("its transmission tint", material.transmission_tint), ("its absorption", material.absorption)]
    elif isinstance(material, Diffuse):
        parts = [("its color", material.albedo), ("its emission", material.emission)]
    else:
        parts = []
    for what, value in parts:
        _finite(name, what, value)
    if isinstance(material, Diffuse) and np.max(material.emission) > _MAX_POWER:
        raise SceneError(f"{name}: its emission of {np.max(material.emission):.3g} W/(m^2 sr) is past the "
                         f"{_MAX_POWER:.0e} that the render's float32 images hold: lower its Strength")


def validate_scene(scene: Scene) -> list[str]:
    """Raise SceneError for what cannot be rendered; return warnings."""
    warnings = []
    cam = scene.camera
    if cam.pixx < 1 or cam.pixy < 1:
        raise SceneError(f"camera: resolution must be at least 1x1 (got {cam.pixx}x{cam.pixy})")
    if cam.kind == "PERSP" and not (0.0 < cam.fov < math.pi):
        raise SceneError(f"camera: fov must be between 0 and 180 degrees (got {math.degrees(cam.fov):.6g})")
    if cam.kind == "ORTHO" and not cam.ortho_scale > 0:
        raise SceneError("camera: ortho_scale must be positive")
    _finite("camera", "its matrix", cam.matrix)

    warnings += _check_scale(scene)
    for obj in scene.objects:
        # an instanced object's copies are as sound as the mesh they copy, under finite transforms
        mesh = obj.mesh if obj.instances is None else obj.instances.mesh
        if obj.instances is not None:
            _finite(obj.name, "its instances' transforms", obj.instances.transforms)
        if mesh.triangles.min() < 0 or mesh.triangles.max() >= len(mesh.vertices):
            raise SceneError(f"{obj.name}: a triangle refers to a vertex that does not exist")
        if mesh.corner_uvs is not None:
            _finite(obj.name, "its UV map", mesh.corner_uvs)
        if mesh.corner_normals is not None:
            _finite(obj.name, "its normals", mesh.corner_normals)
            if mesh.corner_normals.shape != (len(mesh.triangles), 3, 3):
                raise SceneError(f"{obj.name}: corner_normals must have shape (triangles, 3, 3)")
        material = obj.material
        _material_finite(obj.name, material)
        if isinstance(material, (Dielectric, Reflector)) and not 0.0 <= material.roughness <= 1.0:
            raise SceneError(f"{obj.name}: roughness must be between 0 and 1 (got {material.roughness})")
        if isinstance(material, Dielectric):
            if not (math.isfinite(material.ior) and material.ior > 0):
                raise SceneError(f"{obj.name}: IOR must be a positive number (got {material.ior})")
            if np.any(material.absorption < 0):
                raise SceneError(f"{obj.name}: absorption must not be negative")
            if np.any(material.reflection_tint < 0) or np.any(material.transmission_tint < 0):
                raise SceneError(f"{obj.name}: its reflection and transmission tints must not be negative")
            if not material.abbe > 0:
                raise SceneError(f"{obj.name}: the Abbe number must be > 0, or inf for no dispersion "
                                 f"(got {material.abbe})")
            if np.any(cauchy_ior(material.ior, material.abbe, VISIBLE_NM) <= 0):
                raise SceneError(f"{obj.name}: an Abbe number of {material.abbe} with IOR {material.ior} gives "
                                 f"an IOR <= 0 in the visible spectrum")
        if isinstance(material, Diffuse) and material.specular is not None:
            _check_specular(obj.name, material.specular)
        if isinstance(material, Reflector):
            _finite(obj.name, "its reflectance color", material.color)
            if np.any((material.color < 0) | (material.color > 1)):
                raise SceneError(f"{obj.name}: reflectance color must be in 0..1 (got {material.color.tolist()})")

    extent = scene.extent()
    for light in scene.lights:
        warnings += _check_lamp(light, extent)
    _check_world(scene.world)

    if not scene.lights and not scene.emitting and scene.world.is_black:
        warnings.append("the scene has no lights, no emitting surface and a black world: only the ambient term shows")
    if scene.casters and not scene.receivers:
        warnings.append("no object receives caustics: the photon pass is skipped")
    return warnings


def _check_scale(scene: Scene) -> list[str]:
    """Raise SceneError for a vertex that is not a finite number, for an
    object so far from the rest of the scene, or so large against it, that
    the tracing's precision, which follows the whole scene's size, would
    leave the rest black or wrong, and for coordinates past float32's
    arithmetic; each names the object and its vertex. Warn where the rest's
    light moves by a percent or so."""
    for obj in scene.objects:
        if obj.mesh.triangle_count == 0:
            raise SceneError(f"{obj.name}: the mesh has no triangles")
        if not np.isfinite(obj.mesh.bounds).all():
            vertex = int((~np.isfinite(obj.mesh.vertices).all(axis=1)).argmax())
            raise SceneError(f"{obj.name}: its vertex {vertex} is not a finite point "
                             f"{_point(obj.mesh.vertices[vertex])}")
    warnings = _check_far(scene) if len(scene.objects) > 1 else []
    for obj in scene.objects:
        if np.abs(obj.mesh.bounds).max() > _MAX_COORDINATE:
            vertex = int(np.abs(obj.mesh.vertices).max(axis=1).argmax())
            raise SceneError(f"{obj.name}: its vertex {vertex} lies at {_point(obj.mesh.vertices[vertex])}, past "
                             f"the {_MAX_COORDINATE:.0e} m from the origin that the tracing's float32 arithmetic "
                             "holds: move it nearer")
    return warnings


def _check_far(scene: Scene) -> list[str]:
    """_check_scale's objects far from, or large against, the rest of the
    scene: every other object and the camera, which the user looks from
    (so of two objects far apart, the one far from the camera is named)."""
    lows = np.array([obj.mesh.bounds[0] for obj in scene.objects])
    highs = np.array([obj.mesh.bounds[1] for obj in scene.objects])
    # the bounds of every object but each one: the bounds of those before it and of those after it, and the camera
    eye = np.asarray(scene.camera.matrix, dtype=np.float64)[None, :3, 3]
    rest_low = np.minimum(np.minimum.accumulate(np.concatenate([eye, lows[:-1]])),
                          np.minimum.accumulate(np.concatenate([lows[1:], eye])[::-1])[::-1])
    rest_high = np.maximum(np.maximum.accumulate(np.concatenate([eye, highs[:-1]])),
                           np.maximum.accumulate(np.concatenate([highs[1:], eye])[::-1])[::-1])
    rest = np.maximum(np.linalg.norm(rest_high - rest_low, axis=1), 1e-12)
    ratio = scene.extent() / rest
    worst = int(ratio.argmax())
    if ratio[worst] < _SCALE_WARNING:
        return []
    obj = scene.objects[worst]
    outside = np.maximum(rest_low[worst] - obj.mesh.vertices, obj.mesh.vertices - rest_high[worst]).clip(min=0.0)
    distance = np.linalg.norm(outside, axis=1)
    vertex = int(distance.argmax())
    where = (f"'{obj.name}' reaches {distance[vertex]:.3g} m from the rest of the scene, which is "
             f"{rest[worst]:.3g} m across (its vertex {vertex} at {_point(obj.mesh.vertices[vertex])})")
    if ratio[worst] >= _SCALE_ERROR:
        raise SceneError(f"{where}: the tracing's precision follows the whole scene's size, so the rest would "
                         "render black or wrong; move it nearer or make it smaller, or leave it out of the render")
    return [f"{where}: the tracing's precision follows the whole scene's size, {ratio[worst]:.3g} times the rest's, "
            "so light on the rest may move by a percent or so; move it nearer or make it smaller"]


def _point(xyz) -> str:
    return "(" + ", ".join(f"{float(c):.3g}" for c in xyz) + ")"


def _check_specular(name: str, spec) -> None:
    """Raise SceneError for a specular layer outside what a Principled BSDF takes."""
    _finite(name, "its specular layer", [spec.roughness, spec.ior, spec.level, *spec.tint])
    if not 0.0 <= spec.roughness <= 1.0:
        raise SceneError(f"{name}: specular roughness must be in 0..1 (got {spec.roughness})")
    if not spec.ior > 0.0:
        raise SceneError(f"{name}: specular IOR must be positive (got {spec.ior})")
    if spec.level < 0.0 or np.any(spec.tint < 0.0):
        raise SceneError(f"{name}: specular level and tint must not be negative")
    _finite(name, "its Metallic", [spec.metallic])
    if not 0.0 <= spec.metallic <= 1.0:
        raise SceneError(f"{name}: Metallic must be in 0..1 (got {spec.metallic})")
    if spec.layering not in LAYERINGS:
        raise SceneError(f"{name}: layering must be one of {', '.join(LAYERINGS)} (got {spec.layering!r})")
    coat = spec.coat
    if coat is not None:
        _finite(name, "its coat", [coat.weight, coat.roughness, coat.ior, *coat.tint])
        if coat.weight < 0.0 or not 0.0 <= coat.roughness <= 1.0 or coat.ior < 1.0 or np.any(coat.tint < 0.0):
            raise SceneError(f"{name}: the coat's weight and tint must not be negative, its roughness must be in "
                             f"0..1 and its IOR at least 1 (got {coat.weight}, {coat.tint.tolist()}, "
                             f"{coat.roughness}, {coat.ior})")


def _check_lamp(light, extent: float) -> list[str]:
    """Raise SceneError for a lamp that cannot render; its warnings."""
    name = f"light '{light.name}'"
    _finite(name, "its color", light.color)
    if np.any(light.color < 0):
        raise SceneError(f"{name}: its color must not be negative")
    power = light.strength if isinstance(light, SunLight) else light.power
    what = "strength" if isinstance(light, SunLight) else "power"
    if not (math.isfinite(power) and power >= 0):
        raise SceneError(f"{name}: its {what} must be a finite number >= 0 (got {power})")
    if power * float(np.max(light.color)) > _MAX_POWER:
        raise SceneError(f"{name}: its {what} of {power:.3g} {'W/m^2' if what == 'strength' else 'W'} (times its "
                         f"color) is past the {_MAX_POWER:.0e} that the render's float32 images hold (the Sun "
                         "gives 3.8e+26 W): lower it")
    warnings = []
    if power == 0 or not np.any(light.color > 0):
        warnings.append(f"{name} gives no light (power 0 or black): it was left out")
    if isinstance(light, SunLight):
        if not 0.0 <= light.angle <= math.pi:
            raise SceneError(f"{name}: its angle must be between 0 and 180 degrees (got "
                             f"{math.degrees(light.angle):.6g})")
        return warnings
    _finite(name, "its position", light.position)
    if isinstance(light, AreaLight):
        _finite(name, "its size and direction", np.concatenate([light.axis_x, light.axis_y, light.direction]))
        if not light.area > 0:
            raise SceneError(f"{name}: its size is 0, so it has no area to give off light from")
        if not 0.0 <= light.spread <= math.pi:
            raise SceneError(f"{name}: its spread must be between 0 and 180 degrees (got "
                             f"{math.degrees(light.spread):.6g})")
        if light.spread == 0.0:
            warnings.append(f"{name} has a spread of 0, a parallel beam: it lights the scene but casts no caustics")
        size = float(np.linalg.norm(light.axis_x) + np.linalg.norm(light.axis_y))
    else:
        if not (math.isfinite(light.radius) and light.radius >= 0):
            raise SceneError(f"{name}: its radius must be a finite number of metres >= 0 (got {light.radius})")
        size = light.radius
    if size > extent:
        warnings.append(f"{name} is larger than the scene ({size:.3g} m against {extent:.3g} m across): "
                        "its light is that of a light wrapped around everything")
    if isinstance(light, SpotLight):
        if not 0.0 < light.spot_size <= math.pi:
            raise SceneError(f"{name}: its spot size must be between 0 and 180 degrees")
        if not 0.0 <= light.blend <= 1.0:
            raise SceneError(f"{name}: its blend must be between 0 and 1 (got {light.blend})")
    return warnings


def _check_world(world: World) -> None:
    _finite("the world", "its color", world.color)
    if np.any(world.color < 0):
        raise SceneError("the world: its color must not be negative")
    if world.environment is not None:
        image = world.environment
        if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 2 or image.shape[1] < 2:
            raise SceneError(f"the world: its environment image must be (rows, columns, 3), at least 2x2 "
                             f"(got {image.shape})")
        _finite("the world", "its environment image", image)
        if np.any(image < 0):
            raise SceneError("the world: its environment image must not be negative")


def rough_caster_warnings(scene: Scene, density: str) -> list[str]:
    """What is still approximated about the rough casters, in one warning
    that names them all and their range of Roughness: in beam mode the
    light they scatter lands as photons (the adaptive estimate's noise, not
    beams: spread beams measured slower and worse, benchmarks/rough_glass.py),
    and the eye sees through them or in them one microfacet normal per eye
    sample, grainy at few samples."""
    rough = [obj for obj in scene.casters if not obj.material.smooth]
    if not rough:
        return []
    lowest = min(obj.material.roughness for obj in rough)
    highest = max(obj.material.roughness for obj in rough)
    roughness = f"{lowest:.3g}" if f"{lowest:.3g}" == f"{highest:.3g}" else f"{lowest:.3g}-{highest:.3g}"
    its, it, caustic = ("its", "it", "caustic comes") if len(rough) == 1 else ("their", "them", "caustics come")
    as_photons = f"in beam mode {its} {caustic} as photons, with their noise; " if density == "beam" else ""
    return [f"{', '.join(obj.name for obj in rough)}: rough (Roughness {roughness}): {as_photons}the view through "
            f"{it} or in {it} takes one microfacet normal per eye sample (more Samples smooth {its} grain)"]
