"""Vector ASC reader: write/read-back with python-can's ASCWriter, hostile files, sniffing.

Timestamps are absolute, as python-can's ``ASCReader(..., relative_timestamp=False)`` gives
them: the ``Begin Triggerblock`` date (else the ``date`` line) plus each line's offset.
ASCWriter writes that date as the first message's local time truncated to the millisecond,
and ``t - t_first`` with 6 decimals (1 µs). Messages whose times lie on the microsecond grid
and start at 0 come back bit for bit; arbitrary times come back within 0.5 µs (plus float64
rounding at ~1e9 s) of ``start + t - t_first``, ``start`` being ``t_first`` truncated to the
millisecond: the tolerances the text format forces.
"""

from __future__ import annotations

import gzip
import time
from collections.abc import Callable, Iterator
from datetime import datetime
from pathlib import Path

import can
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigtools.errors import RecordingFormatError
from rigtools.ingest import registry as reg
from rigtools.ingest.can import asc
from rigtools.ingest.can.frames import CanFrameBatch, concat, from_messages
from rigtools.ingest.recording import IngestReport

# Zero-length FD frames are left out: python-can reads a CANFD line with data length 0 as a
# remote frame (test_fd_zero_length_reads_as_remote pins that).
FD_LENGTHS = (1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)


# --- helpers ---------------------------------------------------------------------------------

def read(path: Path, **kw) -> tuple[CanFrameBatch, IngestReport]:
    """All frames of an ASC file through rigtools.ingest.can.asc, and the report."""
    report = IngestReport()
    with reg.open_source(path) as stream:
        batches = list(asc.iter_batches(stream, str(path), report, **kw))
    return (concat(batches) if batches else CanFrameBatch.empty(position_unit="line")), report


def write_asc(path: Path, messages: list[can.Message]) -> Path:
    with can.ASCWriter(str(path)) as w:
        for m in messages:
            w.on_message_received(m)
    return path


def msg(t: float, arb: int, data: bytes = b"", *, ext: bool = False, fd: bool = False,
        channel: int = 0, **kw) -> can.Message:
    return can.Message(timestamp=t, arbitration_id=arb, data=data, is_extended_id=ext,
                       is_fd=fd, channel=channel, **kw)


def data_lines(path: Path) -> list[int]:
    """1-based numbers of the lines ASCWriter wrote a CAN frame on."""
    lines = path.read_text().splitlines()
    return [i for i, s in enumerate(lines, 1) if (" Rx " in s or " Tx " in s)]


def written_ms(t_first: float) -> int:
    """The milliseconds ASCWriter writes in its ``Begin Triggerblock`` date (local time)."""
    return datetime.fromtimestamp(t_first).microsecond // 1000


def asc_start(t_first: float) -> float:
    """The measurement start python-can reads back from ASCWriter's ``Begin Triggerblock`` date.

    ASCWriter writes ``datetime.fromtimestamp(t_first)`` (local time) with the microseconds
    truncated to milliseconds, *without leading zeros* (``.62`` for 62 ms); python-can parses
    the digits as a fraction of a second (``.62`` -> 620 ms), in local time.
    """
    dt = datetime.fromtimestamp(t_first)
    fraction = f"0.{written_ms(t_first)}"
    return dt.replace(microsecond=round(float(fraction) * 1e6)).timestamp()


@pytest.fixture
def tz(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[str], None]]:
    """Set the process time zone (python-can reads ASC dates in local time); restored after."""

    def set_tz(name: str) -> None:
        monkeypatch.setenv("TZ", name)
        time.tzset()

    yield set_tz
    monkeypatch.undo()
    time.tzset()


BASIC = [
    msg(0.0, 0x123, bytes([1, 2, 3, 4, 5, 6, 7, 8]), channel=0),
    msg(0.001234, 0x7FF, b"", channel=1),
    msg(0.5, 0x1ABCDEF0, bytes([0xFF, 0x00, 0x10]), ext=True, channel=2),
    msg(1.25, 0x10, bytes(range(64)), fd=True, bitrate_switch=True, channel=0),
    msg(2.000001, 0x1FFFFFFF, bytes(range(12)), ext=True, fd=True, channel=3),
    msg(3.75, 0x0, bytes([0xAA]), channel=0),
]


# --- write / read back -----------------------------------------------------------------------

def test_read_back_is_bit_exact(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "basic.asc", BASIC)
    got, report = read(path)
    lines = data_lines(path)
    want = from_messages(BASIC, lines, "line")
    assert got.equals(want, compare_position=True)
    assert got.position_unit == "line"
    np.testing.assert_array_equal(got.channel, [0, 1, 2, 0, 3, 0])
    assert got.is_fd.tolist() == [False, False, False, True, True, False]
    assert got.length.tolist() == [8, 0, 3, 64, 12, 1]
    assert report.n_rejected == 0
    assert report.warnings == []


@pytest.mark.parametrize("t0", [0.0, 1_700_000_000.123_456_7])
def test_frames_equal_python_can_reader(tmp_path: Path, t0: float) -> None:
    messages = [msg(t0 + m.timestamp, m.arbitration_id, bytes(m.data), ext=m.is_extended_id,
                    fd=m.is_fd, channel=m.channel, bitrate_switch=m.bitrate_switch)
                for m in BASIC]
    path = write_asc(tmp_path / "basic.asc", messages)
    got, report = read(path)
    with can.ASCReader(str(path), relative_timestamp=False) as r:
        ref = list(r)
    assert got.equals(from_messages(ref, data_lines(path), "line"))
    assert report.warnings == []
    assert got.timestamp_s[0] == asc_start(t0)  # absolute: the trigger-block date


@pytest.mark.parametrize("bad", [-1, 2.5, True])
def test_batch_frames_must_be_an_integer(tmp_path: Path, bad: object) -> None:
    """Below 1 for every CAN reader in test_reader_contract.py; text logs also want an int."""
    path = write_asc(tmp_path / "a.asc", BASIC)
    with open(path, "rb") as f, pytest.raises(ValueError,
                                              match=r"`batch_frames` must be an integer >= 1"):
        asc.iter_batches(f, str(path), IngestReport(), batch_frames=bad)  # type: ignore[arg-type]


_classic = st.builds(
    lambda arb, ext, data, ch: (arb if ext else arb & 0x7FF, ext, False, bytes(data), ch),
    st.integers(0, 0x1FFFFFFF), st.booleans(), st.binary(max_size=8), st.integers(0, 15),
)
_fd = st.builds(
    lambda arb, ext, n, seed, ch: (arb if ext else arb & 0x7FF, ext, True,
                                   bytes((seed + 7 * i) & 0xFF for i in range(n)), ch),
    st.integers(0, 0x1FFFFFFF), st.booleans(), st.sampled_from(FD_LENGTHS),
    st.integers(0, 255), st.integers(0, 15),
)


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(frames=st.lists(st.one_of(_classic, _fd), min_size=1, max_size=30),
       t0=st.floats(0, 2e9), gaps=st.lists(st.floats(0, 10), min_size=30, max_size=30))
def test_read_back_property(tmp_path: Path, tz, frames, t0: float, gaps: list[float]) -> None:
    """Any classic/FD frames at any times: equal to what was written.

    Times come back within 0.5 µs of the millisecond start plus the offsets.
    """
    tz("UTC")  # no daylight-saving fold: a local date in the repeated hour reads back 1 h off
    stamps = t0 + np.cumsum([0.0, *gaps[: len(frames) - 1]])
    messages = [msg(float(t), arb, data, ext=ext, fd=fd, channel=ch)
                for t, (arb, ext, fd, data, ch) in zip(stamps, frames, strict=True)]
    path = write_asc(tmp_path / "prop.asc", messages)
    got, report = read(path)
    assert report.n_rejected == 0
    assert len(got) == len(messages)
    want = from_messages(messages, data_lines(path), "line")
    # exact except the time stamp: same ids, flags, lengths, payloads, channels, positions
    same_t = CanFrameBatch(want.timestamp_s.copy(), *[getattr(got, f) for f in (
        "arbitration_id", "is_extended", "is_fd", "length", "data", "channel", "position")],
        "line")
    assert same_t.equals(want, compare_position=True)
    np.testing.assert_array_equal(got.channel, want.channel)
    # ASCWriter writes t_first truncated to the millisecond (trigger-block date) and
    # t - t_first rounded to 1 µs; python-can adds them. Float64 near 2e9 s has 0.24 µs steps
    # (ASCWriter's subtraction, python-can's addition, this test's subtraction).
    start = asc_start(stamps[0])
    ms = written_ms(stamps[0])
    if ms == 0 or ms >= 100:  # three digits (or ".0"): the start truncated to the millisecond
        # (-1 us: a start within half a microsecond below the millisecond rounds up to it)
        assert -1e-6 <= stamps[0] - start < 1e-3 + 0.5e-6
        assert not any("the start date" in w for w in report.warnings)
    else:  # ASCWriter's ".62" for 62 ms reads 620 ms: late, and said so
        assert start - stamps[0] == pytest.approx(float(f"0.{ms}") - ms / 1000, abs=1e-3)
        assert any("the start date (line 4) has" in w for w in report.warnings)
    np.testing.assert_allclose(got.timestamp_s, start + (stamps - stamps[0]), rtol=0,
                               atol=0.5e-6 + 3 * np.spacing(2e9))


# --- absolute time stamps --------------------------------------------------------------------

def _frames_text(*frame_lines: str) -> str:
    return "".join(f"{line}\n" for line in frame_lines)


FRAMES = _frames_text("   0.000000 Start of measurement",
                      "   1.000000 1  100  Rx   d 1 01",
                      "   2.500000 1  101  Rx   d 1 02")


def test_trigger_block_date_wins_over_the_date_line(tmp_path: Path, tz) -> None:
    """python-can's rule: the ``Begin Triggerblock`` date, else the ``date`` header line."""
    tz("UTC")
    head = "date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n" \
           "internal events logged\n"
    with_trigger = tmp_path / "trigger.asc"
    with_trigger.write_text(head + "Begin Triggerblock Sat Sep 30 10:06:13.191 PM 2017\n"
                            + FRAMES + "End TriggerBlock\n")
    date_only = tmp_path / "date_only.asc"
    date_only.write_text(head + FRAMES)
    for path, start in ((with_trigger, 1506809173.191), (date_only, 1506783973.191)):
        got, report = read(path)
        assert got.timestamp_s.tolist() == [start + 1.0, start + 2.5]
        with can.ASCReader(str(path), relative_timestamp=False) as r:
            assert got.equals(from_messages(list(r), got.position, "line"))
        assert report.warnings == [] and report.n_rejected == 0


@pytest.mark.parametrize(("frac", "ms", "late"), [(0.062, 62, 0.558), (0.008, 8, 0.792),
                                                  (0.0, 0, 0.0), (0.1, 100, 0.0)])
def test_ascwriter_milliseconds_without_leading_zeros(tmp_path: Path, tz, frac: float, ms: int,
                                                     late: float) -> None:
    """python-can 4.6.1's ASCWriter writes ``.62`` for 62 ms; python-can reads 620 ms.

    rigtools reads what python-can reads, and warns when the digits are ambiguous.
    """
    tz("UTC")
    t0 = 1_700_000_000.0 + frac + 0.0004  # .0004: within the millisecond, truncated
    path = write_asc(tmp_path / "ms.asc", [msg(t0, 0x100, b"\x01"), msg(t0 + 1.0, 0x101)])
    assert f"Begin Triggerblock Tue Nov 14 22:13:20.{ms} 2023" in path.read_text()
    got, report = read(path)
    with can.ASCReader(str(path), relative_timestamp=False) as r:
        assert got.equals(from_messages(list(r), got.position, "line"))
    np.testing.assert_allclose(got.timestamp_s - (np.array([t0, t0 + 1.0]) - 0.0004),
                               late, rtol=0, atol=1e-6)
    warned = [w for w in report.warnings if "the start date" in w]
    if 0 < ms < 100:
        assert warned == [
            f"{path}: the start date (line 4) has {len(str(ms))} digit(s) after the seconds "
            f"('.{ms}'), read as 0.{ms} s as python-can reads it; python-can's ASCWriter writes "
            "milliseconds without leading zeros ('.62' for 62 ms), so the absolute times may "
            "be up to 0.9 s late"]
    else:
        assert warned == []


def test_dates_are_read_in_local_time(tmp_path: Path, tz) -> None:
    """The date carries no zone; python-can (and rigtools) read it in the local time zone."""
    path = tmp_path / "local.asc"
    path.write_text("date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
                    "internal events logged\n" + FRAMES)
    tz("UTC")
    utc, _ = read(path)
    tz("ZZZ-02")  # POSIX TZ: two hours east of UTC, no daylight saving
    east, report = read(path)
    with can.ASCReader(str(path), relative_timestamp=False) as r:
        assert east.equals(from_messages(list(r), east.position, "line"))
    np.testing.assert_array_equal(utc.timestamp_s - east.timestamp_s, 7200.0)
    assert report.warnings == []


# Dates python-can's ASCReader matches as dates but cannot parse (its month names are English
# and a few German ones, its formats "%m %d %H:%M:%S.%f %Y" and the AM/PM ones).
BAD_DATES = ["Sat Sep 30 15:06:13,191 2017",   # comma before the milliseconds
             "sáb sep 30 15:06:13.191 2017",   # Spanish: lower-case month
             "土 9月 30 15:06:13.191 2017",     # Japanese
             "Sat 30.09.2017 15:06:13.191"]    # day first, numeric month


@pytest.mark.parametrize("date", BAD_DATES)
def test_unparsable_date_falls_back_to_relative_times(tmp_path: Path, date: str) -> None:
    """python-can raises and loses the whole file; rigtools falls back to relative times.

    Every frame is kept, times as python-can's relative_timestamp=True gives them, and one
    warning says so.
    """
    path = tmp_path / "locale.asc"
    path.write_text(f"date {date}\nbase hex  timestamps absolute\ninternal events logged\n"
                    f"Begin Triggerblock {date}\n" + FRAMES + "End TriggerBlock\n",
                    encoding="utf-8")
    with can.ASCReader(str(path), relative_timestamp=False) as r, \
            pytest.raises(ValueError, match="Incompatible datetime string") as raised:
        list(r)
    got, report = read(path)
    assert got.timestamp_s.tolist() == [1.0, 2.5]
    assert got.position.tolist() == [6, 7]
    with can.ASCReader(str(path), relative_timestamp=True) as r:
        assert got.equals(from_messages(list(r), got.position, "line"))
    assert report.n_rejected == 0
    assert report.warnings == [
        f"{path}: python-can cannot parse the date of line 1 ('date {date}': ValueError: "
        f"{raised.value}); timestamps from there on are relative to the measurement start "
        "(s), not UNIX times"
    ]


def test_unparsable_trigger_date_after_a_good_date_line(tmp_path: Path) -> None:
    """The trigger-block date would replace the header's: relative from there on."""
    path = tmp_path / "trigger_locale.asc"
    path.write_text("date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
                    "internal events logged\n// comment\n"
                    "Begin Triggerblock sáb sep 30 15:06:13.191 2017\n" + FRAMES
                    + "End TriggerBlock\n", encoding="utf-8")
    got, report = read(path)
    assert got.timestamp_s.tolist() == [1.0, 2.5]
    assert report.n_rejected == 0
    assert len(report.warnings) == 1
    assert report.warnings[0].startswith(
        f"{path}: python-can cannot parse the date of line 5 ('Begin Triggerblock sáb sep 30 "
        "15:06:13.191 2017': ValueError: Incompatible datetime string sep 30")


@pytest.mark.parametrize("header", ["base hex  timestamps absolute\n",
                                    "// no date\nbase hex  timestamps absolute\n"
                                    "internal events logged\nBegin Triggerblock\n"],
                         ids=["no-date-line", "trigger-without-date"])
def test_no_date_reads_relative_times_with_a_warning(tmp_path: Path, header: str) -> None:
    path = tmp_path / "undated.asc"
    path.write_text(header + FRAMES + ("End TriggerBlock\n" if "Trigger" in header else ""))
    got, report = read(path)
    assert got.timestamp_s.tolist() == [1.0, 2.5]
    with can.ASCReader(str(path), relative_timestamp=False) as r:
        assert list(r)[-1].timestamp == 2.5  # python-can: start 0.0, silently
    assert report.n_rejected == 0
    assert report.warnings == [f"{path}: no 'date' or 'Begin Triggerblock' line with a date; "
                               "timestamps are relative to the measurement start (s), not "
                               "UNIX times"]


def test_date_line_python_can_does_not_recognise(tmp_path: Path) -> None:
    """``date sam. sept. ...`` is no date line for python-can (``date <word> <rest>``).

    It is counted unparsable_line and the times are relative.
    """
    path = tmp_path / "french.asc"
    path.write_text("date sam. sept. 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
                    "internal events logged\n" + FRAMES)
    got, report = read(path)
    assert got.timestamp_s.tolist() == [1.0, 2.5]
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position == {"unparsable_line": "line 1"}
    assert any("no 'date' or 'Begin Triggerblock' line with a date" in w
               for w in report.warnings)


@pytest.mark.parametrize("date", ["Sat Sep 30 15:06:13.191 2017", BAD_DATES[0]],
                         ids=["good-date", "bad-date"])
def test_restart_after_a_python_can_error_keeps_the_time_base(tmp_path: Path, tz,
                                                            date: str) -> None:
    """python-can raising mid-file is restarted with the header replayed.

    The frames after the bad line keep the start time (absolute), or stay relative after a
    bad date.
    """
    tz("UTC")
    path = tmp_path / "restart.asc"
    bad = "   1.800000 1  123  Rx   d 8 0G 00 00 00 00 00 00 00\n"
    path.write_text(f"date {date}\nbase hex  timestamps absolute\ninternal events logged\n"
                    f"Begin Triggerblock {date}\n"
                    + FRAMES.replace("   2.500000", bad + "   2.500000") + "End TriggerBlock\n")
    got, report = read(path)
    start = 1506783973.191 if "2017" in date and "," not in date else 0.0
    assert got.timestamp_s.tolist() == [start + 1.0, start + 2.5]
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position == {"unparsable_line": "line 7"}
    assert any("python-can raised on 1 line(s)" in w for w in report.warnings)
    assert len(report.warnings) == (1 if start else 2)


# --- error and remote frames -----------------------------------------------------------------

def test_error_and_remote_frames_counted_not_kept(tmp_path: Path) -> None:
    messages = [
        msg(0.0, 0x100, b"\x01"),
        msg(0.1, 0, b"", is_error_frame=True, channel=1),
        msg(0.2, 0x200, b"", is_remote_frame=True, dlc=4),
        msg(0.3, 0x1234567, b"", ext=True, is_remote_frame=True, dlc=0),
        msg(0.4, 0x300, b"\x02\x03"),
        msg(0.5, 0, b"", is_error_frame=True),
    ]
    path = write_asc(tmp_path / "err.asc", messages)
    got, report = read(path)
    assert got.arbitration_id.tolist() == [0x100, 0x300]
    assert report.rejected == {"error_frame": 2, "remote_frame": 2}
    lines = path.read_text().splitlines()
    err_line = next(i for i, s in enumerate(lines, 1) if "ErrorFrame" in s)
    rtr_line = next(i for i, s in enumerate(lines, 1) if " r " in s)
    assert report.first_position == {"error_frame": f"line {err_line}",
                                     "remote_frame": f"line {rtr_line}"}


def test_fd_error_and_fd_remote_frames(tmp_path: Path) -> None:
    text = (
        "date Sam Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
        "internal events logged\nBegin Triggerblock Sam Sep 30 15:06:13.191 2017\n"
        "   0.000000 Start of measurement\n"
        "   1.000000 CANFD   3 Tx     50005x   0 1 5 0 140000 73 200050 7a60 46500250 460a0250\n"
        "   2.000000 CANFD   5 Tx ErrorFrame Not Acknowledge error, dominant error flag\n"
        "   3.000000 CANFD   1 Rx        300   1 0 8  8 11 c2 03 04 05 06 07 08   102203  133\n"
        "End TriggerBlock\n"
    )
    path = tmp_path / "fd.asc"
    path.write_text(text)
    got, report = read(path)
    assert report.rejected == {"remote_frame": 1, "error_frame": 1}
    assert report.first_position == {"remote_frame": "line 6", "error_frame": "line 7"}
    assert got.position.tolist() == [8]
    assert bytes(got.data[0, :8]) == bytes([0x11, 0xC2, 3, 4, 5, 6, 7, 8])


def test_fd_zero_length_reads_as_remote(tmp_path: Path) -> None:
    """python-can's ASC dialect: a CANFD line with data length 0 is a remote frame."""
    path = write_asc(tmp_path / "fd0.asc", [msg(0.0, 0x10, b"", fd=True), msg(1.0, 0x11, b"\x01")])
    got, report = read(path)
    assert got.arbitration_id.tolist() == [0x11]
    assert report.rejected == {"remote_frame": 1}


# --- hostile files ---------------------------------------------------------------------------

def test_blank_lines_only_refused(tmp_path: Path) -> None:
    path = tmp_path / "blank_run.asc"
    path.write_bytes(b"\n  \r\n\t\n")
    with pytest.raises(RecordingFormatError, match=r"blank_run\.asc .*an empty file"):
        read(path)


def test_header_only_file_yields_nothing(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "no_frames.asc", [])
    got, report = read(path)
    assert len(got) == 0
    assert report.n_rejected == 0


def test_garbage_lines_in_the_middle_counted(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "clean.asc", BASIC)
    lines = path.read_text().splitlines(keepends=True)
    frames = data_lines(path)
    cut = frames[2]  # insert before the third frame line
    garbage = [
        "this line is garbage\n",                      # python-can skips it silently
        "   0.700000 1  XYZ!           Rx   d 8 00\n",  # frame-like, python-can skips it
        "   0.800000 1  123            Rx   d 8 0G 00 00 00 00 00 00 00\n",  # python-can raises
        "   0.900000 1  124            Rx\n",           # python-can raises (unpacking)
        "\x00\x01\x02 binary noise\n",
    ]
    path2 = tmp_path / "dirty.asc"
    path2.write_text("".join(lines[: cut - 1] + garbage + lines[cut - 1:]))
    got, report = read(path2)
    shifted = [n if n < cut else n + len(garbage) for n in frames]
    assert got.equals(from_messages(BASIC, shifted, "line"), compare_position=True)
    assert report.rejected == {"unparsable_line": len(garbage)}
    assert report.first_position["unparsable_line"] == f"line {cut}"
    assert any("python-can raised on 2 line(s) (first at line " f"{cut + 2}" in w
               for w in report.warnings)


def test_garbage_before_first_frame_then_frames(tmp_path: Path) -> None:
    """python-can errors before the first frame are tolerated when frames follow."""
    path = write_asc(tmp_path / "clean.asc", BASIC)
    lines = path.read_text().splitlines(keepends=True)
    first = data_lines(path)[0]
    bad = ["   0.000000 1  12             Rx   d 2 zz zz\n"] * 3
    path2 = tmp_path / "bad_start.asc"
    path2.write_text("".join(lines[: first - 1] + bad + lines[first - 1:]))
    got, report = read(path2)
    assert len(got) == len(BASIC)
    assert report.rejected == {"unparsable_line": 3}
    assert report.first_position["unparsable_line"] == f"line {first}"


def test_only_unreadable_frames_refused(tmp_path: Path) -> None:
    head = "date Sam Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
    body = "".join(f"   {i}.000000 1  12   Rx   d 2 zz zz\n" for i in range(30))
    path = tmp_path / "all_bad.asc"
    path.write_text(head + body)
    with pytest.raises(RecordingFormatError,
                       match=r"all_bad\.asc at line 3: expected a Vector ASC log.*python-can "
                             r"ValueError"):
        read(path)


def test_truncated_last_line_counted(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "clean.asc", BASIC)
    text = path.read_text()
    last_frame = data_lines(path)[-1]
    lines = text.splitlines(keepends=True)
    # the last frame line loses its tail (and the file its End TriggerBlock)
    lines[last_frame - 1] = "   3.750000 1  0              Rx   d 1"
    path2 = tmp_path / "truncated.asc"
    path2.write_text("".join(lines[:last_frame]))
    got, report = read(path2)
    assert got.equals(from_messages(BASIC[:-1], data_lines(path)[:-1], "line"),
                      compare_position=True)
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position == {"unparsable_line": f"line {last_frame}"}
    assert any("no 'End TriggerBlock'" in w for w in report.warnings)


@pytest.mark.parametrize("tail", ["   3.7", "   3.750000", "   3.750000 1", "   3.750000 1  0  "])
def test_last_line_cut_anywhere_is_counted(tmp_path: Path, tail: str) -> None:
    path = write_asc(tmp_path / "clean.asc", BASIC)
    n = data_lines(path)[-1]
    lines = path.read_text().splitlines(keepends=True)[: n - 1]
    path2 = tmp_path / "cut.asc"
    path2.write_text("".join(lines) + tail)
    got, report = read(path2)
    assert len(got) == len(BASIC) - 1
    assert report.rejected == {"unparsable_line": 1}
    assert report.first_position == {"unparsable_line": f"line {n}"}


def test_short_payload_counted(tmp_path: Path) -> None:
    """A classic frame line with fewer bytes than its DLC is rejected, not zero-padded."""
    text = (
        "date Sam Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
        "internal events logged\n"
        "   1.000000 1  100  Rx   d 8 01 02 03\n"
        "   2.000000 1  100  Rx   d 3 01 02 03\n"
        "   3.000000 CANFD   1 Rx   300   1 0 d 32 01 02 03\n"
    )
    path = tmp_path / "short.asc"
    path.write_text(text)
    got, report = read(path)
    assert got.position.tolist() == [5]
    assert report.rejected == {"unparsable_line": 2}
    assert report.first_position == {"unparsable_line": "line 4"}


def test_events_and_comments_accounted(tmp_path: Path) -> None:
    text = (
        "date Sam Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
        "internal events logged\n// version 9.0.0\n"
        "Begin Triggerblock Sam Sep 30 15:06:13.191 2017\n"
        "   0.000000 Start of measurement\n"
        "   0.015991 CAN 1 Status:chip status error active\n"
        "   1.015991 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%\n"
        "   1.100000 1  64              Rx   d 1 02\n"
        "   3.297743 1  J1939TP FEE3p        6    0  0   -   Rx   d 3 A0 0F A6\n"
        "End TriggerBlock\n"
    )
    path = tmp_path / "events.asc"
    path.write_text(text)
    got, report = read(path)
    assert got.position.tolist() == [9]
    assert report.n_rejected == 0
    assert report.warnings == [f"{path}: 3 logged event line(s) that are not CAN frames "
                               "(status, statistics, transport protocol, ...) ignored; first "
                               "at line 7"]


def test_header_without_events_line_loses_no_frame(tmp_path: Path) -> None:
    """python-can's header scan eats the first non-header line; rigtools keeps that frame."""
    text = (
        "date Sam Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n"
        "   1.000000 1  100  Rx   d 2 01 02\n"
        "   2.000000 1  101  Rx   d 2 03 04\n"
    )
    path = tmp_path / "no_events_line.asc"
    path.write_text(text)
    got, report = read(path)
    assert got.position.tolist() == [3, 4]
    assert report.n_rejected == 0
    with can.ASCReader(str(path)) as r:
        assert len(list(r)) == 1  # python-can alone loses the first frame


def test_decimal_base_is_python_cans(tmp_path: Path) -> None:
    text = (
        "date Sam Sep 30 15:06:13.191 2017\nbase dec  timestamps absolute\n"
        "internal events logged\n"
        "   1.000000 1  256  Rx   d 2 10 255\n"
        "   1.500000 1  65  Rx   d 3 10 11 12 13\n"  # trailing extra byte ignored, like CANoe
    )
    path = tmp_path / "dec.asc"
    path.write_text(text)
    got, report = read(path)
    assert got.arbitration_id.tolist() == [256, 65]
    assert bytes(got.data[0, :2]) == bytes([10, 255])
    assert report.n_rejected == 0


def test_non_utf8_bytes_decoded_and_counted(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "clean.asc", BASIC)
    raw = path.read_bytes().splitlines(keepends=True)
    n = data_lines(path)[1]
    # a cp1252 comment and a stray byte at the end of a frame line (after the payload)
    raw.insert(3, "// Prüfstand 3, Öltemperatur 90 °C\n".encode("cp1252"))
    raw[n] = raw[n].rstrip(b"\r\n") + b" \xff\x81\n"
    path2 = tmp_path / "latin.asc"
    path2.write_bytes(b"".join(raw))
    got, report = read(path2)
    assert got.equals(from_messages(BASIC, [k + 1 for k in data_lines(path)], "line"),
                      compare_position=True)
    assert report.n_rejected == 0
    assert f"{path2}: 2 line(s) are not valid UTF-8 and were decoded as cp1252/latin-1; " \
           "first at line 4" in report.warnings


def test_german_month_in_date_line(tmp_path: Path) -> None:
    text = ("date Mi Mär 15 10:00:00.000 2023\nbase hex  timestamps absolute\n"
            "internal events logged\n   1.000000 1  100  Rx   d 1 01\n").encode("cp1252")
    path = tmp_path / "maerz.asc"
    path.write_bytes(text)
    got, report = read(path)
    assert len(got) == 1
    assert any("not valid UTF-8" in w for w in report.warnings)


def test_crlf_and_bom(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "clean.asc", BASIC)
    path2 = tmp_path / "crlf.asc"
    path2.write_bytes(b"\xef\xbb\xbf" + path.read_bytes().replace(b"\n", b"\r\n"))
    got, report = read(path2)
    assert got.equals(read(path)[0], compare_position=True)
    assert report.n_rejected == 0
    assert asc.sniff(path2.read_bytes())


def test_gzip_stream(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "basic.asc", BASIC)
    gz = tmp_path / "basic.asc.gz"
    gz.write_bytes(gzip.compress(path.read_bytes()))
    assert read(gz)[0].equals(read(path)[0], compare_position=True)


def test_truncated_gzip_keeps_frames_and_reports(tmp_path: Path) -> None:
    path = write_asc(tmp_path / "long.asc", [msg(i * 1e-3, 0x100 + i % 50, bytes([i % 256]))
                                             for i in range(3000)])
    blob = gzip.compress(path.read_bytes())
    gz = tmp_path / "cut.asc.gz"
    gz.write_bytes(blob[: len(blob) // 2])
    got, report = read(gz)
    assert 0 < len(got) < 3000
    assert report.rejected["truncated_stream"] == 1
    assert any("the stream ended with an error" in w for w in report.warnings)


def test_not_an_asc_refused(tmp_path: Path) -> None:
    path = tmp_path / "notes.asc"
    path.write_text("hello\nworld\n")
    with pytest.raises(RecordingFormatError,
                       match=r"notes\.asc at line 1: expected a Vector ASC log.*'hello'"):
        read(path)


# --- sniffing --------------------------------------------------------------------------------

def test_sniff_claims_header_variants() -> None:
    """What ASCWriter writes is claimed by ASC alone (test_reader_contract.py); other tools'."""
    assert asc.sniff(b"// exported by CANoe\nbase hex  timestamps relative\n")
    assert asc.sniff(b"Begin TriggerBlock Sat Sep 30 10:06:13.191 PM 2017\n")
