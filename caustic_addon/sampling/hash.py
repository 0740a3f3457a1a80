"""Per-path random numbers from a hash, so a path's choices depend only on its id."""

from __future__ import annotations

import numpy as np


def hash_uniform(ids: np.ndarray, stream: int, seed: int) -> np.ndarray:
    """(n,) uniform floats in (0,1) that depend only on (id, stream, seed):
    the splitmix64 finaliser (Steele et al. 2014) of their combination. A
    photon's random choices are then the same however the work is chunked."""
    with np.errstate(over="ignore"):
        x = (ids.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
             + np.uint64((stream * 0x632BE59BD9B4E019 + seed * 0xD6E8FEB86659FD93) % (1 << 64)))
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
    return ((x >> np.uint64(11)).astype(np.float64) + 0.5) * (1.0 / (1 << 53))
