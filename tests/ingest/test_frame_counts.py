"""Counts a user can read (issue 17, must-holds 4 and 7): frames and samples kept apart.

A logger that sends one CAN frame per sample time with a frame counter and three axes (the
issue's case: an IMU-like DBC without rigtools' attributes) is written here as a candump log,
with 37 frames lost in 31 runs and 2 frames logged twice:

* through a mapping, one message feeds three channels: a duplicated frame is one
  ``duplicate_frame`` (not three), and the 31 runs of lost frames are 31 gaps of 37 frames,
  as well as 93 gaps of 111 samples over the three channels, each named as such;
* without a mapping, the DBC reads every signal as a slow signal: the reader says that the
  message arrives at 25.6 kHz, that its counter skipped 37 frames, and how to write the mapping
  (``--map``, ``data_schemas/channel_mapping.schema.json``); ``info`` does not say ``gaps
  none`` and ``spectrum`` says what it found instead of a bare "no uniform channel".
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from imu_can_layout import imu_dbc, imu_mapping

from rigtools.cli import EXIT_UNUSABLE, main
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_imu_mcap
from rigtools.ingest import loss_tally, read, read_parquet, write_parquet

FS = 25_600.0
N_FRAMES = 8000
T0 = 1_700_000_000.0
CHANNELS = tuple(f"/imu/linear_acceleration.{a}" for a in "xyz")
DBC = imu_dbc(frame_id=512, message="IMU_ACCEL", counter="Seq", slow_message="RIG_STATE",
              slow_bytes=8, slow_signals=(
                  ' SG_ Speed_rpm : 0|16@1+ (0.25,0) [0|16383.75] "rpm" Logger',
                  ' SG_ Torque_Nm : 16|16@1- (0.05,0) [-1638.4|1638.35] "N.m" Logger'))
MAPPING = imu_mapping(dict(zip("XYZ", CHANNELS, strict=True)), message="IMU_ACCEL", counter="Seq",
                      slow=[("PinionSpeed_rpm", "RIG_STATE", "Speed_rpm")])


def _lost_frames() -> np.ndarray:
    """31 runs of lost frames, 25 of one frame and 6 of two: 37 frames."""
    starts = np.linspace(200, N_FRAMES - 200, 31).astype(int)
    lengths = [2] * 6 + [1] * 25
    return np.concatenate([np.arange(s, s + n) for s, n in zip(starts, lengths, strict=True)])


@pytest.fixture(scope="module")
def imu_log(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("imu_can")
    rng = np.random.default_rng(17)
    t = np.arange(N_FRAMES) / FS
    axes = np.stack([2 * np.sin(2 * np.pi * 2843.0 * t), rng.normal(0, 0.5, N_FRAMES),
                     9.81 + rng.normal(0, 0.5, N_FRAMES)], axis=1)
    keep = np.ones(N_FRAMES, bool)
    keep[_lost_frames()] = False
    kept = np.flatnonzero(keep)
    order = np.sort(np.r_[kept, kept[[500, 3000]]])  # two frames logged twice
    raw = np.round(axes / 0.01).astype(np.int64) & 0xFFFF
    lines = []
    for i in order:
        words = [int(i) & 0xFFFF, *(int(v) for v in raw[i])]
        data = b"".join(w.to_bytes(2, "little") for w in words)
        lines.append((T0 + i / FS + 1e-4, f"can0 200#{data.hex().upper()}"))
    state = (6000).to_bytes(2, "little") + (6000).to_bytes(2, "little") + bytes(4)
    lines += [(T0 + k * 0.1, f"can0 300#{state.hex().upper()}") for k in range(3)]
    lines.sort()
    (d / "imu.log").write_text("".join(f"({ts:.6f}) {body}\n" for ts, body in lines))
    (d / "imu.dbc").write_text(DBC)
    (d / "imu.toml").write_text(MAPPING)
    return {"log": d / "imu.log", "dbc": d / "imu.dbc", "map": d / "imu.toml", "dir": d}


def test_a_duplicated_frame_that_feeds_three_channels_is_one_frame(imu_log):
    rec = read(imu_log["log"], dbc=imu_log["dbc"], mapping=imu_log["map"])
    assert sorted(rec.channels) == sorted(CHANNELS)
    rep = rec.report
    assert rep.rejected == {"duplicate_frame": 2}  # was 6: once per channel fed
    assert rep.first_position["duplicate_frame"] == "message 'IMU_ACCEL'"
    # a frame is decoded or rejected, not both: every frame of the log is counted once
    n_lines = len(imu_log["log"].read_text().splitlines())
    assert rep.decoded + rep.n_rejected_frames == n_lines
    assert rep.n_rejected_samples == 0


def test_lost_frames_are_counted_once_in_frames_and_per_channel_in_samples(imu_log, tmp_path):
    rec = read(imu_log["log"], dbc=imu_log["dbc"], mapping=imu_log["map"])
    assert len(rec.report.gaps) == 93  # one per channel and run: samples, per channel
    tally = loss_tally(rec)
    assert tally.units == "frames"
    assert (len(tally.frame_gaps), tally.n_frames_lost) == (31, 37)
    assert (tally.n_sample_gaps, tally.n_samples_missing) == (93, 111)
    assert tally.by_source == {"message 'IMU_ACCEL'": (31, 37)}
    assert tally.by_channel == {c: (31, 37) for c in CHANNELS}
    assert all(fg.channels == CHANNELS for fg in tally.frame_gaps)
    assert [fg.first_frame for fg in tally.frame_gaps[:2]] == _lost_frames()[[0, 2]].tolist()
    assert tally.uncounted == ()
    # the carriers travel with the recording: a Parquet copy counts the same
    back = read_parquet(write_parquet(rec, tmp_path / "imu.parquet"))
    assert back.equals(rec)
    assert loss_tally(back) == tally


def test_frames_of_three_samples_lose_three_samples_each(tmp_path):
    """The reference layout: one channel per message, three samples per frame."""
    chans = [np.zeros(3 * 2000) + k for k in range(4)]
    frames = encode_reference_frames(chans, {"Torque_Nm": 302.0}, rng=2)
    keep = np.ones(len(frames), bool)
    keep[np.flatnonzero(frames.arbitration_id == 256)[100:110]] = False
    rec = read(write_can_log(tmp_path / "run.blf", frames.take(keep), "blf"))
    tally = loss_tally(rec)
    assert (len(tally.frame_gaps), tally.n_frames_lost) == (1, 10)
    assert (tally.n_sample_gaps, tally.n_samples_missing) == (1, 30)
    assert tally.by_source == {"message 'ACC1'": (1, 10)}


def test_lost_imu_messages_are_counted_once_in_messages(tmp_path):
    """MCAP Imu: one message carries one sample of each axis."""
    n = 800
    rng = np.random.default_rng(3)
    stamps = T0 + np.arange(n) / 400.0
    keep = np.setdiff1d(np.arange(n), [*range(100, 110), 500])
    p = write_imu_mcap(tmp_path / "imu.mcap", stamps[keep], rng.standard_normal((n, 3))[keep])
    tally = loss_tally(read(p))
    assert tally.units == "messages"
    assert (len(tally.frame_gaps), tally.n_frames_lost) == (2, 11)
    assert (tally.n_sample_gaps, tally.n_samples_missing) == (6, 33)
    assert tally.by_source == {"topic '/imu'": (2, 11)}


def test_info_and_warnings_name_frames_and_samples_apart(imu_log, capsys):
    argv = ["info", str(imu_log["log"]), "--dbc", str(imu_log["dbc"]), "--map",
            str(imu_log["map"])]
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "rejected           2  frames   duplicate_frame" in cap.out
    assert "lost      37 frames in 31 gap(s)" in cap.out
    assert "message 'IMU_ACCEL': 37 frames lost in 31 gap(s), each a gap in 3 channels" in cap.out
    assert "missing   111 samples in 93 gap(s) over 3 channels" in cap.out
    assert f"{CHANNELS[0]}: 37 sample(s) in 31 gap(s)" in cap.out
    warnings = cap.err.splitlines()
    assert "rigtools: warning: 2 frames rejected: duplicate_frame (first at message " \
           "'IMU_ACCEL')" in warnings
    assert "rigtools: warning: 37 frames lost in 31 gap(s) (message 'IMU_ACCEL': 37 in 31, " \
           "feeding 3 channels)" in warnings
    assert "rigtools: warning: 93 gap(s) in sample counters, 111 sample(s) missing over 3 " \
           "channels" in warnings
    assert not any("6 frames" in w for w in warnings)
    # the channel table keeps the unit apart from a long channel name
    row = next(ln for ln in cap.out.splitlines() if ln.startswith(CHANNELS[0]))
    assert row.split()[:3] == [CHANNELS[0], "m/s^2", "25600"]
    assert main([*argv[:1], "--json", *argv[1:]]) == 0
    losses = json.loads(capsys.readouterr().out)["losses"]
    assert (losses["frame_gaps"], losses["frames_lost"]) == (31, 37)
    assert (losses["sample_gaps"], losses["samples_missing"]) == (93, 111)
    assert losses["by_source"] == {"message 'IMU_ACCEL'": {"frame_gaps": 31, "frames_lost": 37}}
    assert (losses["rejected_frames"], losses["rejected_samples"]) == (2, 0)


def test_a_dbc_without_rigtools_attributes_says_what_it_found(imu_log, capsys):
    rec = read(imu_log["log"], dbc=imu_log["dbc"])
    assert not rec.channels and {"AccX", "AccY", "AccZ", "Seq"} <= set(rec.slow)
    (hint,) = [w for w in rec.report.warnings if "IMU_ACCEL" in w]
    for fragment in ("message 'IMU_ACCEL' arrives at about 25.6 kHz",
                     "read as slow signals, so no gap in it is counted",
                     "its signal 'Seq' counts frames and skips 37 frame(s) in 31 gap(s)",
                     "marks no message as a uniform channel", "[[uniform]]",
                     "data_schemas/channel_mapping.schema.json", "--map"):
        assert fragment in hint, fragment
    assert not any("RIG_STATE" in w for w in rec.report.warnings)  # 10 Hz: a slow message

    assert main(["info", str(imu_log["log"]), "--dbc", str(imu_log["dbc"])]) == 0
    cap = capsys.readouterr()
    assert "gaps      none" not in cap.out
    assert "gaps      not counted: no uniform channel" in cap.out
    assert "counts frames and skips 37 frame(s)" in cap.err
    row = next(ln for ln in cap.out.splitlines() if ln.startswith("AccX"))
    assert float(row.split()[3]) == pytest.approx(FS, rel=1e-3)  # the rate column

    assert main(["spectrum", str(imu_log["log"]), "--dbc", str(imu_log["dbc"])]) \
        == EXIT_UNUSABLE
    err = capsys.readouterr().err
    (line,) = [ln for ln in err.splitlines() if ln.startswith("rigtools: error: ")]
    for fragment in ("no uniform channel, only 6 slow signal(s)",
                     "4 arrive at up to 25.6 kHz as sampled data does (AccX, AccY, AccZ, Seq)",
                     "imu.dbc marks no message as a uniform channel",
                     "data_schemas/channel_mapping.schema.json", "--map"):
        assert fragment in line, fragment


def test_a_mapping_silences_the_hint(imu_log):
    rec = read(imu_log["log"], dbc=imu_log["dbc"], mapping=imu_log["map"])
    assert not any("arrives at about" in w for w in rec.report.warnings)
