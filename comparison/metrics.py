"""How far the caustic render is from the Cycles reference. Images are
(h,w,3) or (h,w,4) float linear; only RGB is compared."""

import math

import numpy as np

# A pixel is in the caustic region when its caustic radiance is above this
# share of the brightest caustic pixel.
REGION_SHARE = 0.01


def caustic_region(caustic: np.ndarray) -> np.ndarray:
    """(h,w) bool: the pixels the caustics light; all of them if there is no caustic."""
    level = caustic[..., :3].sum(axis=-1)
    peak = level.max()
    return level > REGION_SHARE * peak if peak > 0 else np.ones(level.shape, dtype=bool)


def relative_l2(image: np.ndarray, reference: np.ndarray, region: np.ndarray) -> float:
    """|image - reference| / |reference| over `region (h,w)`, RGB together."""
    difference = image[..., :3][region] - reference[..., :3][region]
    norm = float(np.linalg.norm(reference[..., :3][region]))
    return float(np.linalg.norm(difference)) / norm if norm > 0 else math.inf


def psnr(image: np.ndarray, reference: np.ndarray) -> float:
    """Peak signal-to-noise ratio in dB over the whole image, the peak being the reference's brightest value."""
    mse = float(np.mean((image[..., :3] - reference[..., :3]) ** 2))
    peak = float(reference[..., :3].max())
    return 10.0 * math.log10(peak * peak / mse) if mse > 0 and peak > 0 else math.inf
