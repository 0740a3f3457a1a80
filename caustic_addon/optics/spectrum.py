"""Wavelength bands for dispersion: which wavelengths the photon pass traces
and how each one's light adds up to linear Rec.709 RGB.

The visible spectrum (360-830 nm) is cut into K bands that carry equal
shares of light. A band's RGB weight is the integral over the band of the CIE
1931 colour matching functions, converted from XYZ to linear Rec.709 with
negative (out-of-gamut) parts clipped; each channel is then divided by its
integral over the whole spectrum, so the K weights sum to exactly (1,1,1): a
white photon split over the bands stays white, and with no dispersion a
spectral render equals the plain one. The band edges are where the summed
weight's cumulative share crosses 1/K, 2/K, ...; each band is traced at its
weighted mean wavelength.

With K = 1 (no dispersive material in the scene) the single band has weight
(1,1,1) and the wavelength 587.6 nm at which a material's IOR is given.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..sampling.hash import hash_uniform
from .dispersion import LAMBDA_D

# linear Rec.709 (sRGB primaries, D65) from CIE XYZ (IEC 61966-2-1)
XYZ_TO_REC709 = np.array([[3.2404542, -1.5371385, -0.4985314],
                          [-0.9692660, 1.8760108, 0.0415560],
                          [0.0556434, -0.2040259, 1.0572252]])
VISIBLE_NM = (360.0, 830.0)
# the random stream that picks a photon's band (the transport uses 0 .. 2 max_depth + 1)
_BAND_STREAM = 1 << 20


def cie_xyz(wavelength_nm: np.ndarray) -> np.ndarray:
    """(n,3) CIE 1931 2-degree colour matching functions x, y, z at
    `wavelength_nm (n,)`: the multi-lobe piecewise Gaussian fit of Wyman,
    Sloan and Shirley, "Simple Analytic Approximations to the CIE XYZ Color
    Matching Functions", JCGT 2(2), 2013, eqs. 2-4:

        g(l; mu, s1, s2) = exp(-(l - mu)^2 / (2 s^2)), s = s1 below mu, s2 above
        x = 1.056 g(599.8, 37.9, 31.0) + 0.362 g(442.0, 16.0, 26.7) - 0.065 g(501.1, 20.4, 26.2)
        y = 0.821 g(568.8, 46.9, 40.5) + 0.286 g(530.9, 16.3, 31.1)
        z = 1.217 g(437.0, 11.8, 36.0) + 0.681 g(459.0, 26.0, 13.8)
    """
    lam = np.asarray(wavelength_nm, dtype=np.float64)

    def g(mu, s1, s2):
        return np.exp(-0.5 * ((lam - mu) / np.where(lam < mu, s1, s2)) ** 2)

    x = 1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2)
    y = 0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1)
    z = 1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


@dataclass(frozen=True)
class Bands:
    """K wavelength bands: `wavelengths (K,)` nm, increasing; `weights (K,3)`
    linear Rec.709, each >= 0, summing over the bands to (1,1,1)."""

    wavelengths: np.ndarray
    weights: np.ndarray

    @property
    def count(self) -> int:
        return len(self.wavelengths)


@lru_cache(maxsize=None)
def bands(count: int) -> Bands:
    """`count` bands of equal light (see the module's docstring)."""
    if count == 1:
        return Bands(np.array([LAMBDA_D]), np.ones((1, 3)))
    lam = np.arange(VISIBLE_NM[0], VISIBLE_NM[1] + 0.25, 0.5)
    rgb = np.maximum(cie_xyz(lam) @ XYZ_TO_REC709.T, 0.0)
    rgb /= rgb.sum(axis=0)
    share = rgb.sum(axis=1)
    cdf = np.cumsum(share) / share.sum()
    band = np.minimum((cdf * count - 1e-9).astype(np.int64), count - 1)
    weights = np.stack([rgb[band == b].sum(axis=0) for b in range(count)])
    wavelengths = np.array([np.average(lam[band == b], weights=share[band == b]) for b in range(count)])
    return Bands(wavelengths, weights / weights.sum(axis=0))


def photon_band(ids: np.ndarray, count: int, seed: int) -> np.ndarray:
    """(n,) band of each photon `ids (n,)`: stratified, so every run of
    `count` consecutive ids (id // count equal) takes each band once, in an
    order shifted by a hash of the run. Depends on the id alone, like every
    other choice a photon makes."""
    if count == 1:
        return np.zeros(len(ids), dtype=np.int64)
    shift = (hash_uniform(ids // count, _BAND_STREAM, seed) * count).astype(np.int64)
    return (ids + shift) % count
