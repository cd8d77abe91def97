"""Frames grouped by message: the compiled table against pandas' factorisation and a stable sort."""

from __future__ import annotations

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.ingest.can.grouping import group_by_message


def _reference(ids: np.ndarray, ext: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What assemble_can did before: pd.factorize, a stable argsort, a bincount."""
    key = ids.astype(np.int64) | (ext.astype(np.int64) << 32)
    codes, uniques = pd.factorize(key)
    order = np.argsort(codes, kind="stable")
    bounds = np.r_[0, np.cumsum(np.bincount(codes, minlength=len(uniques)))]
    return order, bounds, np.asarray(uniques, np.int64)


@given(n=st.integers(0, 3000), n_ids=st.integers(1, 700), seed=st.integers(0, 2**32 - 1))
@settings(max_examples=200, deadline=None)
def test_groups_equal_factorize_and_stable_sort(n, n_ids, seed):
    """Any number of distinct keys, identifiers up to 29 bits, standard and extended.

    The table grows past 32, 64, ... keys; one identifier may come both ways.
    """
    rng = np.random.default_rng(seed)
    pool = rng.integers(0, 1 << 29, n_ids, dtype=np.uint32)
    ids = pool[rng.integers(0, n_ids, n)]
    ext = rng.random(n) < 0.3
    got = group_by_message(ids, ext)
    want = _reference(ids, ext)
    for g, w in zip(got, want, strict=True):
        assert np.array_equal(g, w)


def test_one_message_and_none():
    order, bounds, keys = group_by_message(np.full(5, 0x100, np.uint32), np.zeros(5, bool))
    assert order.tolist() == [0, 1, 2, 3, 4] and bounds.tolist() == [0, 5]
    assert keys.tolist() == [0x100]
    order, bounds, keys = group_by_message(np.zeros(0, np.uint32), np.zeros(0, bool))
    assert order.size == 0 and bounds.tolist() == [0] and keys.size == 0
    _, _, keys = group_by_message(np.array([7, 7], np.uint32), np.array([True, False]))
    assert keys.tolist() == [7 | 1 << 32, 7]
