"""Checks on a scene before anything is traced: errors name what is wrong,
warnings name what will render, but perhaps not as the user expects."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..optics.dispersion import cauchy_ior
from ..optics.spectrum import VISIBLE_NM
from .lights import AreaLight, SpotLight, SunLight, World
from .materials import Dielectric, Diffuse, Reflector
from .scene import Scene


def _finite(name: str, what: str, array) -> None:
    if not np.all(np.isfinite(np.asarray(array, dtype=np.float64))):
        raise SceneError(f"{name}: {what} contains NaN or infinite values")


def _material_finite(name: str, material) -> None:
    if isinstance(material, Dielectric):
        parts = [("its colour", material.color), ("its absorption", material.absorption)]
    elif isinstance(material, Diffuse):
        parts = [("its colour", material.albedo), ("its emission", material.emission)]
    else:
        parts = []
    for what, value in parts:
        _finite(name, what, value)


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

    for obj in scene.objects:
        mesh = obj.mesh
        _finite(obj.name, "its vertex coordinates", mesh.vertices)
        if len(mesh.triangles) == 0:
            raise SceneError(f"{obj.name}: the mesh has no triangles")
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
            if not material.abbe > 0:
                raise SceneError(f"{obj.name}: the Abbe number must be > 0, or inf for no dispersion "
                                 f"(got {material.abbe})")
            if np.any(cauchy_ior(material.ior, material.abbe, VISIBLE_NM) <= 0):
                raise SceneError(f"{obj.name}: an Abbe number of {material.abbe} with IOR {material.ior} gives "
                                 f"an IOR <= 0 in the visible spectrum")
        if isinstance(material, Diffuse) and material.specular is not None:
            _check_specular(obj.name, material.specular)
        if isinstance(material, Reflector):
            _finite(obj.name, "its reflectance colour", material.color)
            if np.any((material.color < 0) | (material.color > 1)):
                raise SceneError(f"{obj.name}: reflectance colour must be in 0..1 (got {material.color.tolist()})")

    extent = scene.extent()
    for light in scene.lights:
        warnings += _check_lamp(light, extent)
    _check_world(scene.world)

    if not scene.lights and scene.world.is_black:
        warnings.append("the scene has no lamps and a black world: only the ambient term shows")
    if scene.casters and not scene.receivers:
        warnings.append("no object receives caustics: the photon pass is skipped")
    return warnings


def _check_specular(name: str, spec) -> None:
    """Raise SceneError for a specular layer outside what a Principled BSDF takes."""
    _finite(name, "its specular layer", [spec.roughness, spec.ior, spec.level, *spec.tint])
    if not 0.0 <= spec.roughness <= 1.0:
        raise SceneError(f"{name}: specular roughness must be in 0..1 (got {spec.roughness})")
    if not spec.ior > 0.0:
        raise SceneError(f"{name}: specular IOR must be positive (got {spec.ior})")
    if spec.level < 0.0 or np.any(spec.tint < 0.0):
        raise SceneError(f"{name}: specular level and tint must not be negative")


def _check_lamp(light, extent: float) -> list[str]:
    """Raise SceneError for a lamp that cannot render; its warnings."""
    name = f"lamp '{light.name}'"
    _finite(name, "its colour", light.color)
    if np.any(light.color < 0):
        raise SceneError(f"{name}: its colour must not be negative")
    power = light.strength if isinstance(light, SunLight) else light.power
    if not (math.isfinite(power) and power >= 0):
        raise SceneError(f"{name}: its {'strength' if isinstance(light, SunLight) else 'power'} must be a finite "
                         f"number >= 0 (got {power})")
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
                        "its light is that of a lamp wrapped around everything")
    if isinstance(light, SpotLight):
        if not 0.0 < light.spot_size <= math.pi:
            raise SceneError(f"{name}: its spot size must be between 0 and 180 degrees")
        if not 0.0 <= light.blend <= 1.0:
            raise SceneError(f"{name}: its blend must be between 0 and 1 (got {light.blend})")
    return warnings


def _check_world(world: World) -> None:
    _finite("the world", "its colour", world.color)
    if np.any(world.color < 0):
        raise SceneError("the world: its colour must not be negative")
    if world.environment is not None:
        image = world.environment
        if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 2 or image.shape[1] < 2:
            raise SceneError(f"the world: its environment image must be (rows, columns, 3), at least 2x2 "
                             f"(got {image.shape})")
        _finite("the world", "its environment image", image)
        if np.any(image < 0):
            raise SceneError("the world: its environment image must not be negative")


def rough_caster_warnings(scene: Scene, density: str) -> list[str]:
    """What is still approximated about each rough caster, in one warning
    each: in beam mode the light it scatters lands as photons (the
    adaptive estimate's noise, not beams: spread beams measured slower and
    worse, benchmarks/rough_glass.py), and the eye sees through it or in it
    one microfacet normal per eye sample, grainy at few samples."""
    warnings = []
    for obj in scene.casters:
        roughness = obj.material.roughness
        if not obj.material.smooth:
            as_photons = "in beam mode its caustic comes as photons, with their noise; " if density == "beam" else ""
            warnings.append(f"{obj.name}: rough (Roughness {roughness:.3g}): {as_photons}the view through it or "
                            "in it takes one microfacet normal per eye sample (more Samples smooth its grain)")
    return warnings
