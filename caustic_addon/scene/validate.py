"""Checks on a scene before anything is traced: errors name what is wrong,
warnings name what will render, but perhaps not as the user expects."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from ..optics.dispersion import cauchy_ior
from ..optics.spectrum import VISIBLE_NM
from .lights import PointLight, SpotLight, SunLight
from .materials import Dielectric, Reflector
from .scene import Scene


def _finite(name: str, what: str, array) -> None:
    if not np.all(np.isfinite(np.asarray(array, dtype=np.float64))):
        raise SceneError(f"{name}: {what} contains NaN or infinite values")


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
        if mesh.corner_normals is not None:
            _finite(obj.name, "its normals", mesh.corner_normals)
            if mesh.corner_normals.shape != (len(mesh.triangles), 3, 3):
                raise SceneError(f"{obj.name}: corner_normals must have shape (triangles, 3, 3)")
        material = obj.material
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
        if isinstance(material, Reflector):
            _finite(obj.name, "its reflectance colour", material.color)
            if np.any((material.color < 0) | (material.color > 1)):
                raise SceneError(f"{obj.name}: reflectance colour must be in 0..1 (got {material.color.tolist()})")

    for light in scene.lights:
        if isinstance(light, (PointLight, SpotLight)):
            _finite(light.name, "its position", light.position)
            if not (math.isfinite(light.power) and light.power >= 0):
                raise SceneError(f"{light.name}: power must be a finite number of watts >= 0")
        if isinstance(light, SunLight) and not (math.isfinite(light.strength) and light.strength >= 0):
            raise SceneError(f"{light.name}: strength must be a finite number >= 0")
        _finite(light.name, "its colour", light.color)

    if not scene.lights:
        warnings.append("the scene has no lamps: only ambient light and the background show")
    if scene.casters and not scene.receivers:
        warnings.append("no object receives caustics: the photon pass is skipped")
    return warnings
