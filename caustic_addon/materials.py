"""Per-object material tables, so both passes look materials up by object
index in one numpy gather instead of a Python loop per hit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import Object


@dataclass
class Materials:
    """Indexed by object index (m objects).

    dielectric (m,) bool        reflector (m,) bool        receiver (m,) bool
    specular_surface (m,) bool  dielectric or reflector: rays scatter there
    ior (m,)                    color (m,3): glass tint or reflectance
    absorption (m,3) per metre
    albedo (m,3)                specular (m,3), exponent (m,)
    """

    dielectric: np.ndarray
    reflector: np.ndarray
    receiver: np.ndarray
    ior: np.ndarray
    color: np.ndarray
    absorption: np.ndarray
    albedo: np.ndarray
    specular: np.ndarray
    exponent: np.ndarray

    @staticmethod
    def of(objects: list[Object]) -> "Materials":
        def column(name, default):
            return np.array([getattr(o.material, name, default) for o in objects], dtype=np.float64)

        def rgb_column(name, default):
            return column(name, np.full(3, default)).reshape(-1, 3)

        return Materials(
            dielectric=np.array([o.is_transparent for o in objects], dtype=bool),
            reflector=np.array([o.is_reflector for o in objects], dtype=bool),
            receiver=np.array([o.is_receiver for o in objects], dtype=bool),
            ior=column("ior", 1.0),
            color=rgb_column("color", 1.0),
            absorption=rgb_column("absorption", 0.0),
            albedo=rgb_column("albedo", 0.0),
            specular=rgb_column("specular", 0.0),
            exponent=column("exponent", 1.0),
        )

    @property
    def specular_surface(self) -> np.ndarray:
        return self.dielectric | self.reflector
