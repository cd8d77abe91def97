"""The builder adopts one gap-free float64 block instead of copying it (memory of issue 11).

The adopted channel must be exactly what the copying path gives, non-finite samples included.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigtools.ingest import IngestReport, Provenance, RunMetadata
from rigtools.ingest.builder import RecordingBuilder


def _build(index, values, conversion=()):
    rep = IngestReport()
    b = RecordingBuilder("mem", rep)
    b.add_samples("acc", "m/s^2", 1000.0, index, values, conversion=conversion)
    prov = Provenance("mem", "0" * 64, 0, "test", {}, rep)
    return b.build(RunMetadata(run_id="r1"), prov).channels["acc"], rep


def test_single_float64_block_is_adopted_not_copied():
    v = np.arange(1000.0)
    ch, rep = _build(7, v)
    assert np.shares_memory(ch.values, v)
    assert ch.first_index == 7 and ch.valid.all() and not rep.rejected


def test_adopted_block_still_counts_non_finite_samples():
    v = np.arange(10.0)
    v[[2, 5]] = [np.nan, np.inf]
    ch, rep = _build(0, v)
    assert np.shares_memory(ch.values, v)
    assert ch.valid.tolist() == [i not in (2, 5) for i in range(10)]
    assert rep.rejected["non_finite_sample"] == 2


@pytest.mark.parametrize(
    "index, values, conversion",
    [
        (0, np.arange(10, dtype=np.int16), ()),  # integers: converted, never adopted
        (0, np.arange(10.0), ((2.0, 1.0),)),  # a conversion to apply
        (0, np.arange(10.0)[::2], ()),  # not contiguous
    ],
)
def test_other_blocks_are_copied_and_equal(index, values, conversion):
    ch, _ = _build(index, values, conversion)
    assert not np.shares_memory(ch.values, values)
    expected = np.asarray(values, float)
    for scale, offset in conversion:
        expected = expected * scale + offset
    np.testing.assert_array_equal(ch.values, expected)


def test_per_sample_indices_with_a_hole_are_copied_with_the_gap():
    v = np.arange(10.0)
    idx = np.r_[np.arange(5), np.arange(6, 11)]
    ch, rep = _build(idx, v)
    assert not np.shares_memory(ch.values, v)
    assert np.isnan(ch.values[5]) and not ch.valid[5]
    np.testing.assert_array_equal(ch.values[ch.valid], v)
    assert [(g.start_index, g.n_missing) for g in rep.gaps] == [(5, 1)]
