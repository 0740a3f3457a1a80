"""Figures of a render against a Cycles reference, shared by the benchmarks
that compare caustics with Cycles (emitters.py, liquid_glass.py)."""

from __future__ import annotations

import numpy as np

from caustic_addon.cli.image_io import write_image


def relative_l2(image: np.ndarray, reference: np.ndarray) -> float:
    return float(np.linalg.norm(image - reference) / np.linalg.norm(reference))


def figures(image: np.ndarray, seconds: float, reference: np.ndarray, caustic: np.ndarray) -> dict:
    """The time, and the mean ratio and relative L2 error against
    `reference` over the image and over the pixels `caustic (h,w)` bool."""
    return {"seconds": seconds, "mean_ratio": float(image.mean() / reference.mean()),
            "relative_l2": relative_l2(image, reference),
            "caustic_mean_ratio": float(image[caustic].mean() / reference[caustic].mean()),
            "caustic_relative_l2": relative_l2(image[caustic], reference[caustic])}


def reference_noise(reference: np.ndarray, second: np.ndarray, caustic: np.ndarray) -> dict:
    """The reference's own relative L2 noise, over the image and the
    caustic, from a `second` render of another seed: the difference of two
    has sqrt(2) times the noise of one."""
    return {"relative_l2_noise": relative_l2(second, reference) / np.sqrt(2.0),
            "caustic_relative_l2_noise": relative_l2(second[caustic], reference[caustic]) / np.sqrt(2.0)}


def write_pair(path: str, left: np.ndarray, right: np.ndarray) -> None:
    """`left` and `right` (h,w,3) side by side, opaque, as an image file."""
    pair = np.concatenate([left, right], axis=1)
    write_image(path, np.concatenate([pair, np.ones(pair.shape[:2] + (1,))], axis=2))
