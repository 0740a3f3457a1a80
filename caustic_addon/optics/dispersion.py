"""A glass's index of refraction across the spectrum, from its Abbe number."""

from __future__ import annotations

import numpy as np

# Fraunhofer lines that define the Abbe number (nm): helium d, hydrogen F and C.
LAMBDA_D, LAMBDA_F, LAMBDA_C = 587.6, 486.1, 656.3


def cauchy_ior(ior_d, abbe, wavelength_nm):
    """Index of refraction at `wavelength_nm` of a glass given by its index
    n_d at 587.6 nm and its Abbe number V_d, by Cauchy's two-term law
    (Hecht, Optics, 3.5; Abbe number as in ISO 7944):

        n(lambda) = A + B / lambda^2
        V_d = (n_d - 1) / (n_F - n_C)   =>   B = (n_d - 1) / (V_d (1/lambda_F^2 - 1/lambda_C^2)),
                                             A = n_d - B / lambda_d^2

    An infinite Abbe number gives n_d at every wavelength. Broadcasts."""
    ior_d = np.asarray(ior_d, dtype=np.float64)
    b = (ior_d - 1.0) / (np.asarray(abbe, dtype=np.float64) * (LAMBDA_F ** -2 - LAMBDA_C ** -2))
    return ior_d + b * (np.asarray(wavelength_nm, dtype=np.float64) ** -2 - LAMBDA_D ** -2)
