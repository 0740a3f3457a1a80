"""Per-path random numbers from a hash, so a path's choices depend only on its id."""

from __future__ import annotations

import numpy as np

from ..util.jit import inline, kernel


def stream_key(stream: int, seed: int) -> int:
    """The 64-bit constant that (stream, seed) adds to every id's product."""
    return (stream * 0x632BE59BD9B4E019 + seed * 0xD6E8FEB86659FD93) % (1 << 64)


@inline
def hash_uniform1(path_id, key):
    """A uniform float in (0,1) that depends only on (id, key): the
    splitmix64 finaliser (Steele et al. 2014) of id * golden + key, its top
    53 bits centred in their interval. `key` is stream_key(stream, seed)."""
    x = np.uint64(path_id) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(key)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    x ^= x >> np.uint64(31)
    return (np.float64(x >> np.uint64(11)) + 0.5) * (1.0 / (1 << 53))


def hash_uniform(ids: np.ndarray, stream: int, seed: int) -> np.ndarray:
    """(n,) uniform floats in (0,1) that depend only on (id, stream, seed)
    (hash_uniform1). A photon's random choices are then the same however
    the work is chunked."""
    out = np.empty(len(ids))
    _hash_rows(out, np.ascontiguousarray(ids, dtype=np.int64), np.uint64(stream_key(stream, seed)))
    return out


@kernel("void(f8[::1], i8[::1], u8)")
def _hash_rows(out, ids, key):
    for i in range(len(ids)):
        out[i] = hash_uniform1(ids[i], key)
