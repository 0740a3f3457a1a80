"""Picking and labelling rows of arrays: compiled gathers (np.take of rows
of 3 values is 4 to 5 times slower, np.flatnonzero up to 9 times on numpy
1.24) and the numpy idioms that stay fast."""

from __future__ import annotations

import numpy as np

from .jit import kernel


@kernel("i8[::1](b1[::1])")
def true_rows(mask):
    """(k,) int64 the indices where `mask (n,)` is True, ascending
    (np.flatnonzero), written without a branch."""
    out = np.empty(len(mask) + 1, dtype=np.int64)
    k = 0
    for j in range(len(mask)):
        out[k] = j
        k += mask[j]
    return out[:k]


@kernel("void(i1[::1], i8[::1], i8[::1])")
def partition(group, order, ends):
    """Group the rows by `group (n,)`, values 0 .. g-1: `order (n,)` gets
    the rows of group 0, then of group 1, ..., each in their order (a
    stable counting sort); `ends (g,)` where each group's rows end in it."""
    ends[:] = 0
    for i in range(len(group)):
        ends[group[i]] += 1
    for g in range(1, len(ends)):
        ends[g] += ends[g - 1]
    place = np.empty(len(ends), dtype=np.int64)
    place[0] = 0
    place[1:] = ends[:-1]
    for i in range(len(group)):
        order[place[group[i]]] = i
        place[group[i]] += 1


@kernel("void(f8[::1], i8[::1], f8[::1])", "void(i8[::1], i8[::1], i8[::1])", "void(b1[::1], i8[::1], b1[::1])",
        "void(u8[::1], i8[::1], u8[::1])", "void(i1[::1], i8[::1], i1[::1])")
def _take_values(a, index, out):
    for k in range(len(index)):
        out[k] = a[index[k]]


@kernel("void(f8[:, ::1], i8[::1], f8[:, ::1])", "void(f4[:, ::1], i8[::1], f4[:, ::1])")
def _take_vectors(a, index, out):
    for k in range(len(index)):
        j = index[k]
        for c in range(a.shape[1]):
            out[k, c] = a[j, c]


def take(a: np.ndarray, index: np.ndarray) -> np.ndarray:
    """The rows `index (k,)` int64 of `a`, as np.take(a, index, axis=0): `a`
    (n,) of a kernel's dtypes, or (n,...) float64 or float32."""
    a = np.ascontiguousarray(a)
    out = np.empty((len(index),) + a.shape[1:], dtype=a.dtype)
    if a.ndim == 1:
        _take_values(a, index, out)
    else:
        width = int(np.prod(a.shape[1:]))
        _take_vectors(a.reshape(len(a), width), index, out.reshape(len(index), width))
    return out


def take_rows(mask: np.ndarray, *arrays: np.ndarray) -> list[np.ndarray]:
    """The rows of each of `arrays` where `mask (n,)` is True: the arrays
    themselves, not copies, where it is True throughout."""
    index = true_rows(np.ascontiguousarray(mask, dtype=bool))
    return list(arrays) if len(index) == len(mask) else [take(a, index) for a in arrays]


def contiguous(a, dtype) -> np.ndarray:
    """`a` as a writeable C-contiguous array of `dtype`, the form the
    kernels' signatures take, copied only where it is not one already."""
    a = np.ascontiguousarray(a, dtype=dtype)
    return a if a.flags.writeable else a.copy()


def row_ids(rows: np.ndarray) -> np.ndarray:
    """(n,) int64 labels of `rows (n,k)`, equal exactly where the rows are
    equal: a lexicographic sort, then a new label wherever a row differs
    from the one before (much faster than np.unique(axis=0))."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    new = np.concatenate([[True], (ordered[1:] != ordered[:-1]).any(axis=1)])
    ids = np.empty(len(rows), dtype=np.int64)
    ids[order] = np.cumsum(new) - 1
    return ids
