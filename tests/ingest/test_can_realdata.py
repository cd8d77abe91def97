"""Real files from python-can's and cantools' test suites (see each folder's SOURCE.md).

* python-can logs (``realdata/python-can``): every ASC, gzipped ASC and TRC file is detected
  by content, unwrapped and read; the frames and the error/remote tallies equal what
  python-can's ``LogReader`` yields, configured as rigtools reads (ASC with absolute times,
  ``relative_timestamp=False``); the files holding the same frames agree across formats,
  absolute times included; CAN FD payloads keep their 64 bytes.
* cantools DBCs (``realdata/cantools-dbc``): every file loads with ``load_dbc`` (strict) or
  raises ``DbcError`` naming the file; every signal of every message decodes with
  ``decode_signal`` exactly as cantools' ``decode_message`` over a few hundred seeded random
  payloads (multiplexed signals where cantools returns them, with valid multiplexer values
  written into the payloads).

The folder is found next to the project (``<project>/../shared/realdata``); the tests skip when
it is absent. Files are read in place, never copied.
"""

from __future__ import annotations

import gzip
import time
from collections.abc import Callable, Iterator
from datetime import UTC, datetime
from pathlib import Path

import can
import cantools
import numpy as np
import pytest
from realdata_path import REALDATA

from rigtools.errors import DbcError
from rigtools.ingest.can.dbc import decode_signal, load_dbc, multiplex_mask
from rigtools.ingest.can.frames import CanFrameBatch, concat, from_messages
from rigtools.ingest.files import open_source
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.registry import CAN_READERS, detect_format

PYCAN = REALDATA / "python-can"
DBCS = REALDATA / "cantools-dbc"

needs_pycan = pytest.mark.skipif(not PYCAN.is_dir(), reason=f"{PYCAN} not present")
needs_dbcs = pytest.mark.skipif(not DBCS.is_dir(), reason=f"{DBCS} not present")


def _files(folder: Path, *suffixes: str) -> list[Path]:
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.name.lower().endswith(suffixes))


LOGS = _files(PYCAN, ".asc", ".asc.gz", ".trc")
DBC_FILES = _files(DBCS, ".dbc")
#: The DBCs cantools refuses with strict=True (SOURCE.md of the cantools folder).
BAD_DBCS = {"bad_message_length.dbc", "issue_63.dbc", "issue_199.dbc", "issue_199_extended.dbc"}


def read(path: Path, fmt: str) -> tuple[CanFrameBatch, IngestReport]:
    report = IngestReport()
    with open_source(path) as stream:
        batches = list(CAN_READERS[fmt].iter_batches(stream, str(path), report))
    return (concat(batches) if batches else CanFrameBatch.empty(position_unit="line")), report


def python_can(path: Path) -> tuple[list[can.Message], int, int]:
    """Data frames, error-frame count and remote-frame count as python-can's LogReader gives.

    ASC files are read as rigtools reads them, with absolute times (``relative_timestamp=
    False``; TRCReader takes no such option and ignores it). python-can 4.6.1's LogReader
    drops its keyword arguments for gzipped files (``_decompress(filename)``), so a ``.asc.gz``
    is opened here and handed to ASCReader directly.
    """
    name = path.name.lower()
    kwargs = {"relative_timestamp": False} if ".asc" in name else {}
    if name.endswith(".asc.gz"):
        reader = can.ASCReader(gzip.open(path, "rt"), **kwargs)
    else:
        reader = can.LogReader(str(path), **kwargs)
    with reader as r:
        messages = list(r)
    data = [m for m in messages if not m.is_error_frame and not m.is_remote_frame]
    n_err = sum(m.is_error_frame for m in messages)
    n_rtr = sum(m.is_remote_frame and not m.is_error_frame for m in messages)
    return data, n_err, n_rtr


# --- python-can logs -------------------------------------------------------------------------

@needs_pycan
def test_folder_holds_what_source_md_lists() -> None:
    names = {p.name for p in LOGS}
    assert len(names) == 21  # 14 ASC, 1 ASC.gz, 6 TRC
    assert {"test_CanMessage.asc", "test_CanMessage.asc.gz", "test_CanMessage.trc"} <= names


@needs_pycan
@pytest.mark.parametrize("path", LOGS, ids=[p.name for p in LOGS])
def test_log_reads_like_python_can(path: Path) -> None:
    fmt = detect_format(path)
    assert fmt == ("trc" if path.name.endswith(".trc") else "asc")
    got, report = read(path, fmt)
    data, n_err, n_rtr = python_can(path)
    assert got.position_unit == "line"
    assert got.equals(from_messages(data, got.position, "line"))
    np.testing.assert_array_equal(got.channel, [m.channel for m in data])
    assert report.rejected.get("error_frame", 0) == n_err
    assert report.rejected.get("remote_frame", 0) == n_rtr
    assert set(report.rejected) <= {"error_frame", "remote_frame"}, report.rejected
    assert np.all(np.diff(got.position) > 0)


SOURCE_COUNTS = {  # python-can LogReader counts from SOURCE.md: (n, error frames, remote frames)
    "issue_1256.asc": (1457, 0, 0), "issue_1299.asc": (4, 0, 0), "logfile.asc": (20, 4, 4),
    "logfile_errorframes.asc": (12, 3, 2), "test_CanErrorFrames.asc": (4, 4, 0),
    "test_CanRemoteMessage.asc": (3, 0, 3), "test_CanMessage_V2_1.trc": (11, 0, 1),
    "test_CanMessage_V1_0_BUS1.trc": (11, 0, 1),
}


@needs_pycan
@pytest.mark.parametrize("name", sorted(SOURCE_COUNTS))
def test_counts_match_source_md(name: str) -> None:
    n, n_err, n_rtr = SOURCE_COUNTS[name]
    path = PYCAN / name
    got, report = read(path, "trc" if name.endswith(".trc") else "asc")
    assert len(got) + report.rejected["error_frame"] + report.rejected["remote_frame"] == n
    assert (report.rejected["error_frame"], report.rejected["remote_frame"]) == (n_err, n_rtr)


@needs_pycan
def test_logged_events_are_reported_not_rejected() -> None:
    got, report = read(PYCAN / "logfile.asc", "asc")
    # chip status, bus statistics and J1939 TP lines: 11 events, no data lost
    assert any("11 logged event line(s)" in w and "first at line 8" in w
               for w in report.warnings)
    assert len(got) == 12


@pytest.fixture
def tz(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[str], None]]:
    """Set the process time zone (python-can reads ASC dates in local time); restored after."""

    def set_tz(name: str) -> None:
        monkeypatch.setenv("TZ", name)
        time.tzset()

    yield set_tz
    monkeypatch.undo()
    time.tzset()


@needs_pycan
def test_asc_times_are_absolute_from_the_trigger_block_date(tz) -> None:
    """Every real ASC carries a date python-can parses (the "us_locale" one too).

    So the times are absolute, with no warning about dates.
    """
    tz("UTC")
    start = datetime(2017, 9, 30, 15, 6, 13, 191000, tzinfo=UTC).timestamp()
    for name in ("single_frame.asc", "single_frame_us_locale.asc"):
        got, report = read(PYCAN / name, "asc")
        assert got.timestamp_s.tolist() == [start], name  # "Begin Triggerblock ... 15:06:13.191"
        assert not any("date" in w for w in report.warnings), report.warnings
    for path in LOGS:
        if path.name.endswith(".trc"):
            continue
        got, report = read(path, "asc")
        assert np.all(got.timestamp_s > 1.4e9), path.name  # 2014 onwards
        assert not any("date" in w for w in report.warnings), (path.name, report.warnings)


@needs_pycan
def test_same_frames_across_asc_gz_and_trc(tz) -> None:
    asc_path = PYCAN / "test_CanMessage.asc"
    gz_path = PYCAN / "test_CanMessage.asc.gz"
    trc_path = PYCAN / "test_CanMessage.trc"
    assert [detect_format(p) for p in (asc_path, gz_path, trc_path)] == ["asc", "asc", "trc"]
    # Both formats carry the start: the ASC its "Begin Triggerblock Sat Sep 30 10:06:13.191 PM
    # 2017" (which wins over its "date Sam Sep 30 15:06:13.191 2017" header line), the TRC
    # ";$STARTTIME=43008.920986006946" (days since 1899-12-30, 22:06:13.191). python-can reads
    # the ASC date in local time but the TRC start as UTC (TRCReader: datetime(1899, 12, 30,
    # tzinfo=UTC) + days), so the two agree only in a UTC process: pinned here.
    tz("UTC")
    a, report = read(asc_path, "asc")
    g, _ = read(gz_path, "asc")
    t, _ = read(trc_path, "trc")
    assert report.warnings == []
    assert a.equals(g, compare_position=True)  # gzip changes nothing
    np.testing.assert_array_equal(a.channel, g.channel)
    # ids, flags, payloads exactly; absolute times within 1 µs (ASC has µs, TRC 3 decimals of
    # ms), and both exactly python-can's arithmetic (start + offset)
    assert len(a) == len(t) == 2
    for field in ("arbitration_id", "is_extended", "is_fd", "length"):
        np.testing.assert_array_equal(getattr(a, field), getattr(t, field), err_msg=field)
    np.testing.assert_array_equal(a.data[:, :8], t.data[:, :8])
    np.testing.assert_allclose(a.timestamp_s, t.timestamp_s, rtol=0, atol=1e-6)
    start = datetime(2017, 9, 30, 22, 6, 13, 191000, tzinfo=UTC).timestamp()
    assert a.timestamp_s.tolist() == [start + 2.501, start + 17.876708]
    # python-can numbers ASC channels from 0 (file channel - 1) but TRC ones as written
    np.testing.assert_array_equal(a.channel + 1, t.channel)
    # In any other zone the ASC moves and the TRC does not; times relative to the first
    # frame still agree (the comparison that holds whatever the reading machine's zone).
    tz("ZZZ-02")  # POSIX TZ: two hours east of UTC
    a2, _ = read(asc_path, "asc")
    t2, _ = read(trc_path, "trc")
    np.testing.assert_array_equal(a.timestamp_s - a2.timestamp_s, 7200.0)
    assert t2.equals(t)
    np.testing.assert_allclose(a2.timestamp_s - a2.timestamp_s[0],
                               t2.timestamp_s - t2.timestamp_s[0], rtol=0, atol=1e-6)


@needs_pycan
def test_blf_twin_via_python_can_and_rigtools() -> None:
    """The BLF "twin" holds other frames; rigtools' BLF reader must equal python-can's.

    ``test_CanMessage.blf`` is python-can's BLF fixture for the same test, but it does not
    hold the ASC/TRC frames (it holds two frames of id 0x4444444 with DLC 51, channel 4368).
    It is compared with python-can's BLFReader, the reference, and with rigtools' own BLF
    reader.
    """
    path = PYCAN / "test_CanMessage.blf"
    with can.BLFReader(str(path)) as r:
        ref = [m for m in r if not m.is_error_frame and not m.is_remote_frame]
    ref_batch = from_messages(ref, range(len(ref)), "byte")
    a, _ = read(PYCAN / "test_CanMessage.asc", "asc")
    assert ref_batch.arbitration_id.tolist() == [0x4444444, 0x4444444]
    assert not set(ref_batch.arbitration_id.tolist()) & set(a.arbitration_id.tolist())
    got, _ = read(path, "blf")
    assert got.equals(ref_batch)


@needs_pycan
@pytest.mark.parametrize("name", ["test_CanFdMessage64.asc", "logfile_can_fd.asc",
                                  "logfile_vector_fd.asc", "test_CanFdMessage.asc"])
def test_fd_frames_not_truncated(name: str) -> None:
    got, _ = read(PYCAN / name, "asc")
    data, _, _ = python_can(PYCAN / name)
    assert got.is_fd.all()
    assert got.length.tolist() == [len(m.data) for m in data]
    for i, m in enumerate(data):
        assert bytes(got.data[i, : got.length[i]]) == bytes(m.data)
    if name == "test_CanFdMessage64.asc":
        assert got.length.tolist() == [64, 64]
        assert got.data.shape[1] == 64


# --- cantools DBCs ---------------------------------------------------------------------------

@needs_dbcs
@pytest.mark.parametrize("path", DBC_FILES, ids=[p.name for p in DBC_FILES])
def test_dbc_loads_or_raises_dbc_error(path: Path) -> None:
    if path.name in BAD_DBCS:
        with pytest.raises(DbcError, match=rf"{path.name.replace('.', chr(92) + '.')}: expected a "
                                           r"valid DBC file"):
            load_dbc(path)
    else:
        db = load_dbc(path)
        assert isinstance(db, cantools.database.can.Database)


@needs_dbcs
def test_dbc_folder_split_matches_source_md() -> None:
    loaded = refused = 0
    for path in DBC_FILES:
        try:
            load_dbc(path)
        except DbcError as exc:
            assert path.name in str(exc)
            refused += 1
        else:
            loaded += 1
    assert (loaded, refused) == (79, 4)


def _put_raw(row: bytearray, signal: object, value: int) -> None:
    """Write a raw signal value into a payload (independent of rigtools.ingest.can.dbc).

    Little endian: the value's bits sit at ``start .. start+length-1`` of the payload read as
    one little-endian integer. Big endian: ``start`` is the MSB in DBC sawtooth numbering;
    its MSB-first position is ``8*(start//8) + 7 - start%8`` in the payload read as one
    big-endian integer. The tests check every write through cantools.
    """
    n, start, length = len(row), int(signal.start), int(signal.length)  # type: ignore[attr-defined]
    big = signal.byte_order == "big_endian"  # type: ignore[attr-defined]
    x = int.from_bytes(row, "big" if big else "little")
    shift = 8 * n - ((start // 8) * 8 + 7 - start % 8 + length) if big else start
    mask = ((1 << length) - 1) << shift
    x = (x & ~mask) | (value << shift)
    row[:] = x.to_bytes(n, "big" if big else "little")


def _valid_multiplexers(row: bytearray, message: object, rng: np.random.Generator) -> None:
    """Give every multiplexer reachable from the top a value some signal is defined for."""
    signals = message.signals  # type: ignore[attr-defined]

    def walk(mux: object) -> None:
        children = [s for s in signals
                    if s.multiplexer_signal == mux.name and s.multiplexer_ids]  # type: ignore[attr-defined]
        ids = sorted({i for s in children for i in s.multiplexer_ids})
        if not ids:
            return
        value = int(rng.choice(ids))
        _put_raw(row, mux, value)
        for s in children:
            if s.is_multiplexer and value in s.multiplexer_ids:
                walk(s)

    for s in signals:
        if s.is_multiplexer and not s.multiplexer_ids:
            walk(s)


def _payloads(message: object, rng: np.random.Generator, n: int = 300) -> np.ndarray:
    length = int(message.length)  # type: ignore[attr-defined]
    data = rng.integers(0, 256, (n, length), dtype=np.uint8)
    data[0] = 0
    data[1] = 0xFF
    if message.is_multiplexed():  # type: ignore[attr-defined]
        for i in range(n):
            row = bytearray(data[i].tobytes())
            _valid_multiplexers(row, message, rng)
            data[i] = np.frombuffer(bytes(row), np.uint8)
    return data


def _same(want: float, got: float) -> bool:
    return want == got or (np.isnan(want) and np.isnan(got))


LOADABLE = [p for p in DBC_FILES if p.name not in BAD_DBCS]


@needs_dbcs
@pytest.mark.parametrize("path", LOADABLE, ids=[p.name for p in LOADABLE])
def test_decode_signal_equals_cantools(path: Path) -> None:
    db = load_dbc(path)
    rng = np.random.default_rng(sum(path.name.encode()))  # seeded per file
    failures: list[str] = []
    for message in db.messages:
        if message.length == 0 or not message.signals:
            continue
        data = _payloads(message, rng)
        ext = bool(message.is_extended_frame)
        try:
            unique = db.get_message_by_frame_id(message.frame_id, ext) is message
        except KeyError:
            unique = False
        decoded = []
        for row in data:
            if unique:
                decoded.append(db.decode_message(message.frame_id, row.tobytes(),
                                                 decode_choices=False, scaling=True,
                                                 force_extended_id=ext))
            else:  # several messages share the id: ask the message itself (what
                # decode_message dispatches to)
                decoded.append(message.decode(row.tobytes(), decode_choices=False, scaling=True))
        for signal in message.signals:
            with np.errstate(invalid="ignore"):  # float32 NaN payloads widened to float64
                got = decode_signal(data, signal)
            mask = multiplex_mask(data, message, signal)
            present = np.array([signal.name in d for d in decoded])
            where = np.ones(len(data), bool) if mask is None else mask
            if not np.array_equal(where, present):
                failures.append(f"{message.name}.{signal.name}: multiplex_mask selects "
                                f"{int(where.sum())} rows, cantools returns {int(present.sum())}")
            if not present.any():
                failures.append(f"{message.name}.{signal.name}: never present in {len(data)} "
                                "payloads")
            for i in np.flatnonzero(present):
                want = float(decoded[i][signal.name])
                if not _same(want, float(got[i])):
                    failures.append(f"{message.name}.{signal.name} payload "
                                    f"{data[i].tobytes().hex()}: cantools "
                                    f"{decoded[i][signal.name]!r}, rigtools {got[i]!r}")
                    break
    assert not failures, f"{path.name}:\n" + "\n".join(failures)
