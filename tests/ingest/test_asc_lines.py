"""The vectorised parsers of the CAN logs against their slow paths, on intact and damaged files.

* ASC: lines :mod:`rigtools.ingest.can.asc_lines` parses are exactly the data frames
  python-can's ``ASCReader`` makes of them (line by line, and whole files read with the fast
  parser switched off: same frames, positions and report);
* candump: the lines of the most common length parsed as one matrix give what the general
  path gives;
* the channels of one CAN message unwrapped once (one timeline for all) equal each channel
  read alone.

The files are small recordings written by python-can's writers (error, remote, FD and
extended frames, unknown identifiers, two buses) and every damage of
``tests/make_damaged_corpus.py`` applied to them.
"""

from __future__ import annotations

import io
from pathlib import Path

import can
import numpy as np
import pytest
from imu_can_layout import imu_dbc, imu_mapping
from make_damaged_corpus import damages_for

from rigtools.errors import RigtoolsError
from rigtools.ingest import read
from rigtools.ingest.can import asc, candump
from rigtools.ingest.can.asc_lines import FrameLines, parse_frame_lines
from rigtools.ingest.can.frames import concat
from rigtools.ingest.recording import IngestReport

HEADER = "date Sat Sep 30 15:06:13.191 2017\nbase hex  timestamps absolute\n" \
         "internal events logged\nBegin Triggerblock Sat Sep 30 15:06:13.191 2017\n"

DBC = imu_dbc()


def _mapping(axes: str) -> str:
    return imu_mapping({a: f"accel_{a.lower()}" for a in axes}, slow=[("oil", "Rig", "OilTemp")])


def _messages(n: int = 1500) -> list[can.Message]:
    """IMU frames at 25.6 kHz and a slow message among others, on two buses.

    Unknown identifiers, extended, FD, error and remote frames mixed in.
    """
    gen = np.random.default_rng(3)
    out = []
    t0 = 1_506_776_773.5
    for i in range(n):
        t = t0 + i / 25_600
        payload = (i % 65536).to_bytes(2, "little") + gen.integers(0, 256, 6,
                                                                   np.uint8).tobytes()
        out.append(can.Message(timestamp=t, arbitration_id=0x120, is_extended_id=False,
                               data=payload, channel=0))
        if i % 97 == 3:
            out.append(can.Message(timestamp=t + 1e-6, arbitration_id=0x300,
                                   is_extended_id=False, data=b"\x10\x32\x00\x00", channel=0))
        if i % 31 == 7:
            out.append(can.Message(timestamp=t + 2e-6, arbitration_id=int(gen.integers(0x400,
                                                                                       0x410)),
                                   is_extended_id=False,
                                   data=bytes(range(int(gen.integers(0, 9)))), channel=1))
        if i % 211 == 11:
            out.append(can.Message(timestamp=t + 3e-6, arbitration_id=0x18FF1234,
                                   is_extended_id=True, data=b"\x01\x02\x03", channel=0))
        if i % 401 == 13:
            out.append(can.Message(timestamp=t + 4e-6, arbitration_id=0x321, is_fd=True,
                                   data=bytes(12), channel=0))
        if i % 307 == 17:
            out.append(can.Message(timestamp=t + 5e-6, is_error_frame=True, channel=0))
        if i % 293 == 19:
            out.append(can.Message(timestamp=t + 6e-6, arbitration_id=0x200,
                                   is_remote_frame=True, dlc=8, channel=0))
    return out


@pytest.fixture(scope="module")
def intact(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The recording written as ASC and candump by python-can, with its DBC and mappings."""
    folder = tmp_path_factory.mktemp("fast_paths")
    msgs = _messages()
    paths = {"asc": folder / "intact.asc", "log": folder / "intact.log"}
    for fmt, writer in (("asc", can.ASCWriter), ("log", can.CanutilsLogWriter)):
        with writer(str(paths[fmt])) as w:
            for m in msgs:
                w.on_message_received(m)
    (folder / "m.dbc").write_text(DBC)
    (folder / "xyz.toml").write_text(_mapping("XYZ"))
    for a in "XYZ":
        (folder / f"{a}.toml").write_text(_mapping(a))
    return {**paths, "dbc": folder / "m.dbc", "folder": folder}


def _damaged(intact: dict[str, Path], fmt: str) -> list[tuple[str, Path]]:
    src = intact[fmt]
    data = src.read_bytes()
    out = [("intact", src)]
    for name, damage in damages_for(src, data).items():
        got = damage(data)
        if got is None:
            continue
        p = intact["folder"] / f"{src.stem}__{name}{src.suffix}"
        p.write_bytes(got)
        out.append((name, p))
    return out


def _frames(fmt: str, path: Path) -> tuple[object, dict[str, object]]:
    """All frames and the report of one file, or the error raised."""
    module = asc if fmt == "asc" else candump
    report = IngestReport()
    try:
        with open(path, "rb") as f:
            batches = list(module.iter_batches(f, str(path), report))
    except RigtoolsError as exc:
        return repr(exc), {}
    return concat(batches), report.to_dict()


def _same(a: object, b: object) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return a.equals(b, compare_position=True) and np.array_equal(  # type: ignore[attr-defined]
        a.channel, b.channel)  # type: ignore[attr-defined]


def _no_fast_lines(block: bytes) -> FrameLines:
    got = parse_frame_lines(block)
    return FrameLines(got.line_end, np.zeros_like(got.plain), got.mantissa, got.scale,
                      got.channel, got.can_id, got.extended, got.length, got.data)


def test_asc_fast_lines_equal_python_can_on_damaged_files(intact, monkeypatch) -> None:
    """Same frames, line numbers and report with and without the vectorised line parser."""
    files = _damaged(intact, "asc")
    fast = {name: _frames("asc", p) for name, p in files}
    monkeypatch.setattr(asc, "parse_frame_lines", _no_fast_lines)
    for name, p in files:
        slow = _frames("asc", p)
        assert _same(fast[name][0], slow[0]), name
        assert fast[name][1] == slow[1], name
    assert len(fast["intact"][0]) > 1500  # type: ignore[arg-type]


def test_candump_matrix_path_equals_general_path_on_damaged_files(intact, monkeypatch) -> None:
    """Same frames, line numbers and report with and without the most-common-length path."""
    files = _damaged(intact, "log")
    fast = {name: _frames("log", p) for name, p in files}
    monkeypatch.setattr(candump, "_DOMINANT_MIN_LINES", 1 << 62)
    for name, p in files:
        slow = _frames("log", p)
        assert _same(fast[name][0], slow[0]), name
        assert fast[name][1] == slow[1], name


#: Damages that reach the sample counters (frames repeated, lost, reordered, cut).
COUNTER_DAMAGES = {"intact", "lines_duplicated", "lines_dropped", "lines_shuffled",
                   "line_cut_in_middle", "garbage_lines", "cut_at_1"}


@pytest.mark.parametrize("fmt", ["asc", "log"])
def test_shared_timeline_equals_each_channel_alone(intact, fmt) -> None:
    """Three channels of one message (one counter unwrapped once) read as each alone."""
    dbc = intact["dbc"]
    for name, path in _damaged(intact, fmt):
        if name not in COUNTER_DAMAGES:
            continue
        try:
            together = read(path, dbc=dbc, mapping=intact["folder"] / "xyz.toml")
        except RigtoolsError:
            continue
        for axis in "XYZ":
            alone = read(path, dbc=dbc, mapping=intact["folder"] / f"{axis}.toml")
            a, b = together.channels[f"accel_{axis.lower()}"], alone.channels[
                f"accel_{axis.lower()}"]
            assert a.first_index == b.first_index, name
            np.testing.assert_array_equal(a.values, b.values, err_msg=name)
            np.testing.assert_array_equal(a.valid, b.valid, err_msg=name)
            assert together.report.timebase[f"accel_{axis.lower()}"] == \
                alone.report.timebase[f"accel_{axis.lower()}"], name


LINES = [
    "   0.015991 1  120             Rx   d 8 00 01 02 03 04 05 06 07",
    "   0.015991 1  120             Rx   d 8 00 01 02 03 04 05 06 07  Length = 228000 "
    "BitCount = 118 ID = 288",
    "\t0.5\t2\t1ABCDEFx\tTx\td\t3\tAA\tbb\tCc",
    "0.000001 0 7FF Rx d 0",
    "12345678901.1234 99999 0 Rx d 1 FF",
    "1.0 1 120 rx d 2 00 01",
    "1.0 1 800 Rx d 1 00",  # standard id above 11 bits: python-can reads it, rigtools counts
    "1.0 1 20000000x Rx d 1 00",
    "1.0 1 120 Rx d 9 00 01 02 03 04 05 06 07 08",
    "1.0 1 120 Rx d 8 00 01 02 03",
    "1.0 1 120 Rx d 2 0 01",
    "1.0 1 120 Rx d 2 001 01",
    "1.0 1 120 Rx r 8",
    "1.0 1 120 Rx d 2 0G 01",
    "1.0 1 12G Rx d 2 00 01",
    "1..0 1 120 Rx d 2 00 01",
    "1. 1 120 Rx d 2 00 01",
    "1.0 1 120 Rxx d 2 00 01",
    "1.0 1 0x120 Rx d 2 00 01",
    "1.0 CANFD 1 Rx 120 1 0 8 8 00 01 02 03 04 05 06 07 0 0 0 0 0 0",
    "1.0 1 ErrorFrame",
    "1.0 1 120 Rx d 2 00 01 \xe9",
    "1.0 1 120 Rx D 2 00 01",
    "1.0 1 120 Rx d 2 00 01\x0b",
    "1.000000000000000 1 120 Rx d 2 00 01",
]


def _python_can_line(line: str) -> can.Message | None:
    text = HEADER + line + "\n"
    try:
        got = list(can.ASCReader(io.StringIO(text), relative_timestamp=True))
    except (ValueError, IndexError):
        return None
    return got[0] if len(got) == 1 else None


@pytest.mark.parametrize("line", LINES)
def test_plain_lines_are_python_cans_data_frames(line: str) -> None:
    """A line parsed without python-can is a data frame python-can reads the same way."""
    got = parse_frame_lines(line.encode("utf-8") + b"\n")
    m = _python_can_line(line)
    if not got.plain[0]:
        return
    assert m is not None and not m.is_error_frame and not m.is_remote_frame and not m.is_fd
    b = got.batch(0, 1, 1, 0.0)
    assert b.timestamp_s[0] == m.timestamp
    assert int(b.arbitration_id[0]) == m.arbitration_id
    assert bool(b.is_extended[0]) == m.is_extended_id
    assert bytes(b.data[0, : b.length[0]]) == bytes(m.data)
    assert int(b.channel[0]) == (m.channel if m.channel <= 32767 else -1)
    assert m.arbitration_id <= (0x1FFFFFFF if m.is_extended_id else 0x7FF)


def test_plain_line_examples_are_recognised() -> None:
    """The first lines of :data:`LINES` are plain; the damaged ones are not."""
    got = parse_frame_lines("".join(f"{s}\n" for s in LINES).encode("utf-8"))
    assert got.plain[:6].tolist() == [True] * 6
    assert not got.plain[6:].any()


def test_matrix_path_equals_token_path() -> None:
    """Lines of one length parsed as a matrix, damaged lines of that length among them."""
    good = "   0.015991 1  120             Rx   d 8 00 01 02 03 04 05 06 07"
    bad = [good.replace("01 02", "01 0G"), good.replace("0.015991", "0.0159.1"),
           good.replace(" d ", " D "), good.replace("120 ", "1G0 "), good.replace("Rx", "Rz"),
           good.replace("d 8", "d 9"), good.replace("1  120", "1 8120")]
    lines = []
    for i in range(200):
        lines.append(good.replace("0.015991", f"0.{i:06d}"))
        if i % 20 == 3:
            lines.append(bad[(i // 20) % len(bad)])
    block = "".join(f"{s}\n" for s in lines).encode()
    got = parse_frame_lines(block)
    one_by_one = [parse_frame_lines(f"{s}\n".encode()) for s in lines]
    assert got.plain.tolist() == [bool(x.plain[0]) for x in one_by_one]
    assert got.plain.sum() == 200
    for i in np.flatnonzero(got.plain).tolist():
        assert got.batch(i, i + 1, 1, 0.0).equals(one_by_one[i].batch(0, 1, 1, 0.0))
