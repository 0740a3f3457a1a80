"""A Blender material read as the engine's: Glass or Refraction BSDF, or
Principled BSDF that mostly transmits, is a Dielectric; Glossy BSDF, or
Principled BSDF that is mostly metal, is a Reflector, each with its
Roughness and whether its distribution is Multiscatter GGX; Principled and
Diffuse BSDFs, plain viewport colours and anything not understood are
Diffuse receivers, a Principled BSDF's with its specular layer (Roughness,
IOR, Specular IOR Level, Specular Tint, the GGX or Multiscatter GGX
distribution); a material with no output node, or nothing connected to it,
is black, as Cycles renders it. A Volume Absorption node on the Volume
output gives glass its absorption. What is read approximately comes back as
a warning naming the material.

Dispersion comes from a Principled BSDF's Transmission Dispersion Scale and
Abbe Number (OpenPBR's; Blender 5.3 has them, 4.2 and 4.5 and every Glass BSDF
do not) where its scale is above 0, as the Abbe number abbe / scale, which is
exactly what Cycles renders (Cauchy's law through the IOR at 587.6 nm,
measured: benchmarks/cycles_dispersion.py); elsewhere from the object's Abbe
Number (Object.caustic.abbe). Where both are set and differ, the material's
is used and a warning names the object and the material."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import bpy
import numpy as np

from ..caustic_addon import (Coat, Dielectric, Diffuse, Reflector, Specular, absorption_from_color,
                             volume_absorption)
from ..caustic_addon import textures as nodes
from .textures import Recipe, color_recipe

DEFAULT_ALBEDO = 0.8
# Custom property marking the node groups a bake made (writeback/bake_group.py).
BAKE_TAG = "caustic_bake"
GLASS_NODES = {'ShaderNodeBsdfGlass', 'ShaderNodeBsdfRefraction'}
# Blender 4.0 merged Anisotropic BSDF into Glossy BSDF; both names still make the node.
GLOSSY_NODES = {'ShaderNodeBsdfGlossy', 'ShaderNodeBsdfAnisotropic'}
# A Principled receiver's inputs the engine does not render, with the value
# that leaves them out (Blender's default).
UNRENDERED = {"Sheen Weight": 0.0, "Subsurface Weight": 0.0, "Anisotropic": 0.0, "Thin Film Thickness": 0.0,
              "Diffuse Roughness": 0.0, "Transmission Weight": 0.0, "Alpha": 1.0}
# A Principled BSDF's inputs the engine does not render on a metal, which
# it renders as a mirror of its Base Color (Metallic above 0.5).
UNRENDERED_ON_METAL = {"Coat Weight": 0.0, "Sheen Weight": 0.0, "Thin Film Thickness": 0.0}
# The engine's microfacets are GGX; these distributions are read as GGX, with a warning.
OTHER_DISTRIBUTIONS = {'BECKMANN': "Beckmann", 'ASHIKHMIN_SHIRLEY': "Ashikhmin-Shirley"}
# Inputs that make a microfacet lobe anisotropic, which the engine's is not.
ANISOTROPY_INPUTS = ("Anisotropy", "Anisotropic")
# The Blenders whose Principled layering the engine follows
# (optics/layers.py), by the first version taken to layer so (checked in
# 4.2, 4.5 and 5.3; 5.0 to 5.2 are taken to layer as 5.3).
LAYERING_SINCE = {(5, 0, 0): "5.3", (4, 5, 0): "4.5", (0, 0, 0): "4.2"}
# A Principled BSDF's dispersion (Blender 5.3 on): OpenPBR's scale and Abbe number.
DISPERSION_SCALE, DISPERSION_ABBE = "Transmission Dispersion Scale", "Transmission Dispersion Abbe Number"


@dataclass
class Surface:
    """How a material reads: `transparent` (glass) or `reflector` (mirror,
    metal) pick the engine material; neither is a diffuse receiver.
    `color` is a reflector's reflectance; `tints` glass's (reflection,
    transmission) colours, `fresnel` False for a Refraction BSDF, which
    reflects nothing (the engine's Dielectric); `roughness` Blender's
    Roughness of glass or metal, `multiscatter` whether its distribution is
    Multiscatter GGX; `emission` the radiance it gives off (an Emission
    shader, or a Principled BSDF's emission), with which the engine's
    faces light the scene as a lamp does (its MeshLight); `texture` the nodes that drive a
    receiver's colour (textures.py), if read; `specular` a Principled
    receiver's specular layer. `black` says why a material renders black,
    as Cycles renders it: no output node, or no shader connected to it.
    `abbe` is the Abbe number of glass's own dispersion (inf: none)."""

    transparent: bool
    reflector: bool = False
    emission: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ior: float = 1.5
    color: np.ndarray = field(default_factory=lambda: np.ones(3))
    tints: tuple[np.ndarray, np.ndarray] = field(default_factory=lambda: (np.ones(3), np.ones(3)))
    fresnel: bool = True
    albedo: np.ndarray = field(default_factory=lambda: np.full(3, DEFAULT_ALBEDO))
    texture: Optional[Recipe] = None
    absorption: np.ndarray = field(default_factory=lambda: np.zeros(3))
    roughness: float = 0.0
    multiscatter: bool = True
    abbe: float = math.inf
    specular: Specular | None = None
    warnings: list[str] = field(default_factory=list)
    black: Optional[str] = None


def _value(node, name: str, what: str, warnings: list[str]):
    """An input's own value, with a warning if other nodes drive it instead."""
    socket = node.inputs[name]
    if socket.is_linked:
        warnings.append(f"{what}: its {name} comes from other nodes; the unconnected value is used")
    value = socket.default_value
    return np.array(value[:3], dtype=np.float64) if hasattr(value, "__len__") else float(value)


def _albedo(material, node, name: str, what: str, warnings: list[str]) -> tuple[np.ndarray, Optional[Recipe]]:
    """(a colour input's own value, the recipe of the nodes that drive it or None)."""
    socket = node.inputs[name]
    return np.array(socket.default_value[:3], dtype=np.float64), color_recipe(material.name, socket, what, warnings)


def albedo_socket(material):
    """The colour input of the receiver shader `material` shows (Base
    Color or Color), or None: what a bake multiplies the caustic by."""
    if material is None or material.node_tree is None:
        return None
    shader = _shader(material, 'Surface')
    if shader is None:
        return None
    name = {'ShaderNodeBsdfPrincipled': "Base Color", 'ShaderNodeBsdfDiffuse': "Color"}.get(shader.bl_idname)
    return shader.inputs[name] if name is not None else None


def _shader(material, output_socket: str):
    """The shader node feeding the material's Cycles output's `output_socket`
    ('Surface' or 'Volume'), past reroutes and a bake's node group (which
    adds the baked caustic to the shader it takes); None if nothing is
    connected."""
    output = material.node_tree.get_output_node('CYCLES')
    if output is None:
        return None
    socket = output.inputs[output_socket]
    while socket.is_linked:
        node = socket.links[0].from_node
        if node.bl_idname == 'ShaderNodeGroup' and node.node_tree is not None and BAKE_TAG in node.node_tree:
            socket = node.inputs['Shader']
        elif node.bl_idname == 'NodeReroute':
            socket = node.inputs[0]
        else:
            return node
    return None


def read_surface(material) -> Surface:
    """The engine's view of `material` (None: Cycles' default surface, a
    grey Diffuse BSDF before Blender 5.0 and a grey Principled BSDF since)."""
    if material is None:
        return Surface(transparent=False, specular=Specular() if bpy.app.version >= (5, 0, 0) else None)
    what = f"material '{material.name}'"
    viewport = np.array(material.diffuse_color[:3], dtype=np.float64)
    if material.node_tree is None or not (bpy.app.version >= (5, 0, 0) or material.use_nodes):
        return Surface(transparent=False, albedo=viewport)
    shader = _shader(material, 'Surface')
    if shader is None:
        missing = ("has no Material Output node" if material.node_tree.get_output_node('CYCLES') is None
                   else "has no shader connected to its Material Output's Surface")
        return Surface(transparent=False, albedo=np.zeros(3), black=missing)
    warnings: list[str] = []
    kind = shader.bl_idname
    if kind in GLASS_NODES or (kind == 'ShaderNodeBsdfPrincipled'
                               and _value(shader, "Transmission Weight", what, warnings) > 0.5):
        roughness, multiscatter = _microfacets(shader, what, warnings)
        return Surface(transparent=True, ior=_value(shader, "IOR", what, warnings),
                       tints=_glass_tints(shader, what, warnings), fresnel=kind != 'ShaderNodeBsdfRefraction',
                       absorption=_read_volume(material, what, warnings), roughness=roughness,
                       multiscatter=multiscatter, abbe=_dispersion(shader, what, warnings), warnings=warnings)
    if kind in GLOSSY_NODES:
        return _mirror(shader, "Color", what, warnings)
    if kind == 'ShaderNodeBsdfPrincipled' and _value(shader, "Metallic", what, warnings) > 0.5:
        _warn_unrendered(shader, UNRENDERED_ON_METAL, "it is rendered as a mirror of its Base Color", what, warnings)
        return _mirror(shader, "Base Color", what, warnings)
    if kind == 'ShaderNodeBsdfPrincipled':
        emission = _value(shader, "Emission Color", what, warnings) * _value(shader, "Emission Strength", what,
                                                                              warnings)
        albedo, texture = _albedo(material, shader, "Base Color", what, warnings)
        return Surface(transparent=False, albedo=albedo, texture=texture, emission=emission,
                       specular=_specular_layer(shader, what, warnings), warnings=warnings)
    if kind == 'ShaderNodeBsdfDiffuse':
        albedo, texture = _albedo(material, shader, "Color", what, warnings)
        return Surface(transparent=False, albedo=albedo, texture=texture, warnings=warnings)
    if kind == 'ShaderNodeEmission':
        return Surface(transparent=False, albedo=np.zeros(3), warnings=warnings,
                       emission=_value(shader, "Color", what, warnings) * _value(shader, "Strength", what, warnings))
    return Surface(transparent=False, albedo=viewport,
                   warnings=[f"{what}: a '{shader.name}' shader is not understood; it is rendered as diffuse "
                             "with the material's viewport color"])


def _glass_tints(shader, what: str, warnings: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """(reflection, transmission) colours of a glass shader, as Cycles sets
    its Fresnel's tints (svm/closure.h): a Glass BSDF's Color for both; a
    Refraction BSDF's Color where it refracts and no reflection; a
    Principled BSDF's white reflection and the square root of its Base
    Color at each refraction, so that a thin shell, crossed twice, takes
    its Base Color once, both times its Transmission Weight t (Cycles'
    glass closure's weight; the base under the rest, 1 - t, is not
    rendered, which a warning says). A Principled BSDF's Specular Tint,
    which colours its glass's Fresnel reflectance, is read as white, with
    a warning."""
    if shader.bl_idname == 'ShaderNodeBsdfGlass':
        color = np.maximum(_value(shader, "Color", what, warnings), 0.0)
        return color, color
    if shader.bl_idname == 'ShaderNodeBsdfRefraction':
        return np.zeros(3), np.maximum(_value(shader, "Color", what, warnings), 0.0)
    if not np.allclose(_value(shader, "Specular Tint", what, warnings), 1.0):
        warnings.append(f"{what}: its Specular Tint is not rendered on glass; its reflections are white")
    if "Thin Wall" in shader.inputs and _value(shader, "Thin Wall", what, warnings):
        warnings.append(f"{what}: its Thin Wall is not rendered; it is rendered as solid glass")
    base = np.clip(_value(shader, "Base Color", what, warnings), 0.0, 1.0)
    weight = min(_value(shader, "Transmission Weight", what, warnings), 1.0)
    if weight < 1.0:
        warnings.append(f"{what}: its Transmission Weight {weight:.3g} is rendered as glass of {weight:.3g} of the "
                        "light; the base under the rest is not rendered")
    return np.full(3, weight), weight * np.sqrt(base)


def _specular_layer(shader, what: str, warnings: list[str]) -> Specular:
    """A Principled BSDF's layers over its diffuse base, their inputs
    clamped as Cycles clamps them (svm/closure.h): the specular layer, the
    metal of its Metallic (at most 0.5 here) and its coat; a warning names
    the inputs left out of the render."""
    _warn_unrendered(shader, UNRENDERED, "it is rendered as a diffuse base under its specular layer, metal and coat",
                     what, warnings)
    return Specular(roughness=min(max(_value(shader, "Roughness", what, warnings), 0.0), 1.0),
                    ior=max(_value(shader, "IOR", what, warnings), 1e-5),
                    level=max(_value(shader, "Specular IOR Level", what, warnings), 0.0),
                    tint=np.maximum(_value(shader, "Specular Tint", what, warnings), 0.0),
                    multiscatter=shader.distribution == 'MULTI_GGX',
                    metallic=min(max(_value(shader, "Metallic", what, warnings), 0.0), 1.0),
                    coat=_coat(shader, what, warnings),
                    layering=next(name for since, name in LAYERING_SINCE.items() if bpy.app.version >= since))


def _coat(shader, what: str, warnings: list[str]) -> Coat | None:
    """A Principled BSDF's coat, None where its Coat Weight is 0."""
    weight = max(_value(shader, "Coat Weight", what, warnings), 0.0)
    if weight == 0.0:
        return None
    return Coat(weight=weight, roughness=min(max(_value(shader, "Coat Roughness", what, warnings), 0.0), 1.0),
                ior=max(_value(shader, "Coat IOR", what, warnings), 1.0),
                tint=np.maximum(_value(shader, "Coat Tint", what, warnings), 0.0))


def _warn_unrendered(shader, unrendered: dict[str, float], rendered_as: str, what: str, warnings: list[str]) -> None:
    """One warning naming the inputs of `unrendered` (name: the value that
    leaves it out) that the Principled BSDF `shader` sets, and a linked
    Coat Normal, and how it is rendered instead."""
    names = [name for name, off in unrendered.items()
             if name in shader.inputs and _value(shader, name, what, warnings) != off]
    if "Coat Weight" not in unrendered and shader.inputs["Coat Normal"].is_linked:
        names.append("Coat Normal")
    if names:
        warnings.append(f"{what}: its {', '.join(names)} {'are' if len(names) > 1 else 'is'} not rendered; "
                        f"{rendered_as}")


def _mirror(shader, color_input: str, what: str, warnings: list[str]) -> Surface:
    """A reflector of the shader's colour and roughness."""
    color = _value(shader, color_input, what, warnings)
    roughness, multiscatter = _microfacets(shader, what, warnings)
    return Surface(transparent=False, reflector=True, color=np.clip(color, 0.0, 1.0), roughness=roughness,
                   multiscatter=multiscatter, warnings=warnings)


def _microfacets(shader, what: str, warnings: list[str]) -> tuple[float, bool]:
    """(Roughness clamped to 0..1, whether the distribution is Multiscatter
    GGX) of a glass, glossy or Principled node. A rough Beckmann or
    Ashikhmin-Shirley lobe is read as GGX, and an anisotropic one as
    isotropic, each named in a warning."""
    roughness = min(max(_value(shader, "Roughness", what, warnings), 0.0), 1.0)
    distribution = shader.distribution
    if roughness > 0.0 and distribution in OTHER_DISTRIBUTIONS:
        warnings.append(f"{what}: its {OTHER_DISTRIBUTIONS[distribution]} distribution is rendered as GGX")
    anisotropy = next((shader.inputs[name] for name in ANISOTROPY_INPUTS if name in shader.inputs), None)
    if roughness > 0.0 and anisotropy is not None and (anisotropy.is_linked or anisotropy.default_value != 0.0):
        warnings.append(f"{what}: its {anisotropy.name} is not rendered: its microfacets are isotropic")
    return roughness, distribution == 'MULTI_GGX'


def _dispersion(shader, what: str, warnings: list[str]) -> float:
    """The Abbe number V_d of a glass shader's own dispersion: OpenPBR's
    abbe_number / scale, with which Cycles refracts by Cauchy's law through
    the IOR at 587.6 nm, as the engine does (cauchy_ior); inf (none) where
    the shader has no such inputs, its scale is 0, or its Abbe number is not
    above 0 (Cycles renders no dispersion then either); a scale above 1 is
    1, as Cycles clamps it."""
    if DISPERSION_SCALE not in shader.inputs:
        return math.inf
    scale = min(_value(shader, DISPERSION_SCALE, what, warnings), 1.0)
    if not scale > 0.0:
        return math.inf
    abbe = _value(shader, DISPERSION_ABBE, what, warnings)
    return abbe / scale if abbe > 0.0 else math.inf


def _read_volume(material, what: str, warnings: list[str]) -> np.ndarray:
    """Absorption (3,) per metre of the material's volume: a Volume
    Absorption node's density x (1 - colour), as Cycles; none without one."""
    volume = _shader(material, 'Volume')
    if volume is None:
        return np.zeros(3)
    if volume.bl_idname != 'ShaderNodeVolumeAbsorption':
        warnings.append(f"{what}: a '{volume.name}' volume is not understood; only Volume Absorption is read, "
                        "so the glass is clear inside")
        return np.zeros(3)
    color = _value(volume, "Color", what, warnings)
    if np.any(color > 1.0):
        warnings.append(f"{what}: a Volume Absorption color above 1 would add light; it is read as 1")
    return volume_absorption(np.minimum(color, 1.0), _value(volume, "Density", what, warnings))


def engine_material(surface: Surface, settings,
                    texture: Optional[nodes.Node] = None) -> Dielectric | Diffuse | Reflector:
    """The engine material for an object of `Object.caustic` `settings`
    whose material reads as `surface`, its colour from `texture` (the
    surface's recipe bound to the object) if it has one. A glass's
    dispersion is its material's where that has one, else the object's
    Abbe Number (0: none)."""
    role = settings.role
    if role == 'REFLECTOR' or (role == 'AUTO' and surface.reflector):
        return Reflector(surface.color if surface.reflector else np.ones(3), surface.roughness, surface.multiscatter)
    transparent = role == 'TRANSPARENT' or (role == 'AUTO' and surface.transparent)
    if not transparent:
        opaque = not (surface.transparent or surface.reflector)
        # an emitting surface that reflects nothing (an Emission shader alone) shows no caustic, unless
        # asked to; a black one that emits nothing still receives, rendered black as in Cycles
        reflects = not opaque or np.any(surface.albedo > 0.0) or texture is not None or surface.specular is not None
        return Diffuse(albedo=surface.albedo if opaque else DEFAULT_ALBEDO, emission=surface.emission,
                       texture=texture if opaque else None, specular=surface.specular if opaque else None,
                       receiver=reflects or not np.any(surface.emission > 0.0) or role == 'RECEIVER')
    ior = settings.ior if settings.use_ior else (surface.ior if surface.transparent else 1.5)
    reflection_tint, transmission_tint = surface.tints if surface.transparent else (np.ones(3), np.ones(3))
    if settings.absorption_from == 'COLOR':
        absorption = absorption_from_color(settings.absorption_color[:], settings.absorption_distance)
    elif settings.absorption_from == 'COEFFICIENT':
        absorption = np.array(settings.absorption[:], dtype=np.float64)
    else:
        absorption = surface.absorption if surface.transparent else np.zeros(3)
    return Dielectric(ior=ior, reflection_tint=reflection_tint, transmission_tint=transmission_tint,
                      fresnel=surface.fresnel or not surface.transparent, absorption=absorption,
                      abbe=_abbe(surface, settings), roughness=surface.roughness,
                      multiscatter=surface.multiscatter)


def _abbe(surface: Surface, settings) -> float:
    """The Abbe number a glass object disperses with: its material's own
    where set, else its Object.caustic.abbe (0: none)."""
    if surface.transparent and math.isfinite(surface.abbe):
        return surface.abbe
    return settings.abbe if settings.abbe > 0 else math.inf


def abbe_conflict(surface: Surface, settings, name: str, material: Optional[str]) -> Optional[str]:
    """A warning where glass object `name`'s Abbe Number and its material's
    own dispersion are both set and differ (the material's is used), else None."""
    if not (surface.transparent and math.isfinite(surface.abbe) and settings.abbe > 0):
        return None
    if math.isclose(settings.abbe, surface.abbe, rel_tol=1e-6):
        return None
    return (f"'{name}': its Abbe Number {settings.abbe:.4g} differs from the dispersion of its material "
            f"'{material}' (Abbe Number {surface.abbe:.4g}, its Transmission Dispersion Abbe Number over its "
            "Scale); the material's is used")
