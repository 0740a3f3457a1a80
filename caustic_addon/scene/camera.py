"""Blender's camera: pinhole or orthographic, with its view plane."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np


@dataclass
class Camera:
    """A camera as Blender's: it looks down its local -Z with +Y up.

    matrix        (4,4) camera-to-world, rotation and translation only
    kind          'PERSP' (pinhole) or 'ORTHO'
    fov           full field of view along the sensor-fit axis, radians
    ortho_scale   width of the view along the sensor-fit axis, metres
    sensor_fit    'AUTO' (the larger image side), 'HORIZONTAL' or 'VERTICAL'
    shift_x/y     lens shift, in units of the sensor-fit side, as Blender's
    pixx, pixy    image width and height in pixels (the paper's names)
    """

    matrix: np.ndarray
    pixx: int = 640
    pixy: int = 480
    kind: Literal["PERSP", "ORTHO"] = "PERSP"
    fov: float = math.radians(39.6)
    ortho_scale: float = 6.0
    sensor_fit: Literal["AUTO", "HORIZONTAL", "VERTICAL"] = "AUTO"
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 1e-3
    clip_end: float = 1e30

    def __post_init__(self):
        self.matrix = np.asarray(self.matrix, dtype=np.float64).reshape(4, 4)

    @property
    def position(self) -> np.ndarray:
        return self.matrix[:3, 3]

    @staticmethod
    def look_at(eye, target, up=(0.0, 0.0, 1.0), **kwargs) -> "Camera":
        """A camera at `eye` looking at `target`, with `up` as near to its +Y as possible."""
        eye = np.asarray(eye, dtype=np.float64)
        back = eye - np.asarray(target, dtype=np.float64)
        if not np.linalg.norm(back) > 0:
            raise ValueError("camera: the eye and the point it looks at must differ")
        back /= np.linalg.norm(back)
        right = np.cross(np.asarray(up, dtype=np.float64), back)
        if np.linalg.norm(right) < 1e-9:
            right = np.cross(np.array([0.0, 1.0, 0.0]), back)
        right /= np.linalg.norm(right)
        matrix = np.eye(4)
        matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = right, np.cross(back, right), back, eye
        return Camera(matrix=matrix, **kwargs)

    @staticmethod
    def from_paper(FOV, pixx, pixy, S, eye, target, up=(0.0, 0.0, 1.0)) -> "Camera":
        """The paper's camera: FOV in degrees across the width, an image of
        pixx x pixy pixels and a screen of width S world units.

        The screen sits at distance S / (2 tan(FOV/2)) from the eye, so S
        scales the screen and its distance together; for a pinhole the image
        does not depend on it.
        """
        if S <= 0:
            raise ValueError("screen size S must be positive")
        return Camera.look_at(eye, target, up, pixx=int(pixx), pixy=int(pixy), fov=math.radians(FOV),
                              sensor_fit="HORIZONTAL")
