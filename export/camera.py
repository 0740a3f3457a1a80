"""The scene's active camera at the render size, as the engine's Camera; what
of it the engine leaves out, as warnings; a stand-in for runs without one."""

import numpy as np

from ..caustic_addon import Camera
from .errors import InputError
from .matrices import numpy_matrix


def render_size(render) -> tuple[int, int]:
    """(pixx, pixy): the render resolution scaled by its percentage, as Blender computes it."""
    return (render.resolution_x * render.resolution_percentage // 100,
            render.resolution_y * render.resolution_percentage // 100)


def check_camera(scene) -> None:
    """InputError unless the scene has a camera that is a camera object."""
    if scene.camera is None:
        raise InputError("The scene has no active camera")
    if scene.camera.type != 'CAMERA':
        kind = (f"{scene.camera.data.type.lower()} light" if scene.camera.type == 'LIGHT'
                else f"object of type {scene.camera.type.lower()}")
        kind = ("an " if kind[0] in "aeiou" else "a ") + kind
        raise InputError(f"The scene's camera '{scene.camera.name}' is {kind}, not a camera: choose a camera "
                         "object in Scene Properties > Camera")


def check_render_size(render) -> None:
    """InputError unless the render size is at least one pixel each way:
    Blender would only say "Image too small"."""
    pixx, pixy = render_size(render)
    if pixx < 1 or pixy < 1:
        raise InputError(f"The render size is {pixx} x {pixy} pixels (Resolution {render.resolution_x} x "
                         f"{render.resolution_y} at {render.resolution_percentage}%): raise Resolution % or the "
                         "resolution X and Y (Output Properties) to make it at least 1 x 1")


def read_camera(scene, depsgraph) -> Camera:
    """The active camera at the render resolution."""
    check_camera(scene)
    camera = scene.camera.evaluated_get(depsgraph)
    data = camera.data
    if data.type not in ('PERSP', 'ORTHO'):
        raise InputError(f"'{scene.camera.name}' is a panoramic camera; only perspective and orthographic "
                         "cameras are supported")
    matrix = numpy_matrix(camera.matrix_world)
    matrix[:3, :3] /= np.linalg.norm(matrix[:3, :3], axis=0)
    pixx, pixy = render_size(scene.render)
    return Camera(matrix=matrix, pixx=pixx, pixy=pixy, kind=data.type, fov=data.angle, ortho_scale=data.ortho_scale,
                  sensor_fit=data.sensor_fit, shift_x=data.shift_x, shift_y=data.shift_y,
                  clip_start=data.clip_start, clip_end=data.clip_end)


def camera_warnings(scene) -> list[str]:
    """What of the camera and its render settings the engine does not render."""
    warnings = []
    if scene.render.pixel_aspect_x != scene.render.pixel_aspect_y:
        warnings.append("non-square pixels (Pixel Aspect) are rendered square")
    if scene.camera is not None and scene.camera.type == 'CAMERA' and scene.camera.data.dof.use_dof:
        warnings.append(f"'{scene.camera.name}': depth of field is not rendered")
    return warnings


def dummy_camera() -> Camera:
    """A one-pixel camera, for runs that only need the photon pass."""
    return Camera(matrix=np.eye(4), pixx=1, pixy=1)
