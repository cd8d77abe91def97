"""candump -L reader: frame for frame against python-can's CanutilsLogReader, garbage counted.

Logs are written in code, by python-can's ``CanutilsLogWriter`` or by hand for the layouts it
never writes (no suffix, CRLF, tabs, lower-case hex, remote DLC, garbage).
"""

from __future__ import annotations

import io
import tempfile
from pathlib import Path

import can
import numpy as np
import pytest
from can.util import channel2int
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can import candump
from rigtools.ingest.can.frames import CanFrameBatch, concat
from rigtools.ingest.recording import IngestReport

FD_LENGTHS = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64]


def read_log(text: str | bytes, **kwargs) -> tuple[CanFrameBatch, IngestReport]:
    raw = text.encode() if isinstance(text, str) else text
    report = IngestReport()
    batches = list(candump.iter_batches(io.BytesIO(raw), "test.log", report, **kwargs))
    for b in batches:
        assert b.position_unit == "line"
    return (concat(batches) if batches else CanFrameBatch.empty()), report


def pycan_messages(text: str) -> list[can.Message]:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "f.log"
        p.write_bytes(text.encode())
        return list(can.CanutilsLogReader(str(p)))


def assert_same_frames(batch: CanFrameBatch, msgs: list[can.Message]) -> None:
    """Same frames as python-can (channel as python-can's channel2int of the interface)."""
    msgs = [m for m in msgs if not m.is_error_frame and not m.is_remote_frame]
    assert len(batch) == len(msgs)
    if not msgs:
        return
    ts = np.array([m.timestamp for m in msgs], np.float64)
    assert np.array_equal(batch.timestamp_s.view(np.uint64), ts.view(np.uint64))
    assert batch.arbitration_id.tolist() == [m.arbitration_id for m in msgs]
    assert batch.is_extended.tolist() == [m.is_extended_id for m in msgs]
    assert batch.is_fd.tolist() == [m.is_fd for m in msgs]
    assert batch.length.tolist() == [len(m.data) for m in msgs]
    assert [bytes(batch.data[i, : batch.length[i]]) for i in range(len(batch))] == [
        bytes(m.data) for m in msgs]
    assert not np.any(batch.data[np.arange(batch.data.shape[1]) >= batch.length[:, None]])
    want = [channel2int(m.channel) if m.channel is not None else -1 for m in msgs]
    assert batch.channel.tolist() == [-1 if c is None else c for c in want]


def _write_python_can(msgs: list[can.Message]) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "f.log"
        with can.CanutilsLogWriter(str(p)) as w:
            for m in msgs:
                w.on_message_received(m)
        return p.read_text()


def _mixed_messages(n: int, seed: int) -> list[can.Message]:
    rng = np.random.default_rng(seed)
    t = float(rng.uniform(0, 2e9))
    out = []
    for i in range(n):
        t += float(rng.uniform(0, 0.01))
        ext = bool(rng.integers(0, 2))
        cid = int(rng.integers(0, 1 << 29 if ext else 1 << 11))
        ch = ["can0", "can1", "vcan7", 3, None][int(rng.integers(0, 5))]
        kind = int(rng.integers(0, 10))
        if kind == 0:
            out.append(can.Message(timestamp=t, is_error_frame=True, channel=ch))
        elif kind == 1:
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   is_remote_frame=True, channel=ch))
        elif kind < 4:
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   is_fd=True, bitrate_switch=bool(i % 2),
                                   error_state_indicator=bool(i % 3 == 0),
                                   data=rng.integers(0, 256, int(rng.choice(FD_LENGTHS)),
                                                     dtype=np.uint8).tobytes(), channel=ch))
        else:
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   data=rng.integers(0, 256, int(rng.integers(0, 9)),
                                                     dtype=np.uint8).tobytes(),
                                   channel=ch, is_rx=bool(i % 2)))
    return out


# -- detection -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "head",
    [
        b"(1700000000.123456) can0 123#DEADBEEF\n",
        b"\n\n(0.000000) vcan0 1F334455#R\n",
        b"(1.5) can0 123##1AA R\n",
    ],
)
def test_sniff_claims_every_layout(head):
    """Other formats' content is refused by every reader in test_reader_contract.py."""
    assert candump.sniff(head) is True


def test_blank_file_is_refused():
    with pytest.raises(RecordingFormatError, match="expected a candump -L log") as info:
        read_log(b"\n\n  \n")
    assert info.value.position == "line 1"


# -- equality with python-can ---------------------------------------------------------------------


def test_python_can_written_log_matches_frame_for_frame():
    msgs = _mixed_messages(3000, 1)
    text = _write_python_can(msgs)
    batch, report = read_log(text)
    ref = pycan_messages(text)
    assert_same_frames(batch, ref)
    assert report.rejected["error_frame"] == sum(m.is_error_frame for m in ref)
    assert report.rejected["remote_frame"] == sum(m.is_remote_frame for m in ref)
    assert set(report.rejected) <= {"error_frame", "remote_frame"}
    # positions are the 1-based line numbers of the data frames
    lines = text.splitlines()
    for row in (0, len(batch) // 2, len(batch) - 1):
        line = lines[batch.position[row] - 1]
        assert f"{batch.arbitration_id[row]:03X}#" in line


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(n=st.integers(0, 60), seed=st.integers(0, 2**31), block=st.sampled_from([64, 1000, 1 << 20]))
def test_any_python_can_log_matches_python_can(n, seed, block):
    text = _write_python_can(_mixed_messages(n, seed))
    if not text:
        return
    batch, _ = read_log(text, block_bytes=block)
    assert_same_frames(batch, pycan_messages(text))


HAND_WRITTEN = """\
(1700000000.000001) can0 123#DEADBEEF
(1700000000.000002) can0 1F334455#0011223344556677 T
(1700000000.1) vcan12 7FF#
(1700000000) can0 0123#AB
   (1700000001.5)   can1\t456#cafe   \r
(1700000002.250000) can0 00000010##3AABBCCDDEEFF0011
(1700000002.25) can0 010#R
(1700000002.25) can0 010#R4 R
(1700000003.000000) can0 20000080#0000000000000000
(1700000003.000000) can0 20000004#0000000000000000
(1700000004.999999) can0 12345678#FF R\r
(0.000000) any 7#01
(12345678901234.123456789) can0 100#01
(1700000005.000000) can0 80000123#0102
"""


def test_hand_written_layouts_match_python_can():
    batch, report = read_log(HAND_WRITTEN)
    ref = [m for m in pycan_messages(HAND_WRITTEN)]
    # python-can reads the error class without CAN_ERR_BUSERROR as a data frame; rigtools
    # counts every CAN_ERR_FLAG identifier as an error frame (see the module docstring).
    ref = [m for m in ref if not (m.arbitration_id == 0x4 and m.is_extended_id)]
    assert_same_frames(batch, ref)
    assert report.rejected == {"error_frame": 2, "remote_frame": 2}
    assert report.first_position == {"error_frame": "line 9", "remote_frame": "line 7"}
    assert batch.position.tolist() == [1, 2, 3, 4, 5, 6, 11, 12, 13, 14]
    assert batch.is_extended.tolist()[:4] == [False, True, False, True]  # '0123' has 4 digits


def test_garbage_lines_are_counted_with_the_first_line_number():
    text = "\n".join([
        "(1700000000.000001) can0 123#DEADBEEF",
        "this is not a frame",
        "(1700000000.000002) can0 123#DEADBEE",  # odd number of hex digits
        "(1700000000.000003) can0 12G#00",  # bad hex in the id
        "(1700000000.000004) can0 123#00ZZ",  # bad hex in the data
        "(17000000x0.000005) can0 123#00",  # timestamp float() cannot read
        "",  # blank: skipped, as python-can skips it
        "(1700000000.000006) can0 123#" + "00" * 65,  # more than 64 bytes
        "(1700000000.000007) can0 123#R4x",  # remote with a bad DLC
        "(1700000000.000008) can0 123#0102",
        "\x00\x01\x02binary",
    ]) + "\n"
    batch, report = read_log(text)
    assert batch.position.tolist() == [1, 10]
    assert report.rejected == {"unparsable_line": 8}
    assert report.first_position["unparsable_line"] == "line 2"


def test_invalid_utf8_is_unparsable_not_fatal():
    batch, report = read_log(b"(1.0) can0 123#00\n(2.0) c\xffn0 123#00\n(3.0) can0 124#01\n")
    assert batch.arbitration_id.tolist() == [0x123, 0x124]
    assert report.rejected == {"unparsable_line": 1}


def test_over_long_line_is_counted_and_not_buffered():
    text = ("(1.0) can0 123#00\n" + "x" * (candump.MAX_LINE_BYTES * 3) + "\n"
            + "(2.0) can0 124#01\n")
    batch, report = read_log(text, block_bytes=4096)
    assert batch.arbitration_id.tolist() == [0x123, 0x124]
    assert batch.position.tolist() == [1, 3]
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position["unparsable_line"] == "line 2"


def test_error_frames_are_counted_and_left_out():
    msgs = [can.Message(timestamp=1.0 + i, arbitration_id=0x10, data=b"\x01")
            for i in range(3)]
    msgs.insert(1, can.Message(timestamp=1.5, is_error_frame=True))
    text = _write_python_can(msgs)
    batch, report = read_log(text)
    assert len(batch) == 3 and report.rejected == {"error_frame": 1}
    assert report.first_position["error_frame"] == "line 2"


def test_timestamps_going_backwards_are_kept_as_logged():
    text = "".join(f"({t}) can0 100#00\n" for t in ("10.5", "12.0", "11.0", "13.25"))
    batch, report = read_log(text)
    assert batch.timestamp_s.tolist() == [10.5, 12.0, 11.0, 13.25]
    assert report.n_rejected == 0


def test_block_boundaries_do_not_change_anything():
    text = _write_python_can(_mixed_messages(500, 9)) + "garbage\n(1.0) can0 1#00"  # no final \n
    whole, rep_whole = read_log(text)
    for block in (1, 17, 100, 4096):
        part, rep = read_log(text, block_bytes=block)
        assert part.equals(whole, compare_position=True), block
        assert rep.rejected == rep_whole.rejected
        assert rep.first_position == rep_whole.first_position
    assert rep_whole.rejected["unparsable_line"] == 1


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 10**10), st.integers(1, 9), st.integers(0, 10**9))
def test_timestamps_are_bit_identical_to_float(ip, fl, frac):
    frac_s = str(frac % 10**fl).zfill(fl)
    text = f"({ip}.{frac_s}) can0 123#00\n" * 3
    batch, _ = read_log(text)
    want = float(f"{ip}.{frac_s}")
    assert batch.timestamp_s.view(np.uint64).tolist() == [np.float64(want).view(np.uint64)] * 3


def test_wide_fd_frames_keep_64_bytes_and_classic_batches_stay_8_wide():
    fd = "(1.0) can0 123##1" + "AB" * 64 + "\n"
    batch, _ = read_log(fd)
    assert batch.data.shape == (1, 64) and batch.length.tolist() == [64] and batch.is_fd[0]
    batch, _ = read_log("(1.0) can0 123#0102\n")
    assert batch.data.shape == (1, 8)


@pytest.mark.parametrize("stamp", ["1234567890123456.5", "1.23456789012345678", "0.5",
                                   "99999999999999999.9", "1700000000.000000001"])
def test_long_timestamps_take_the_exact_path(stamp):
    text = f"({stamp}) can0 123#00\n" * 2 + "(1.0) can0 123#00\n"
    batch, _ = read_log(text)
    assert_same_frames(batch, pycan_messages(text))
    text = f"({stamp}) can0 123#00\n" * 3  # uniform block
    batch, _ = read_log(text)
    assert_same_frames(batch, pycan_messages(text))


def _pycan_line_by_line(text: str) -> list[can.Message]:
    """python-can's messages of each line read alone (a line it cannot read gives none).

    A payload that is not plain hex digits gives none either: python-can reads each pair
    with ``int(pair, 16)``, which takes ``+5`` or `` 5``; rigtools counts it unparsable
    (the module docstring's "bad hex"). Nor does an odd number of payload digits: python-can
    drops the last one (``10##0000FF`` read as FD flags 0 and the bytes ``00 0F``, found by
    this test), rigtools and can-utils' own parser refuse the line.
    """
    out: list[can.Message] = []
    for line in text.split("\n"):  # not splitlines(): it also splits at \v, \f, \x1c...
        frame = line.strip().split(" ")[-1]
        fd = "##" in frame
        payload = frame.partition("##")[2][1:] if fd else frame.rpartition("#")[2]
        if payload and (fd or payload[0] not in "Rr") and (len(payload) % 2 or not all(
                ch in "0123456789abcdefABCDEF" for ch in payload)):
            continue
        try:
            out += pycan_messages(line)
        except Exception:  # python-can raises many kinds on a bad line
            continue
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(row=st.integers(0, 99), col=st.integers(0, 45), byte=st.integers(1, 255).filter(
    lambda b: b not in (10, 13)))
def test_one_damaged_character_in_a_uniform_block_reads_as_python_can_reads_each_line(
        row, col, byte):
    """The compiled fixed-layout parser: every field's check, against python-can line by line.

    100 lines of one layout (the zero-copy matrix path), one character replaced by any byte
    but a line end: the damaged line goes the general way, the others stay as they were.
    """
    lines = [f"(1700000000.{i:06d}) can0 1{i % 16:X}3#{i:02X}00FFa5{i % 10}0b1c2d3" .encode()
             for i in range(100)]
    line = bytearray(lines[row])
    line[col % len(line)] = byte
    lines[row] = bytes(line)
    raw = b"\n".join(lines) + b"\n"
    batch, report = read_log(raw)
    text = raw.decode("utf-8", errors="replace")
    if raw.decode("utf-8", errors="ignore") != text:
        return  # an invalid UTF-8 byte: python-can cannot open the file as text at all
    assert_same_frames(batch, _pycan_line_by_line(text))
    assert len(batch) + report.n_rejected == 100
