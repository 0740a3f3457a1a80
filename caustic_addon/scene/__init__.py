"""The scene model: plain data in world space, what the engine renders.
Units follow Blender: metres, radians, watts; colours are linear Rec.709."""

from . import paper, shapes
from .camera import Camera
from .geometry import Mesh
from .lights import Light, PointLight, SpotLight, SunLight
from .materials import Dielectric, Diffuse, Material, Reflector
from .scene import Object, Scene
from .settings import RenderSettings

__all__ = ["Camera", "Dielectric", "Diffuse", "Light", "Material", "Mesh", "Object", "PointLight", "Reflector",
           "RenderSettings", "Scene", "SpotLight", "SunLight", "paper", "shapes"]
