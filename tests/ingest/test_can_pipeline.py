"""End to end: a synthetic reference-layout recording, written in every CAN log format, read back.

samples -> ``encode_reference_frames`` -> python-can's (or rigtools') writers -> ``rigtools.ingest
.read`` -> channels equal to the int16-quantised input exactly, slow signals right, and every
frame that did not make it accounted for (gaps, duplicates, counter wraps, ids absent from the
DBC, short payloads, error and remote frames).
"""

from __future__ import annotations

from pathlib import Path

import can
import numpy as np
import pytest

from rigtools.demo.can_writer import (
    encode_reference_frames,
    quantise_reference,
    write_can_log,
)
from rigtools.ingest import read
from rigtools.ingest.can.frames import CanFrameBatch, concat

FS = 25_600.0
N_FRAMES = 3000  # per channel: 9000 samples, 0.35 s
FIRST_COUNTER = 65_000  # the 16-bit counter wraps after 536 frames
START = 1_700_000_000.0
LATENCY = 250e-6
SPEED = np.array([1500.0, 1500.25, 1501.0, 1502.5])  # one per slow frame (10 Hz, 4 frames)

@pytest.fixture(scope="module")
def source():
    rng = np.random.default_rng(42)
    t = np.arange(3 * N_FRAMES) / FS
    chans = [40 * np.sin(2 * np.pi * (400 * (i + 1)) * t) + rng.normal(0, 5, t.size)
             for i in range(4)]
    chans[3][:10] = [1e6, -1e6, 491.6, -491.6, 0.0075, -0.0075, 0.0225, 0, 0, 0]  # clip, ties
    slow = {"Torque_Nm": 302.0, "PinionSpeed_rpm": SPEED, "OilTemp_C": 90.5}
    frames = encode_reference_frames(chans, slow, start_time_s=START, latency_s=LATENCY,
                                     first_counter=FIRST_COUNTER, rng=7)
    return chans, frames, quantise_reference(chans)


def _check_channels(rec, want: dict[str, np.ndarray]) -> None:
    assert sorted(rec.channels) == sorted(want)
    for name, values in want.items():
        ch = rec.channels[name]
        assert ch.first_index == 3 * FIRST_COUNTER
        assert ch.sample_rate_Hz == FS
        assert ch.valid.all()
        np.testing.assert_array_equal(ch.values, values, err_msg=name)


@pytest.mark.parametrize(
    ("fmt", "engine"),
    [("blf", "python-can"), ("blf", "rigtools"), ("log", "python-can"), ("log", "rigtools"),
     ("asc", "python-can"), ("trc", "python-can"), ("csv", "python-can")],
)
def test_every_format_reads_back_the_quantised_input_exactly(tmp_path, source, fmt, engine):
    _, frames, want = source
    path = write_can_log(tmp_path / f"run.{fmt}", frames, fmt, engine=engine)
    rec = read(path)
    _check_channels(rec, want)
    assert rec.report.n_rejected == 0 and rec.report.gaps == []
    assert rec.report.decoded == len(frames)
    np.testing.assert_array_equal(rec.slow["PinionSpeed_rpm"].values, SPEED)
    np.testing.assert_array_equal(rec.slow["Torque_Nm"].values, [302.0] * 4)
    np.testing.assert_array_equal(rec.slow["OilTemp_C"].values, [90.5] * 4)
    assert rec.slow["Torque_Nm"].unit == "N.m"
    # slow frames every 0.1 s (jitter below 20 µs, format resolution 1 µs or better), at
    # absolute times in every format; ASCWriter's start (its trigger-block date) is the first
    # frame's time truncated to the millisecond, so ASC times may be up to 1 ms early
    t = rec.slow["PinionSpeed_rpm"].time_s
    np.testing.assert_allclose(np.diff(t), 0.1, atol=30e-6)
    early = 1e-3 if fmt == "asc" else 0.0
    assert -early - 30e-6 < t[0] - (START + LATENCY) < 30e-6
    assert rec.provenance.reader == ("candump" if fmt == "log" else fmt)


def _shifted(frames: CanFrameBatch, shift_s: float) -> CanFrameBatch:
    return CanFrameBatch(frames.timestamp_s + shift_s, frames.arbitration_id, frames.is_extended,
                         frames.is_fd, frames.length, frames.data, frames.channel,
                         frames.position, frames.position_unit)


@pytest.mark.parametrize("start", ["as-encoded", "sub-ms", "ms-aligned"])
def test_asc_and_blf_of_the_same_frames_agree_in_absolute_time(tmp_path, source, start):
    """python-can's ASCWriter and BLFWriter, the same frames, read through ``read``.

    ASC text precision: the start (``Begin Triggerblock`` date) has milliseconds, which
    ASCWriter truncates from the first frame's time, and each line's offset from the first
    frame 6 decimals (1 µs). BLFWriter stores the start truncated to the millisecond too but
    offsets from it in ns, so BLF times are the frames' own. Hence ASC times are BLF times
    minus one constant ``delta`` = the first frame's time past its millisecond, in [0, 1 ms),
    each within 0.5 µs; channel start times (median of stamp - index / fs) and slow-signal
    times alike. With a first frame on a millisecond they agree within 1 µs.
    """
    _, frames, want = source
    t_first = float(frames.timestamp_s[0])  # START + 0.257 ms
    past_ms = (t_first - START) % 1e-3  # START is a whole second
    shift = {"as-encoded": 0.0, "sub-ms": 0.1234567, "ms-aligned": -past_ms}[start]
    # (not 1..99 ms past the second: python-can's ASCWriter writes those milliseconds
    # without leading zeros, test_asc.py::test_ascwriter_milliseconds_without_leading_zeros)
    frames = _shifted(frames, shift)
    t_first = float(frames.timestamp_s[0])
    delta = (t_first - START) % 1e-3
    assert (start == "ms-aligned") == (delta < 1e-6 or delta > 1e-3 - 1e-6)
    delta = 0.0 if start == "ms-aligned" else delta
    asc = read(write_can_log(tmp_path / "run.asc", frames, "asc", engine="python-can"))
    blf = read(write_can_log(tmp_path / "run.blf", frames, "blf", engine="python-can"))
    assert asc.report.warnings == [] and blf.report.warnings == []
    _check_channels(asc, want)
    _check_channels(blf, want)
    for name in want:
        a, b = asc.channels[name].start_time_s, blf.channels[name].start_time_s
        assert abs(b - a - delta) <= 1e-6, name
        assert -1e-6 <= b - a < 1e-3 + 1e-6, name  # the ASC text precision
    for name, sig in blf.slow.items():
        # BLF: the frames' own times (ns offsets from a millisecond start)
        nearest = np.min(np.abs(frames.timestamp_s[:, None] - sig.time_s[None, :]), axis=0)
        assert np.all(nearest <= 2 * np.spacing(START)), name
        np.testing.assert_allclose(sig.time_s - asc.slow[name].time_s, delta, rtol=0,
                                   atol=0.5e-6 + 2 * np.spacing(START), err_msg=name)
        np.testing.assert_array_equal(sig.values, asc.slow[name].values, err_msg=name)


def test_quantisation_rounds_clips_and_matches_the_dbc_scale(source):
    chans, _, want = source
    q = want["accel_4"]
    assert q[0] == 32767 * 0.015 and q[1] == -32768 * 0.015  # clipped to int16
    assert q[2] == 32767 * 0.015 and q[3] == -32768 * 0.015
    np.testing.assert_array_equal(q[4:7], [0.0, -0.0, 2 * 0.015])  # round half to even
    assert np.max(np.abs(want["accel_1"] - chans[0])) <= 0.0075 + 1e-12


def test_blf_and_candump_writers_of_rigtools_equal_python_cans_bytes(tmp_path, source):
    _, frames, _ = source
    part = frames.take(np.arange(2500))
    for fmt in ("blf", "log"):
        a = write_can_log(tmp_path / f"a.{fmt}", part, fmt, engine="python-can")
        b = write_can_log(tmp_path / f"b.{fmt}", part, fmt, engine="rigtools")
        assert a.read_bytes() == b.read_bytes(), fmt


def test_write_can_log_refuses_unknown_formats_and_engines(tmp_path, source):
    _, frames, _ = source
    with pytest.raises(ValueError, match="`fmt` must be one of"):
        write_can_log(tmp_path / "x.mf4", frames)
    with pytest.raises(ValueError, match="writes blf and log only"):
        write_can_log(tmp_path / "x.asc", frames, engine="rigtools")
    with pytest.raises(ValueError, match="`engine` must be"):
        write_can_log(tmp_path / "x.blf", frames, engine="vector")  # type: ignore[arg-type]


def test_encode_refuses_bad_input():
    with pytest.raises(ValueError, match="multiple of 3"):
        encode_reference_frames([np.zeros(10)])
    with pytest.raises(ValueError, match="must be finite"):
        encode_reference_frames([np.array([0.0, np.nan, 0.0])])
    with pytest.raises(ValueError, match="not a slow signal"):
        encode_reference_frames([np.zeros(3)], {"Nope": 1.0})
    with pytest.raises(ValueError, match="one per slow frame"):
        encode_reference_frames([np.zeros(3 * 2560)], {"Torque_Nm": np.zeros(4)})
    with pytest.raises(ValueError, match="not channels of the layout"):
        encode_reference_frames({"accel_9": np.zeros(3)})


def test_counters_wrap_and_frames_are_in_time_order(source):
    _, frames, _ = source
    acc1 = frames.take(frames.arbitration_id == 256)
    counter = acc1.data[:, 0].astype(np.int64) | (acc1.data[:, 1].astype(np.int64) << 8)
    assert counter[0] == FIRST_COUNTER and counter[536] == 0
    assert np.all(np.diff(frames.timestamp_s) >= 0)


# -- losses, read through the whole pipeline ----------------------------------------------------


def _rows(frames: CanFrameBatch, frame_id: int) -> np.ndarray:
    return np.flatnonzero(frames.arbitration_id == frame_id)


def _with_length(frames: CanFrameBatch, row: int, length: int) -> CanFrameBatch:
    lengths = frames.length.copy()
    data = frames.data.copy()
    lengths[row] = length
    data[row, length:] = 0
    return CanFrameBatch(frames.timestamp_s, frames.arbitration_id, frames.is_extended,
                         frames.is_fd, lengths, data, frames.channel, frames.position,
                         frames.position_unit)


def _sorted(batch: CanFrameBatch) -> CanFrameBatch:
    return batch.take(np.argsort(batch.timestamp_s, kind="stable"))


def _foreign(n: int, t0: float) -> CanFrameBatch:
    return CanFrameBatch(t0 + np.arange(n) * 1e-3, np.full(n, 0x700, np.uint32),
                         np.zeros(n, bool), np.zeros(n, bool), np.full(n, 8, np.uint8),
                         np.zeros((n, 8), np.uint8), np.zeros(n, np.int16),
                         np.arange(n, dtype=np.int64), "byte")


@pytest.fixture(scope="module")
def damaged(source):
    """The source frames with frames dropped, duplicated, shortened and foreign ids added."""
    _, frames, want = source
    keep = np.ones(len(frames), bool)
    acc1 = _rows(frames, 256)
    keep[acc1[100:110]] = False  # 10 frames lost: a 30-sample gap
    acc3 = _rows(frames, 258)
    keep[acc3[530:546]] = False  # 16 frames lost across the counter wrap (65530..9)
    lossy = frames.take(keep)
    acc4 = _rows(lossy, 259)
    lossy = _with_length(lossy, int(acc4[200]), 4)  # DLC shorter than the DBC's 8
    acc2 = _rows(lossy, 257)
    dup = lossy.take(acc2[50:51])  # the same frame logged twice
    lossy = _sorted(concat([lossy, dup, _foreign(5, START + 0.01)]))
    expected = {k: v.copy() for k, v in want.items()}
    missing = {"accel_1": np.arange(300, 330), "accel_3": np.arange(1590, 1638),
               "accel_4": np.arange(600, 603)}
    for name, idx in missing.items():
        expected[name][idx] = np.nan
    return lossy, expected, missing


@pytest.mark.parametrize("fmt", ["blf", "log"])
def test_gaps_duplicates_wraps_foreign_ids_and_short_frames_are_accounted(tmp_path, damaged,
                                                                         fmt):
    lossy, expected, missing = damaged
    rec = read(write_can_log(tmp_path / f"lossy.{fmt}", lossy, fmt))
    for name, values in expected.items():
        ch = rec.channels[name]
        assert ch.first_index == 3 * FIRST_COUNTER and len(ch) == 3 * N_FRAMES
        np.testing.assert_array_equal(ch.values, values, err_msg=name)
        invalid = np.flatnonzero(~ch.valid)
        np.testing.assert_array_equal(invalid, missing.get(name, []), err_msg=name)
    gaps = {(g.channel, g.start_index, g.n_missing) for g in rec.report.gaps}
    first = 3 * FIRST_COUNTER
    assert gaps == {("accel_1", first + 300, 30), ("accel_3", first + 1590, 48),
                    ("accel_4", first + 600, 3)}
    assert rec.report.rejected == {"id_not_in_dbc": 5, "dlc_shorter_than_dbc": 1,
                                   "duplicate_frame": 1}
    where = rec.report.first_position["id_not_in_dbc"]
    assert where.startswith("byte " if fmt == "blf" else "line ")


def test_error_and_remote_frames_are_counted_through_read(tmp_path, source):
    _, frames, want = source
    part = frames
    msgs = []
    for i in range(len(part)):
        n = int(part.length[i])
        msgs.append(can.Message(timestamp=float(part.timestamp_s[i]),
                                arbitration_id=int(part.arbitration_id[i]),
                                is_extended_id=False, data=bytes(part.data[i, :n]), channel=0))
        if i % 1000 == 7:
            msgs.append(can.Message(timestamp=float(part.timestamp_s[i]), is_error_frame=True,
                                    channel=0))
        if i % 1000 == 9:
            msgs.append(can.Message(timestamp=float(part.timestamp_s[i]), arbitration_id=256,
                                    is_extended_id=False, is_remote_frame=True, dlc=8,
                                    channel=0))
    for fmt, writer in (("blf", can.BLFWriter), ("log", can.CanutilsLogWriter)):
        path = Path(tmp_path / f"errors.{fmt}")
        with writer(str(path)) as w:
            for m in msgs:
                w.on_message_received(m)
        rec = read(path)
        n_err = sum(1 for i in range(len(part)) if i % 1000 == 7)
        n_rtr = sum(1 for i in range(len(part)) if i % 1000 == 9)
        assert rec.report.rejected == {"error_frame": n_err, "remote_frame": n_rtr}, fmt
        _check_channels(rec, want)


def test_truncated_blf_reads_the_intact_prefix_through_read(tmp_path, source):
    _, frames, want = source
    path = write_can_log(tmp_path / "run.blf", frames, "blf")
    raw = path.read_bytes()
    cut = tmp_path / "cut.blf"
    cut.write_bytes(raw[: len(raw) * 2 // 3])
    rec = read(cut)
    lost = {"truncated_container", "truncated_object"} & set(rec.report.rejected)
    assert lost
    for name, values in want.items():
        ch = rec.channels[name]
        assert 0 < len(ch) < values.size
        np.testing.assert_array_equal(ch.values, values[: len(ch)])


@pytest.mark.parametrize("fmt", ["blf", "log"])
def test_gzipped_logs_read_like_the_plain_ones(tmp_path, source, fmt):
    import gzip

    _, frames, want = source
    path = write_can_log(tmp_path / f"run.{fmt}", frames, fmt, engine="rigtools")
    gz = tmp_path / f"run.{fmt}.gz"
    gz.write_bytes(gzip.compress(path.read_bytes()))
    plain, packed = read(path), read(gz)
    _check_channels(packed, want)
    for name in want:
        assert packed.channels[name].equals(plain.channels[name])
    assert packed.report.to_dict() == plain.report.to_dict()


def test_content_decides_the_reader_whatever_the_suffix(tmp_path, source):
    from rigtools.ingest.registry import detect_format

    _, frames, want = source
    part = frames.take(np.arange(600))
    blf_named_log = write_can_log(tmp_path / "x.blf", part, "blf").rename(tmp_path / "blf.log")
    log_named_txt = write_can_log(tmp_path / "x.log", part, "log").rename(tmp_path / "dump.txt")
    assert detect_format(blf_named_log) == "blf"
    assert detect_format(log_named_txt) == "candump"
    for fmt in ("asc", "trc", "csv"):
        other = write_can_log(tmp_path / f"x.{fmt}", part, fmt).rename(tmp_path / f"{fmt}.dat")
        assert detect_format(other) == fmt
    rec = read(log_named_txt)
    assert rec.provenance.reader == "candump"
    np.testing.assert_array_equal(rec.channels["accel_1"].values,
                                  want["accel_1"][: len(rec.channels["accel_1"])])


def test_restart_with_a_logger_clock_step_back_keeps_both_runs(tmp_path):
    """A sensor restart (counter back to 0) at the moment the logger clock steps back 1 ms.

    Review of issue 12 (r5, defect 4): the clock going back with the counter was taken for a
    replayed block, and the 100 frames after the restart were dropped as duplicates. Their
    payloads differ from the frames first received at those counter values, so it is a
    restart: every frame is kept, the second run right after the first (the resynchronised
    step is the usual one, as the clock cannot say more), and the restart is reported.
    """
    rng = np.random.default_rng(8)
    n = 3 * 100  # samples per channel and run
    runs = [[rng.normal(0, 30, n) for _ in range(4)] for _ in range(2)]
    first = encode_reference_frames(runs[0], {}, start_time_s=START, first_counter=0, rng=1)
    t_next = float(first.timestamp_s.max()) + 3 / FS - 1e-3  # the clock steps back 1 ms
    second = encode_reference_frames(runs[1], {}, start_time_s=t_next, first_counter=0, rng=2)
    frames = concat([first, second])
    rec = read(write_can_log(tmp_path / "restart.log", frames, "log"))
    assert rec.report.rejected["duplicate_frame"] == 0, rec.report.to_dict()
    assert any("restarted" in w for w in rec.report.warnings)
    want = [quantise_reference(r) for r in runs]
    for name in want[0]:
        ch = rec.channels[name]
        assert ch.valid.all()
        np.testing.assert_array_equal(
            ch.values, np.concatenate([want[0][name], want[1][name]]), err_msg=name
        )
