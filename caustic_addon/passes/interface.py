"""The state of n rays where they meet specular surfaces: the struct of
arrays that passes/bounce.py orients and scatters."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..util.rows import take_rows


@dataclass
class Interface:
    """n rays at specular hits, oriented.

    points      (n,3) world hit points
    facing      (n,3) geometric normal on the side the ray comes from
    shading     (n,3) shading normal on that same side
    entering    (n,) bool: the ray goes from outside the object to inside
    eta         (n,) eta_i / eta_t for this crossing
    fresnel     (n,) unpolarised reflectance at `scattering`; 1 under total
                internal reflection and at reflectors
    alpha       (n,) GGX width; 0 where the surface is smooth
    scattering  (n,3) the normal the ray scatters about: the shading normal,
                or where rough a microfacet normal drawn by `facets`
    beyond      (n,) the closed object (MISS: air) a ray that crosses is in
                next, and `beneath` (n,) the one it is also in beneath
                that (Paths.medium and Paths.outer)
    joined      (n,) the object whose surface lies against this one where
                the ray crosses, glass into water (bounce.orient): its
                transmission tint applies too; MISS where none
    """

    points: np.ndarray
    facing: np.ndarray
    shading: np.ndarray
    entering: np.ndarray
    eta: np.ndarray
    fresnel: np.ndarray
    alpha: np.ndarray
    scattering: np.ndarray
    beyond: np.ndarray
    beneath: np.ndarray
    joined: np.ndarray

    @property
    def rough(self) -> np.ndarray:
        """(n,) bool: the rows whose surface is rough."""
        return self.alpha > 0.0

    def select(self, mask: np.ndarray) -> "Interface":
        return Interface(*take_rows(mask, self.points, self.facing, self.shading, self.entering, self.eta,
                                    self.fresnel, self.alpha, self.scattering, self.beyond, self.beneath,
                                    self.joined))


# The numba type of each field, for the kernels that take them by name
# (util.jit.named_kernel).
INTERFACE_TYPES = {"points": "f8[:, ::1]", "facing": "f8[:, ::1]", "shading": "f8[:, ::1]", "entering": "b1[::1]",
                   "eta": "f8[::1]", "fresnel": "f8[::1]", "alpha": "f8[::1]", "scattering": "f8[:, ::1]",
                   "beyond": "i8[::1]", "beneath": "i8[::1]", "joined": "i8[::1]"}
