"""RecordingBuilder (grid, gaps, duplicates, non-finite) and the Parquet round trip."""

import hashlib
import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from rigtools.errors import RecordingFormatError
from rigtools.ingest import IngestReport, Provenance, RunMetadata, read, read_parquet, write_parquet
from rigtools.ingest.builder import RecordingBuilder


def _build(blocks, slow=None):
    rep = IngestReport()
    b = RecordingBuilder("mem", rep)
    for idx, vals in blocks:
        b.add_samples("acc", "m/s^2", 1000.0, np.asarray(idx), np.asarray(vals, float),
                      stamp_index=np.asarray(idx), stamps_s=10.0 + np.asarray(idx) / 1000.0)
    for name, (t, v) in (slow or {}).items():
        b.add_slow(name, "rpm", np.asarray(t, float), np.asarray(v, float))
    prov = Provenance("mem", "0" * 64, 0, "test", {}, rep)
    return b.build(RunMetadata(run_id="r1", conditions={"torque_Nm": 302.0}), prov), rep


def test_gap_is_nan_and_invalid_never_interpolated():
    rec, rep = _build([([0, 1, 2], [1.0, 2.0, 3.0]), ([6, 7], [7.0, 8.0])])
    ch = rec.channels["acc"]
    assert ch.first_index == 0 and len(ch) == 8
    assert ch.valid.tolist() == [True] * 3 + [False] * 3 + [True] * 2
    assert np.isnan(ch.values[3:6]).all()
    assert ch.values[[0, 1, 2, 6, 7]].tolist() == [1, 2, 3, 7, 8]
    assert [(g.start_index, g.n_missing) for g in rep.gaps] == [(3, 3)]
    assert ch.start_time_s == pytest.approx(10.0)


def test_duplicates_counted_and_out_of_order_blocks_sorted():
    rec, rep = _build([([5, 6], [5.0, 6.0]), ([0, 1, 2, 3, 4], [0.0, 1, 2, 3, 4]), ([6], [9.0])])
    ch = rec.channels["acc"]
    assert ch.values.tolist() == [0, 1, 2, 3, 4, 5, 6]
    assert rep.rejected["duplicate_sample"] == 1
    assert any("out of order" in w for w in rep.warnings)


def test_non_finite_samples_kept_but_marked_invalid_and_counted():
    rec, rep = _build([([0, 1, 2, 3], [1.0, np.nan, np.inf, -np.inf])])
    ch = rec.channels["acc"]
    assert ch.valid.tolist() == [True, False, False, False]
    assert np.isinf(ch.values[2]) and np.isinf(ch.values[3])
    assert rep.rejected["non_finite_sample"] == 3


def test_absurd_counter_keeps_the_intact_run_without_allocating_the_span():
    import tracemalloc

    tracemalloc.start()
    rec, rep = _build([([0, 1, 2], [0.0, 1.0, 2.0]), ([2**40], [3.0]), ([3], [3.0])])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 50e6
    assert rec.channels["acc"].values.tolist() == [0.0, 1.0, 2.0, 3.0]
    assert rep.rejected["implausible_sample_index"] == 1


def test_non_finite_slow_points_are_counted_or_reported():
    rec, rep = _build([([0], [0.0])], slow={"t": ([1.0, np.nan, 2.0], [1.0, 2.0, np.inf])})
    assert rec.slow["t"].time_s.tolist() == [1.0, 2.0]
    assert rep.rejected["non_finite_timestamp"] == 1
    assert any("non-finite value" in w for w in rep.warnings)


def test_slow_signal_sorted_when_stamps_go_backwards_nothing_dropped():
    rec, rep = _build([([0], [0.0])], slow={"speed": ([1.0, 3.0, 2.0], [10.0, 30.0, 20.0])})
    s = rec.slow["speed"]
    assert s.time_s.tolist() == [1.0, 2.0, 3.0] and s.values.tolist() == [10, 20, 30]
    assert any("backwards" in w for w in rep.warnings)


def test_parquet_round_trip_is_exact(tmp_path):
    rec, _ = _build(
        [([3, 4, 5], [1.0, np.inf, -0.0]), ([9], [np.nan])],
        slow={"speed": ([1.0, 2.0], [1500.0, 1500.25]), "torque": ([1.5], [302.0])},
    )
    out = write_parquet(rec, tmp_path / "r.parquet")
    back = read_parquet(out)
    assert back.equals(rec)
    # read() dispatches .parquet by content, even under a lying suffix.
    lying = tmp_path / "r.blf"
    lying.write_bytes(out.read_bytes())
    assert read(lying).equals(rec)


def test_parquet_without_rigtools_metadata_is_refused(tmp_path):
    import pyarrow as pa

    p = tmp_path / "plain.parquet"
    pq.write_table(pa.table({"x": [1.0, 2.0]}), p)
    with pytest.raises(RecordingFormatError, match=r"without 'rigtools\.recording' metadata"):
        read_parquet(p)


def test_parquet_with_metadata_claiming_more_samples_than_stored_is_refused(tmp_path):
    rec, _ = _build([([0, 1, 2], [1.0, 2.0, 3.0])])
    p = write_parquet(rec, tmp_path / "r.parquet")
    table = pq.read_table(p)
    doc = json.loads(table.schema.metadata[b"rigtools.recording"])
    doc["channels"][0]["n_samples"] = 10
    text = json.dumps(doc).encode()
    forged = table.replace_schema_metadata({b"rigtools.recording": text})
    pq.write_table(forged, tmp_path / "forged.parquet")
    with pytest.raises(RecordingFormatError, match="expected the SHA-256 stored beside it"):
        read_parquet(tmp_path / "forged.parquet")
    digest = hashlib.sha256(text).hexdigest().encode()
    bad = table.replace_schema_metadata({b"rigtools.recording": text,
                                         b"rigtools.recording.sha256": digest})
    pq.write_table(bad, tmp_path / "bad.parquet")
    with pytest.raises(RecordingFormatError, match="at least 10 rows"):
        read_parquet(tmp_path / "bad.parquet")


def test_rows_of_raw_ints_with_partial_overlap_and_conversion_stages():
    rep = IngestReport()
    b = RecordingBuilder("mem", rep)
    raw = np.array([[1, 2, 3], [4, 5, 6]], np.int16)
    b.add_samples("acc", "m/s^2", 300.0, np.array([0, 3]), raw, conversion=((0.5, 0.0),))
    # A late block overlapping the last two samples already received, then running on.
    b.add_samples("acc", "m/s^2", 300.0, np.array([4]), np.array([[50, 60, 7]], np.int16),
                  conversion=((0.5, 0.0),))
    b.add_samples("acc", "m/s^2", 300.0, 10, np.array([8.0, 9.0]))
    rec = b.build(RunMetadata(), Provenance("mem", "0" * 64, 0, "t", {}, rep))
    ch = rec.channels["acc"]
    # First received wins; only the new sample of the late block is used.
    assert ch.values[:7].tolist() == [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5]
    assert ch.valid.tolist() == [True] * 7 + [False] * 3 + [True] * 2
    assert rep.rejected["duplicate_sample"] == 2
    assert [(g.start_index, g.n_missing) for g in rep.gaps] == [(7, 3)]


def test_channel_names_that_look_like_column_suffixes_round_trip(tmp_path):
    rep = IngestReport()
    b = RecordingBuilder("mem", rep)
    b.add_samples("a", "m/s^2", 10.0, 0, np.array([1.0, 2.0]))
    b.add_samples("a/valid", "m/s^2", 10.0, 0, np.array([3.0]))
    b.add_slow("a/values", "rpm", np.array([0.0]), np.array([5.0]))
    rec = b.build(RunMetadata(), Provenance("mem", "0" * 64, 0, "t", {}, rep))
    assert read_parquet(write_parquet(rec, tmp_path / "r.parquet")).equals(rec)


def test_flipped_bits_in_a_normalized_recording_never_read_back_as_other_values(tmp_path):
    rng = np.random.default_rng(5)
    rec, _ = _build([(np.arange(5000), rng.normal(size=5000))])
    good = write_parquet(rec, tmp_path / "good.parquet").read_bytes()
    bad = tmp_path / "bad.parquet"
    silent = 0
    for pos in rng.choice(len(good), 400, replace=False):
        data = bytearray(good)
        data[pos] ^= 1 << int(rng.integers(8))
        bad.write_bytes(bytes(data))
        try:
            back = read_parquet(bad)
        except RecordingFormatError:
            continue
        silent += not back.equals(rec)
    assert silent == 0
