"""util/rows.py's compiled gathers pick the rows numpy would, in numpy's order."""

import numpy as np
import pytest

from caustic_addon.util.rows import partition, take, take_rows, true_rows


@pytest.mark.parametrize("share", [0.0, 0.03, 0.5, 1.0])
def test_true_rows_are_flatnonzero(share):
    mask = np.random.default_rng(1).random(1001) < share
    assert np.array_equal(true_rows(mask), np.flatnonzero(mask))


def test_take_is_np_take_for_each_column_kind():
    rng = np.random.default_rng(2)
    index = np.flatnonzero(rng.random(500) < 0.4)[::-1].copy()
    columns = [rng.random((500, 3)), rng.random((500, 3, 2)), rng.random(500), rng.random(500) < 0.5,
               rng.integers(-1, 9, 500), rng.integers(0, 1 << 62, 500).astype(np.uint64),
               rng.integers(0, 3, 500).astype(np.int8), np.zeros((500, 3))[:, ::2]]
    for column in columns:
        picked = take(column, index)
        assert picked.dtype == column.dtype and np.array_equal(picked, np.take(column, index, axis=0))
    assert all(len(a) == 0 for a in take_rows(np.zeros(500, dtype=bool), *columns))


def test_partition_is_a_stable_sort_by_group():
    group = np.random.default_rng(3).integers(0, 3, 999).astype(np.int8)
    group[group == 1] = 2  # an empty group keeps its place
    order, ends = np.empty(999, dtype=np.int64), np.empty(3, dtype=np.int64)
    partition(group, order, ends)
    assert np.array_equal(order, np.argsort(group, kind="stable"))
    assert np.array_equal(ends, np.cumsum(np.bincount(group, minlength=3)))
