"""The demo's second CAN layout: frames packed here decode with cantools and with rigtools."""

from __future__ import annotations

from pathlib import Path

import cantools
import numpy as np
import pytest

from rigtools.demo.can_writer import write_can_log
from rigtools.demo.triax_can import (
    ACCEL_CHANNELS,
    encode_triax_frames,
    write_triax_layout,
)
from rigtools.ingest import read


@pytest.fixture
def layout(tmp_path: Path) -> tuple[Path, Path]:
    return write_triax_layout(tmp_path)


def _samples(n: int) -> np.ndarray:
    rng = np.random.default_rng(5)
    return np.round(rng.normal(0.0, 20.0, (n, 3)) / 0.01) * 0.01


def test_frames_decode_with_cantools(layout) -> None:
    dbc, _mapping = layout
    acc = _samples(70_000)  # the 16-bit counter wraps
    slow = {"PinionSpeed_rpm": 1500.0, "Torque_Nm": -12.34, "BulkTemp_C": 55.5,
            "OilTemp_C": 41.82}
    batch = encode_triax_frames(acc, slow, dbc=dbc, start_time_s=1.7e9)
    db = cantools.database.load_file(str(dbc))
    triax = db.get_message_by_name("TRIAX")
    rows = np.flatnonzero(batch.is_extended)
    assert rows.size == acc.shape[0]
    assert np.all(np.diff(batch.timestamp_s) >= 0)
    for j in (0, 1, 65_535, 65_536, 69_999):
        assert int(batch.arbitration_id[rows[j]]) == triax.frame_id == 0x0CFF1021
        msg = triax.decode(bytes(batch.data[rows[j]]))
        assert msg["SeqCnt"] == j % 65_536
        assert [msg["AccX"], msg["AccY"], msg["AccZ"]] == pytest.approx(acc[j], abs=1e-9)
    state = int(np.flatnonzero(batch.arbitration_id == 0x300)[0])
    got = db.decode_message(0x300, bytes(batch.data[state]))
    assert got["SpeedPinion"] == pytest.approx(1500.0) and got["TorqueShaft"] == pytest.approx(
        -12.34)


def test_rigtools_reads_the_layout_through_the_mapping_with_gaps(layout, tmp_path) -> None:
    dbc, mapping = layout
    acc = _samples(12_800)
    batch = encode_triax_frames(acc, {"Torque_Nm": 302.0}, dbc=dbc, start_time_s=1.7e9,
                                drop_frames=[500, 501, 9_000])
    for fmt in ("blf", "log"):
        path = write_can_log(tmp_path / f"run.{fmt}", batch, fmt, engine="rigtools")
        rec = read(path, dbc=dbc, mapping=mapping)
        assert tuple(rec.channels) == ACCEL_CHANNELS
        for k, name in enumerate(ACCEL_CHANNELS):
            ch = rec.channels[name]
            assert len(ch) == acc.shape[0] and int((~ch.valid).sum()) == 3
            assert np.array_equal(ch.values[ch.valid], acc[ch.valid, k])
        assert sorted((g.start_index, g.n_missing) for g in rec.report.gaps
                      if g.channel == "accel_x") == [(500, 2), (9_000, 1)]
        assert rec.slow["Torque_Nm"].unit == "N.m"


def test_bad_input_is_refused(layout) -> None:
    dbc, _mapping = layout
    with pytest.raises(ValueError, match=r"must have shape \(n, 3\)"):
        encode_triax_frames(np.zeros((4, 2)), dbc=dbc, start_time_s=0.0)
    with pytest.raises(ValueError, match="`drop_frames` must lie in"):
        encode_triax_frames(np.zeros((4, 3)), dbc=dbc, start_time_s=0.0, drop_frames=[4])
    with pytest.raises(ValueError, match="not one of"):
        encode_triax_frames(np.zeros((4, 3)), {"Speed": 1.0}, dbc=dbc, start_time_s=0.0)
