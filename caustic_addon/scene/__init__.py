"""The scene model: plain data in world space, what the engine renders.
Units follow Blender: metres, radians, watts; colours are linear Rec.709."""

from . import paper, shapes, textures
from .camera import Camera
from .geometry import Mesh
from .lights import AreaLight, Light, MeshLight, PointLight, SpotLight, SunLight, World
from .materials import Coat, Dielectric, Diffuse, Material, Reflector, Specular
from .scene import Instances, Object, Scene, Visibility
from .settings import RenderSettings

__all__ = ["AreaLight", "Camera", "Coat", "Dielectric", "Diffuse", "Instances", "Light", "Material", "Mesh",
           "MeshLight", "Object", "PointLight", "Reflector", "RenderSettings", "Scene", "Specular", "SpotLight",
           "SunLight", "Visibility", "World", "paper", "shapes", "textures"]
