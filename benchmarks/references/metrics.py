"""The accuracy metrics the benchmarks and tests use: the relative L2 error
of radially averaged caustic irradiance against the exact reference, over
the caustic region (the sphere's shadow disc), weighted by annulus area
(`relative_l2`); and the relative L2 error of an image against a reference
image over a region of pixels (`region_relative_l2`)."""

from __future__ import annotations

import numpy as np


def annulus_points(r_edges: np.ndarray, per_annulus: int, seed: int = 0) -> np.ndarray:
    """(m * per_annulus, 2) points uniform in area within each of the m
    annuli `r_edges (m+1,)` around the origin, annulus by annulus. The axis
    singularity of a lens caustic makes any other sampling biased."""
    rng = np.random.default_rng(seed)
    m = len(r_edges) - 1
    inner, outer = r_edges[:-1, None] ** 2, r_edges[1:, None] ** 2
    r = np.sqrt(inner + rng.random((m, per_annulus)) * (outer - inner))
    angle = 2 * np.pi * rng.random((m, per_annulus))
    return np.stack([r * np.cos(angle), r * np.sin(angle)], axis=-1).reshape(-1, 2)


def annulus_means(values: np.ndarray, r_edges: np.ndarray) -> np.ndarray:
    """(m,) means of `values` sampled at `annulus_points(r_edges, ...)`."""
    return values.reshape(len(r_edges) - 1, -1).mean(axis=1)


def relative_l2(estimate: np.ndarray, reference: np.ndarray, r_edges: np.ndarray) -> float:
    """sqrt(sum A_i (e_i - r_i)^2 / sum A_i r_i^2) over annuli of area A_i."""
    area = np.diff(r_edges ** 2)
    return float(np.sqrt(np.sum(area * (estimate - reference) ** 2) / np.sum(area * reference ** 2)))


def region_relative_l2(image: np.ndarray, reference: np.ndarray, region: np.ndarray) -> float:
    """||image - reference|| / ||reference|| over the pixels of `region`
    ((h,w) bool), for images of the same shape: a caustic against its
    reference, pixel by pixel."""
    difference = (image - reference)[region]
    return float(np.sqrt(np.sum(difference ** 2) / np.sum(reference[region] ** 2)))
