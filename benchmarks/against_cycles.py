"""Figures of a render against a Cycles reference, shared by the benchmarks
that compare caustics with Cycles (emitters.py, sky_caustics.py,
liquid_glass.py), and the comparison the first two run and record."""

from __future__ import annotations

import tempfile
from typing import Callable, Optional

import numpy as np

from benchmarks import record
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


def record_against_cycles(name: str, scene: str, renders: dict, defaults: str,
                          cycles: Callable[[int, int, str], tuple[np.ndarray, float]], reference_samples: int,
                          sweep: list[int], side_by_side: Optional[str]) -> None:
    """Record the add-on's `renders` ({name: (image, caustic pass, seconds)})
    of `scene` against Cycles, `cycles(samples, seed, folder)` giving
    (image, seconds): the reference at `reference_samples` (seed 0), its own
    noise from a second seed, and the `sweep` of samples (seed 2), each
    render's `figures` over the image and over the caustic, the pixels where
    the `defaults` render's caustic pass holds at least a tenth of its
    brightest. Writes results/<name>.json, prints the figures, and where
    `side_by_side` names a PNG, the defaults' image beside the reference."""
    caustic_pass = renders[defaults][1].sum(axis=-1)
    caustic = caustic_pass >= 0.1 * caustic_pass.max()
    with tempfile.TemporaryDirectory() as folder:
        reference, reference_s = cycles(reference_samples, 0, folder)
        second, _ = cycles(reference_samples, 1, folder)
        swept = {samples: figures(*cycles(samples, 2, folder), reference, caustic) for samples in sweep}
    results = {key: figures(image, seconds, reference, caustic) for key, (image, _, seconds) in renders.items()}
    path = record.write(name, {
        "scene": scene, "caustic_pixels": int(caustic.sum()),
        "cycles_reference": {"samples": reference_samples, "seconds": reference_s,
                             **reference_noise(reference, second, caustic)},
        "ours": results, "cycles": {str(s): f for s, f in swept.items()}})
    print(f"wrote {path}")
    for key, f in {**results, **{f"Cycles {s}": f for s, f in swept.items()}}.items():
        print(f"{key}: mean x{f['mean_ratio']:.3f}, L2 {f['relative_l2']:.1%}, "
              f"caustic L2 {f['caustic_relative_l2']:.1%}, {f['seconds']:.2f} s")
    if side_by_side:
        write_pair(side_by_side, renders[defaults][0], reference)
