"""How far the caustic render is from the Cycles reference, and how far the
reference is from its own limit. Images are (h,w,3) or (h,w,4) float
linear; only RGB is compared. Regions and masks are (h,w) bool."""

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


def relative_l2(image: np.ndarray, reference: np.ndarray, region: np.ndarray,
                of: np.ndarray | None = None) -> float:
    """|image - reference| / |of| over `region`, RGB together; `of` is the
    reference unless given (the reference's caustic light, say)."""
    difference = image[..., :3][region] - reference[..., :3][region]
    norm = float(np.linalg.norm((reference if of is None else of)[..., :3][region]))
    return float(np.linalg.norm(difference)) / norm if norm > 0 else math.inf


def half_renders_noise(first: np.ndarray, second: np.ndarray, region: np.ndarray, of: np.ndarray) -> float:
    """The noise of the mean M = (A + B) / 2 of two renders A, B of the same
    samples and different seeds, relative to |of| over `region`:
    |A - B| / 2 / |of|. A and B are independent with the same mean and
    variance, so E[(A - B)^2] = 4 Var(M) per pixel; an image's squared
    L2 distance from M is its own from M's mean plus this one's square, on
    average."""
    norm = float(np.linalg.norm(of[..., :3][region]))
    return 0.5 * float(np.linalg.norm(first[..., :3][region] - second[..., :3][region])) / norm if norm > 0 \
        else math.inf


def light(image: np.ndarray, region: np.ndarray) -> float:
    """The sum of the RGB radiance over `region`."""
    return float(image[..., :3][region].sum(dtype=np.float64))


def half_renders_light_noise(first: np.ndarray, second: np.ndarray, region: np.ndarray) -> float:
    """The standard deviation of light(M, region), M = (A + B) / 2: pixels
    are independent, and each one's (a - b)^2 / 4 estimates its variance
    (a, b: the pixel's RGB sums)."""
    a = first[..., :3][region].sum(axis=-1, dtype=np.float64)
    b = second[..., :3][region].sum(axis=-1, dtype=np.float64)
    return 0.5 * math.sqrt(float(((a - b) ** 2).sum()))


def psnr(image: np.ndarray, reference: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Peak signal-to-noise ratio in dB over the pixels of `mask` (all without
    one), the peak being the reference's brightest value there."""
    if mask is None:
        mask = np.ones(image.shape[:2], dtype=bool)
    mse = float(np.mean((image[..., :3][mask] - reference[..., :3][mask]) ** 2))
    peak = float(reference[..., :3][mask].max())
    return 10.0 * math.log10(peak * peak / mse) if mse > 0 and peak > 0 else math.inf
