"""python-can CSV reader: write/read-back with python-can's CSVWriter, hostile files, sniffing.

CSVWriter writes ``repr(timestamp)``, so timestamps come back bit for bit (no tolerance). The
format has no channel (read as -1) and no FD flag (only classic frames are written here).
"""

from __future__ import annotations

from pathlib import Path

import can
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.errors import RecordingFormatError
from rigtools.ingest import registry as reg
from rigtools.ingest.can import csv_log
from rigtools.ingest.can.frames import CanFrameBatch, concat, from_messages
from rigtools.ingest.recording import IngestReport

HEADER = "timestamp,arbitration_id,extended,remote,error,dlc,data"


def read(path: Path, **kw) -> tuple[CanFrameBatch, IngestReport]:
    report = IngestReport()
    with reg.open_source(path) as stream:
        batches = list(csv_log.iter_batches(stream, str(path), report, **kw))
    return (concat(batches) if batches else CanFrameBatch.empty(position_unit="line")), report


def write_csv(path: Path, messages: list[can.Message]) -> Path:
    with can.CSVWriter(str(path)) as w:
        for m in messages:
            w.on_message_received(m)
    return path


def msg(t: float, arb: int, data: bytes = b"", *, ext: bool = False, **kw) -> can.Message:
    return can.Message(timestamp=t, arbitration_id=arb, data=data, is_extended_id=ext, **kw)


BASIC = [
    msg(1_700_000_000.123456789, 0x123, bytes([1, 2, 3, 4, 5, 6, 7, 8])),
    msg(1_700_000_000.2, 0x7FF, b""),
    msg(1_700_000_000.3, 0x1ABCDEF0, bytes([0xFF, 0x00, 0x10]), ext=True),
    msg(1_700_000_001.0 / 3.0, 0x0, bytes([0xAA])),
    msg(0.0, 0x5, bytes(range(7)), ext=True),
]
LINES = [2, 3, 4, 5, 6]


def test_read_back_is_bit_exact(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "basic.csv", BASIC)
    got, report = read(path)
    assert got.equals(from_messages(BASIC, LINES, "line"), compare_position=True)
    assert got.channel.tolist() == [-1] * 5
    assert report.n_rejected == 0
    assert report.warnings == []


def test_frames_equal_python_can_reader(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "basic.csv", BASIC)
    got, _ = read(path)
    with can.CSVReader(str(path)) as r:
        assert got.equals(from_messages(list(r), LINES, "line"))


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(frames=st.lists(st.tuples(st.floats(0, 4e9, allow_nan=False), st.integers(0, 0x1FFFFFFF),
                                 st.booleans(), st.binary(max_size=8)), min_size=1, max_size=40))
def test_read_back_property(tmp_path: Path, frames) -> None:
    messages = [msg(t, arb if ext else arb & 0x7FF, data, ext=ext) for t, arb, ext, data in frames]
    path = write_csv(tmp_path / "prop.csv", messages)
    got, report = read(path)
    assert report.n_rejected == 0
    assert got.equals(from_messages(messages, range(2, 2 + len(messages)), "line"),
                      compare_position=True)


def test_error_and_remote_frames_counted_not_kept(tmp_path: Path) -> None:
    messages = [
        msg(1.0, 0x100, b"\x01"),
        msg(2.0, 0, b"", is_error_frame=True),
        msg(3.0, 0x200, b"", is_remote_frame=True, dlc=4),
        msg(4.0, 0x300, b"\x02\x03"),
        msg(5.0, 0x1234, b"", ext=True, is_remote_frame=True),
    ]
    path = write_csv(tmp_path / "err.csv", messages)
    got, report = read(path)
    assert got.arbitration_id.tolist() == [0x100, 0x300]
    assert got.position.tolist() == [2, 5]
    assert report.rejected == {"error_frame": 1, "remote_frame": 2}
    assert report.first_position == {"error_frame": "line 3", "remote_frame": "line 4"}


# --- hostile files ---------------------------------------------------------------------------

def test_header_only_yields_nothing(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "header_only.csv", [])
    got, report = read(path)
    assert len(got) == 0
    assert report.n_rejected == 0


def test_garbage_lines_in_the_middle_counted(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "clean.csv", BASIC)
    lines = path.read_text().splitlines(keepends=True)
    garbage = [
        "this line is garbage\n",
        "1.5,0x12G,0,0,0,1,AQ==\n",        # bad hex id
        "1.5,0x12,0,0,0,1,A\n",            # bad base64
        "1.5,0x12,0,0,0,1,AQ==,extra\n",   # one column too many
        HEADER + "\n",                     # a second header (concatenated logs): fine
        "\xff\xfe\n",
    ]
    path2 = tmp_path / "dirty.csv"
    path2.write_bytes("".join(lines[:3] + garbage + lines[3:]).encode("latin-1"))
    got, report = read(path2)
    n = len(garbage)
    assert got.equals(from_messages(BASIC, [2, 3, 4 + n, 5 + n, 6 + n], "line"),
                      compare_position=True)
    assert report.rejected == {"unparsable_line": n - 1}
    assert report.first_position == {"unparsable_line": "line 4"}
    assert any("1 line(s) are not valid UTF-8" in w for w in report.warnings)


def test_truncated_last_line_counted(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "clean.csv", BASIC)
    text = path.read_text()
    for cut in (3, 6, 12, len(text.splitlines()[-1]) - 4):
        lines = text.splitlines(keepends=True)
        path2 = tmp_path / f"cut{cut}.csv"
        path2.write_text("".join(lines[:-1]) + lines[-1][:cut])
        got, report = read(path2)
        assert got.equals(from_messages(BASIC[:-1], LINES[:-1], "line"), compare_position=True)
        assert report.rejected == {"unparsable_line": 1}, cut
        assert report.first_position == {"unparsable_line": "line 6"}


def test_short_payload_counted(tmp_path: Path) -> None:
    text = HEADER + "\n1.0,0x10,0,0,0,8,AQID\n2.0,0x11,0,0,0,3,AQID\n"
    path = tmp_path / "short.csv"
    path.write_text(text)
    got, report = read(path)
    assert got.position.tolist() == [3]
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position == {"unparsable_line": "line 2"}


def test_only_bad_lines_refused(tmp_path: Path) -> None:
    path = tmp_path / "all_bad.csv"
    path.write_text(HEADER + "\n" + "x,y,z\n" * 25)
    with pytest.raises(RecordingFormatError,
                       match=r"all_bad\.csv at line 2: expected a python-can CSV log.*'x,y,z'"):
        read(path)


def test_long_unreadable_tail_abandoned_and_counted(tmp_path: Path) -> None:
    """After 1000 python-can errors in a row the rest is counted, not parsed line by line."""
    good = "1.0,0x10,0,0,0,1,AQ==\n"
    path = tmp_path / "tail.csv"
    path.write_text(HEADER + "\n" + good * 2 + "x,y\n" * 1500 + "\n" + good)
    got, report = read(path)
    assert got.position.tolist() == [2, 3]
    assert report.rejected == {"unparsable_line": 1501}
    assert report.first_position == {"unparsable_line": "line 4"}
    assert any("python-can failed on 1000 lines in a row; the 501 non-blank lines after "
               "line 1003" in w for w in report.warnings)


def test_crlf_blank_lines_and_bom(tmp_path: Path) -> None:
    path = write_csv(tmp_path / "clean.csv", BASIC)
    body = path.read_bytes().replace(b"\n", b"\r\n\r\n")
    path2 = tmp_path / "crlf.csv"
    path2.write_bytes(b"\xef\xbb\xbf" + body)
    got, report = read(path2)
    assert got.position.tolist() == [3, 5, 7, 9, 11]
    want = from_messages(BASIC, [3, 5, 7, 9, 11], "line")
    assert got.equals(want, compare_position=True)
    assert report.n_rejected == 0
    assert csv_log.sniff(path2.read_bytes())


def test_not_a_csv_log_refused(tmp_path: Path) -> None:
    path = tmp_path / "table.csv"
    path.write_text("a,b,c\n1,2,3\n")
    with pytest.raises(RecordingFormatError, match=r"table\.csv at line 1: expected a python-can "):
        read(path)
