"""``take_rows`` and ``byte_rows`` (rows moved as one void item each) against NumPy."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from rigtools.ingest.can.frames import byte_rows, take_rows


@pytest.mark.parametrize("width", [1, 3, 8, 12, 64])
@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.float64])
def test_rows_by_index_and_by_mask_equal_numpy(width, dtype):
    rng = np.random.default_rng(width)
    a = rng.integers(0, 200, (500, width)).astype(dtype)
    idx = rng.integers(0, 500, 700)          # repeats and any order
    mask = rng.random(500) < 0.3
    for rows in (idx, mask, idx[:0], np.zeros(500, bool)):
        got = take_rows(a, rows)
        assert got.dtype == a.dtype and got.shape == a[rows].shape
        assert np.array_equal(got, a[rows])


def test_views_that_are_not_c_contiguous_and_empty_widths_take_numpy_s_path():
    a = np.arange(80, dtype=np.uint8).reshape(10, 8)
    rows = np.array([3, 1, 3])
    for view in (a[:, :5], a[::2], a.T, np.zeros((10, 0), np.uint8)):
        k = rows[rows < view.shape[0]]
        assert np.array_equal(take_rows(view, k), view[k])


@pytest.mark.parametrize("width", [1, 7, 8, 40, 64])
def test_byte_rows_equal_the_rows_of_a_sliding_window(width):
    rng = np.random.default_rng(width)
    buf = rng.integers(0, 256, 300, np.uint8).tobytes()
    offs = rng.integers(0, 300 - width + 1, 500)
    want = sliding_window_view(np.frombuffer(buf, np.uint8), width)[offs]
    for b in (buf, memoryview(buf), np.frombuffer(buf, np.uint8)):
        got = byte_rows(b, offs, width)
        assert got.dtype == np.uint8 and np.array_equal(got, want)
    assert byte_rows(buf, offs[:0], width).shape == (0, width)


def test_byte_rows_past_the_end_are_an_error_not_garbage():
    with pytest.raises(IndexError):
        byte_rows(b"abc", np.array([0]), 8)
    with pytest.raises(IndexError):
        byte_rows(b"abcdefgh", np.array([1]), 8)
    assert byte_rows(b"abc", np.array([0, 2]), 0).shape == (2, 0)
