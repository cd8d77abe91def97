"""BLF reader: frame for frame against python-can's BLFReader, and every kind of damage counted.

Hostile files are built in code (``_blf``, ``_obj``, ``_container``); the real BLF files of
python-can's test suite are read from ``../shared/realdata/python-can`` and skipped when that
folder is absent.
"""

from __future__ import annotations

import io
import struct
import tempfile
import zlib
from pathlib import Path

import can
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from realdata_path import REALDATA

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can import blf
from rigtools.ingest.can.frames import CanFrameBatch, concat
from rigtools.ingest.recording import IngestReport

PYCAN_DATA = REALDATA / "python-can"

FD_LENGTHS = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64]


# -- helpers -----------------------------------------------------------------------------------


def read_blf(data: bytes | Path, **kwargs) -> tuple[CanFrameBatch, IngestReport]:
    """All frames of a BLF file (bytes or path) through rigtools, and the report."""
    raw = data.read_bytes() if isinstance(data, Path) else data
    report = IngestReport()
    batches = list(blf.iter_batches(io.BytesIO(raw), "test.blf", report, **kwargs))
    for b in batches:
        assert b.position_unit == "byte"
    return (concat(batches) if batches else CanFrameBatch.empty()), report


def pycan_messages(data: bytes | Path) -> list[can.Message]:
    """Every message python-can's BLFReader yields."""
    raw = data.read_bytes() if isinstance(data, Path) else data
    return list(can.BLFReader(io.BytesIO(raw)))


def data_frames(msgs: list[can.Message]) -> list[can.Message]:
    return [m for m in msgs if not m.is_error_frame and not m.is_remote_frame]


def assert_same_frames(batch: CanFrameBatch, msgs: list[can.Message]) -> None:
    """Timestamp (bit for bit), id, extended, FD, length, payload and channel agree."""
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
    assert batch.channel.tolist() == [m.channel for m in msgs]


def _obj(otype: int, body: bytes, *, ts: int = 0, flags: int = 2, hv: int = 1,
         pad: int | None = None) -> bytes:
    """One BLF object with a v1 or v2 header; padding ``size % 4`` as python-can writes it."""
    if hv == 1:
        rest = struct.pack("<LHHQ", flags, 0, 0, ts)
    else:
        rest = struct.pack("<LBxHQ8x", flags, 0, 0, ts)
    hs = 16 + len(rest)
    size = hs + len(body)
    out = struct.pack("<4sHHLL", b"LOBJ", hs, hv, size, otype) + rest + body
    return out + b"\x00" * (len(body) % 4 if pad is None else pad)


def _can(can_id: int, data: bytes, *, ch: int = 1, flags: int = 0, dlc: int | None = None,
         ext: bool = False, otype: int = 1, **kw) -> bytes:
    body = struct.pack("<HBBL8s", ch, flags, len(data) if dlc is None else dlc,
                       can_id | (0x80000000 if ext else 0), data)
    return _obj(otype, body, **kw)


def _fd(can_id: int, data: bytes, *, ch: int = 1, edl: bool = True, flags: int = 0,
        **kw) -> bytes:
    dlc = FD_LENGTHS.index(len(data))
    body = struct.pack("<HBBLLBBB5x64s", ch, flags, dlc, can_id, 0, 0, 1 if edl else 0,
                       len(data), data)
    return _obj(100, body, **kw)


def _fd64(can_id: int, data: bytes, *, ch: int = 1, valid: int | None = None,
          fdflags: int = 0x1000, **kw) -> bytes:
    dlc = FD_LENGTHS.index(len(data)) if valid is None else 15
    body = struct.pack("<BBBBLLLLLLLHBBL", ch, dlc, len(data) if valid is None else valid, 0,
                       can_id, 0, fdflags, 0, 0, 0, 0, 0, 0, 0, 0) + data
    return _obj(101, body, **kw)


def _error_ext(**kw) -> bytes:
    body = struct.pack("<HHLBBBxLLH2x8s", 1, 0, 0, 0, 0, 102, 0, 0x19999999, 0, b"\x01" * 8)
    return _obj(73, body, **kw)


def _container(data: bytes, *, method: int = 2, claimed: int | None = None) -> bytes:
    payload = zlib.compress(data) if method == 2 else data
    size = 32 + len(payload)
    head = struct.pack("<4sHHLL", b"LOBJ", 16, 1, size, 10)
    return head + struct.pack("<H6xL4x", method, len(data) if claimed is None else claimed) + (
        payload + b"\x00" * (size % 4))


def _header(file_size: int = 0, start: tuple[int, ...] = (2024, 3, 5, 14, 9, 26, 53, 589)) -> bytes:
    h = struct.pack("<4sLBBBBBBBBQQLL8H8H", b"LOGG", 144, 5, 0, 0, 0, 2, 6, 8, 1, file_size, 0,
                    0, 0, *start, *start)
    return h + b"\x00" * (144 - len(h))


def _blf(stream: bytes, *, chunk: int = 4096, method: int = 2, with_size: bool = True) -> bytes:
    """A BLF file whose object ``stream`` is cut into containers of ``chunk`` bytes."""
    body = b"".join(_container(stream[i : i + chunk], method=method)
                    for i in range(0, len(stream), chunk))
    return _header(144 + len(body) if with_size else 0) + body


def _python_can_file(msgs: list[can.Message], **writer_kwargs) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "f.blf"
        with can.BLFWriter(str(path), **writer_kwargs) as w:
            for m in msgs:
                w.on_message_received(m)
        return path.read_bytes()


def _mixed_messages(n: int = 600, seed: int = 0) -> list[can.Message]:
    rng = np.random.default_rng(seed)
    out = []
    t = 1_700_000_000.25
    for i in range(n):
        t += float(rng.uniform(0, 2e-3))
        kind = rng.integers(0, 10)
        ext = bool(rng.integers(0, 2))
        cid = int(rng.integers(0, 1 << 29 if ext else 1 << 11))
        ch = int(rng.integers(0, 4))
        if kind == 0:
            out.append(can.Message(timestamp=t, is_error_frame=True, channel=ch))
        elif kind == 1:
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   is_remote_frame=True, dlc=int(rng.integers(0, 9)), channel=ch))
        elif kind < 4:
            n_bytes = int(rng.choice(FD_LENGTHS))
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   is_fd=True, bitrate_switch=bool(i % 2),
                                   data=rng.integers(0, 256, n_bytes, dtype=np.uint8).tobytes(),
                                   channel=ch))
        else:
            n_bytes = int(rng.integers(0, 9))
            out.append(can.Message(timestamp=t, arbitration_id=cid, is_extended_id=ext,
                                   data=rng.integers(0, 256, n_bytes, dtype=np.uint8).tobytes(),
                                   channel=ch, is_rx=bool(i % 3)))
    return out


# -- format detection and header ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("content", "match"),
    [
        (b"", "empty file"),
        (b"LOGX" + b"\x00" * 200, "LOGG"),
        (b"LOGG\x90\x00\x00\x00", "72-byte BLF file header"),
        (b"LOGG" + struct.pack("<L", 12) + b"\x00" * 100, "header size of 72..65536"),
    ],
)
def test_bad_header_is_refused_at_byte_0(content, match):
    with pytest.raises(RecordingFormatError, match=match) as info:
        read_blf(content)
    assert info.value.position == 0
    assert info.value.path == "test.blf"


def test_bad_header_error_survives_pickling():
    import pickle

    with pytest.raises(RecordingFormatError, match="LOGG") as info:
        read_blf(b"NOPE" * 40)
    back = pickle.loads(pickle.dumps(info.value))
    assert str(back) == str(info.value)


# -- equality with python-can ---------------------------------------------------------------------


REAL_FILES = {
    # file: (data frames, error frames, remote frames)
    "logfile.blf": (1, 1, 0),
    "issue_1905.blf": (22, 0, 0),
    "test_CanMessage.blf": (2, 0, 0),
    "test_CanMessage2.blf": (2, 0, 0),
    "test_CanFdMessage.blf": (2, 0, 0),
    "test_CanFdMessage64.blf": (0, 0, 2),
    "test_CanErrorFrameExt.blf": (0, 2, 0),
}


@pytest.mark.parametrize("name", sorted(REAL_FILES))
def test_real_files_match_python_can_frame_for_frame(name):
    path = PYCAN_DATA / name
    if not path.is_file():
        pytest.skip(f"third-party file {path} is absent")
    batch, report = read_blf(path)
    msgs = pycan_messages(path)
    assert_same_frames(batch, data_frames(msgs))
    n_data, n_err, n_rtr = REAL_FILES[name]
    assert len(batch) == n_data
    assert report.rejected["error_frame"] == n_err == sum(m.is_error_frame for m in msgs)
    assert report.rejected["remote_frame"] == n_rtr == sum(m.is_remote_frame for m in msgs)
    # Everything else in these files is another object type, counted by type, never lost.
    other = {k for k in report.rejected if k not in ("error_frame", "remote_frame")}
    assert all(k.startswith("blf_object_type_") for k in other), report.rejected


def test_real_file_quirks_are_decided_and_reported(realdata):
    """python-can's fixtures: classic DLC 51 kept as 8 bytes (warned), error DLC 102 counted."""
    batch, report = read_blf(PYCAN_DATA / "test_CanMessage.blf")
    assert batch.length.tolist() == [8, 8]
    assert [m.dlc for m in pycan_messages(PYCAN_DATA / "test_CanMessage.blf")] == [51, 51]
    assert any("DLC above 15" in w for w in report.warnings)
    assert batch.channel.tolist() == [4368, 4368]
    _, report = read_blf(PYCAN_DATA / "test_CanErrorFrameExt.blf")
    assert report.rejected["error_frame"] == 2
    assert report.first_position["error_frame"] == "byte 144"
    # issue 1905: valid_bytes 64 but 48 stored -> zero padded, as python-can and CANoe do
    batch, _ = read_blf(PYCAN_DATA / "issue_1905.blf")
    assert (batch.data[:, :48] == 0xFF).all() and (batch.data[:, 48:] == 0).all()


@pytest.mark.parametrize(
    "writer_kwargs",
    [{}, {"compression_level": 0}, {"max_container_size": 300}, {"max_container_size": 4096},
     {"compression_level": 9, "max_container_size": 1000}],
    ids=["default", "uncompressed", "tiny-containers", "4k-containers", "level9"],
)
def test_python_can_written_files_match_frame_for_frame(writer_kwargs):
    msgs = _mixed_messages()
    raw = _python_can_file(msgs, **writer_kwargs)
    batch, report = read_blf(raw)
    ref = pycan_messages(raw)
    assert_same_frames(batch, data_frames(ref))
    assert report.rejected["error_frame"] == sum(m.is_error_frame for m in msgs)
    assert report.rejected["remote_frame"] == sum(m.is_remote_frame for m in msgs)
    assert set(report.rejected) <= {"error_frame", "remote_frame"}
    assert 0 < batch.is_fd.sum() < len(batch)
    assert batch.data.shape[1] == 64


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_any_python_can_file_matches_python_can(data):
    n = data.draw(st.integers(0, 80))
    seed = data.draw(st.integers(0, 2**31))
    container = data.draw(st.sampled_from([64, 100, 257, 1024, 128 * 1024]))
    level = data.draw(st.sampled_from([0, 1, -1]))
    msgs = _mixed_messages(n, seed)
    raw = _python_can_file(msgs, max_container_size=container, compression_level=level)
    batch, _ = read_blf(raw)
    assert_same_frames(batch, data_frames(pycan_messages(raw)))


def test_hand_built_objects_v2_headers_10us_ticks_and_padding_match_python_can():
    stream = b"".join([
        _can(0x100, b"\x01\x02", ts=123_456, flags=1),  # 10 µs ticks
        _can(0x101, b"\x03" * 8, ts=987_654_321_987, flags=2, hv=2),  # v2 header, 1 ns ticks
        _can(0x1ABCDEF, b"\x04" * 3, ext=True, ts=5, flags=0, otype=86),  # CAN_MESSAGE2
        _fd(0x7FF, bytes(range(12)), ts=7, hv=2),
        _fd(0x55, bytes(range(8)), edl=False, ts=8),  # FD object carrying a classic frame
        _fd64(0x66, bytes(range(20)), ts=9),
        _fd64(0x67, bytes(range(16)), valid=32, ts=10),  # valid > stored: zero padded
        _can(0x102, b"\x05" * 8, ts=11, pad=3),  # unusual padding: found within 8 bytes
        _can(0x103, b"\x06" * 8, ts=(1 << 60) + 1),  # beyond 2**53: Decimal path
    ])
    raw = _blf(stream, chunk=37)
    batch, report = read_blf(raw)
    assert_same_frames(batch, data_frames(pycan_messages(raw)))
    assert len(batch) == 9 and report.n_rejected == 0


@pytest.mark.parametrize("seed", range(3))
def test_plain_frames_decoded_by_the_walk_equal_the_numpy_decoding(seed, monkeypatch):
    """Every limit of a *plain* frame (decoded inside the compiled walk) on either side.

    Classic objects of both types and header versions, 10 µs and 1 ns ticks, ticks on both
    sides of 2**53, channel numbers 0, 1, 32768 and 32769 (the last set to -1 with a
    warning), DLC 0-8, 9-15 and 16-255 (a warning), remote frames, objects one byte short of
    their record (corrupt), CAN FD and error objects between them, containers of 37 bytes
    to 4 kB. The frames, positions and report equal those of the compiled walk that leaves
    every frame to the NumPy decoding of its type; without the short objects (which
    python-can reads past), the frames equal python-can's, channel 32769 aside.
    """
    from rigtools.ingest.can import blf_objects

    rng = np.random.default_rng(seed)
    objs, short = [], []
    for i in range(2500):
        kind = rng.integers(0, 20)
        ts = int(rng.choice([i * 10_007, (1 << 53) - 1 - i, (1 << 53) + i]))
        short.append(kind == 5)
        if kind == 0:
            objs.append(_fd(0x200 + i % 7, bytes(rng.integers(0, 256, 12, dtype=np.uint8)),
                            ts=i))
            continue
        if kind == 1:
            objs.append(_error_ext(ts=i))
            continue
        dlc = int(rng.choice([0, 3, 8, 9, 15, 16, 255])) if kind == 2 else int(
            rng.integers(0, 9))
        ch = int(rng.choice([0, 1, 2, 32768, 32769])) if kind == 3 else 1
        flags = 0x80 if kind == 4 else int(rng.integers(0, 0x80))
        body = struct.pack("<HBBL8s", ch, flags, dlc, int(rng.integers(0, 1 << 32)),
                           bytes(rng.integers(0, 256, 8, dtype=np.uint8)))
        if kind == 5:
            body = body[:-1]  # one byte short of the record: corrupt_object
        objs.append(_obj(int(rng.choice([1, 86])), body, ts=ts, flags=int(rng.choice([1, 2])),
                         hv=int(rng.integers(1, 3))))
    chunk = int(rng.choice([37, 500, 4096]))
    raw = _blf(b"".join(objs), chunk=chunk)
    fast, fast_report = read_blf(raw)
    with monkeypatch.context() as m:
        m.setattr(blf_objects, "walk_sound_objects", _compiled_walk_only)
        slow, slow_report = read_blf(raw)
    assert fast.equals(slow, compare_position=True)
    assert np.array_equal(fast.channel, slow.channel)
    assert fast_report.to_dict() == slow_report.to_dict()
    assert {"remote_frame", "corrupt_object", "error_frame"} <= set(fast_report.rejected)
    assert any("DLC above 15" in w for w in fast_report.warnings)
    assert any("above 32768" in w for w in fast_report.warnings)

    sound = _blf(b"".join(o for o, cut in zip(objs, short, strict=True) if not cut),
                 chunk=chunk)
    batch, _ = read_blf(sound)
    msgs = data_frames(pycan_messages(sound))
    for msg in msgs:
        msg.channel = msg.channel if msg.channel <= 32767 else -1
    assert_same_frames(batch, msgs)


def test_runs_of_equal_objects_and_mixed_traffic_give_the_same_frames():
    """The arithmetic fast path (long runs) and the object-by-object walk agree."""
    rng = np.random.default_rng(5)
    objs = []
    for i in range(3000):
        if 1000 <= i < 1100 and i % 2:  # a stretch of alternating types
            objs.append(_fd(0x200 + i % 7, bytes(rng.integers(0, 256, 12, dtype=np.uint8)),
                            ts=i * 1000))
        elif i % 997 == 0:
            objs.append(_obj(96, b"\x00" * 44, ts=i * 1000))  # a marker: other object type
        else:
            objs.append(_can(0x100 + i % 4, bytes(rng.integers(0, 256, 8, dtype=np.uint8)),
                             ts=i * 1000))
    raw = _blf(b"".join(objs), chunk=128 * 1024)
    batch, report = read_blf(raw)
    assert_same_frames(batch, data_frames(pycan_messages(raw)))
    assert report.rejected == {"blf_object_type_96": 4}


def test_batches_respect_batch_frames_and_concatenate_to_the_whole():
    raw = _python_can_file(_mixed_messages(900, 3), max_container_size=2000)
    whole, _ = read_blf(raw)
    report = IngestReport()
    parts = list(blf.iter_batches(io.BytesIO(raw), "x.blf", report, batch_frames=50))
    assert all(len(p) <= 50 for p in parts) and len(parts) > 5
    assert concat(parts).equals(whole, compare_position=True)


def test_positions_are_container_offsets():
    stream = b"".join(_can(0x100, bytes([i]) * 8, ts=i) for i in range(200))
    raw = _blf(stream, chunk=1000)
    batch, _ = read_blf(raw)
    offsets = []
    pos = 144
    while pos < len(raw):
        offsets.append(pos)
        size = struct.unpack_from("<L", raw, pos + 8)[0]
        pos += size + size % 4
    # object k starts at byte 48 k of the stream; its container is the one holding that byte
    want = [offsets[(48 * k) // 1000] for k in range(200)]
    assert batch.position.tolist() == want


def test_the_file_is_read_container_by_container():
    """No read asks for more than one container (the file is never held whole)."""
    raw = _python_can_file(_mixed_messages(3000, 4), max_container_size=4096)

    class Spy(io.BytesIO):
        largest = 0

        def read(self, n=-1):
            Spy.largest = max(Spy.largest, len(raw) if n is None or n < 0 else n)
            return super().read(n)

    report = IngestReport()
    n = sum(len(b) for b in blf.iter_batches(Spy(raw), "x.blf", report))
    assert n > 0 and Spy.largest <= 4096 + 64


# -- frames that carry no data ------------------------------------------------------------------


def test_error_frames_and_remote_frames_are_counted_not_returned():
    stream = b"".join([
        _can(0x100, b"\x01" * 8, ts=1),
        _error_ext(ts=2),
        _can(0x101, b"", flags=0x80, dlc=4, ts=3),  # remote
        _obj(2, b"\x00" * 8, ts=4),  # CAN_ERROR
        _fd64(0x102, b"", fdflags=0x1010, ts=5),  # FD64 remote
        _obj(104, b"\x00" * 64, ts=6),  # CAN_FD_ERROR_64
        _can(0x103, b"\x02" * 8, ts=7),
    ])
    batch, report = read_blf(_blf(stream))
    assert batch.arbitration_id.tolist() == [0x100, 0x103]
    assert report.rejected == {"error_frame": 3, "remote_frame": 2}
    assert report.first_position["error_frame"] == "byte 144"


def test_timestamps_going_backwards_are_kept_as_logged():
    msgs = [can.Message(timestamp=t, arbitration_id=0x10, data=b"\x00" * 8)
            for t in (1_700_000_010.0, 1_700_000_012.5, 1_700_000_011.0, 1_700_000_013.0)]
    raw = _python_can_file(msgs)
    batch, report = read_blf(raw)
    assert_same_frames(batch, pycan_messages(raw))
    assert np.diff(batch.timestamp_s).tolist()[1] < 0
    assert report.n_rejected == 0


def test_fd64_claiming_more_than_64_bytes_is_counted():
    raw = _blf(_fd64(0x10, b"\x01" * 8, valid=100) + _can(0x11, b"\x02" * 8))
    batch, report = read_blf(raw)
    assert batch.arbitration_id.tolist() == [0x11]
    assert report.rejected == {"invalid_length": 1}


# -- damage --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def damaged_source():
    """A python-can file with many small containers, and the frames it holds."""
    msgs = [can.Message(timestamp=1_700_000_000 + i * 1e-4, arbitration_id=0x100 + i % 5,
                        data=struct.pack("<Q", i)) for i in range(1500)]
    raw = _python_can_file(msgs, max_container_size=2048)
    whole, report = read_blf(raw)
    assert report.n_rejected == 0 and len(whole) == 1500
    return raw, whole


def _container_offsets(raw: bytes) -> list[int]:
    out, pos = [], 144
    while pos + 16 <= len(raw):
        out.append(pos)
        size = struct.unpack_from("<L", raw, pos + 8)[0]
        pos += size + size % 4
    return out


def test_truncation_anywhere_returns_the_exact_prefix_and_counts_the_loss(damaged_source):
    raw, whole = damaged_source
    offsets = _container_offsets(raw)
    cuts = set(range(144, len(raw), 97)) | set(range(offsets[3] - 20, offsets[3] + 60))
    cuts |= {144, 145, 160, len(raw) - 1}
    previous = -1
    for cut in sorted(cuts):
        batch, report = read_blf(raw[:cut])
        n = len(batch)
        assert batch.equals(whole.take(np.arange(n)), compare_position=True), cut
        assert n >= previous, cut
        previous = n
        lost = {"truncated_container", "truncated_object"} & set(report.rejected)
        assert lost, (cut, report.rejected)
        assert set(report.rejected) <= {"truncated_container", "truncated_object"}
        where = int(report.first_position[sorted(lost)[0]].split()[1])
        assert 144 <= where <= cut
    # within the last container, python-can's own reader yields the same prefix
    cut = (offsets[-2] + offsets[-1]) // 2
    assert_same_frames(read_blf(raw[:cut])[0], pycan_messages(raw[:cut]))


def test_file_ending_inside_the_header_padding_counts_a_truncated_container(damaged_source):
    raw, _ = damaged_source
    batch, report = read_blf(raw[:100])
    assert len(batch) == 0 and report.rejected == {"truncated_container": 1}


def test_corrupt_zlib_in_one_container_loses_that_container_only(damaged_source):
    raw, whole = damaged_source
    offsets = _container_offsets(raw)
    bad = offsets[5]
    size = struct.unpack_from("<L", raw, bad + 8)[0]
    broken = bytearray(raw)
    broken[bad + 40 : bad + 48] = b"\xff" * 8  # inside the deflate stream
    batch, report = read_blf(bytes(broken))
    assert report.rejected["corrupt_container"] == 1
    assert report.first_position["corrupt_container"] == f"byte {bad}"
    # every frame outside the lost container is there, in order, unchanged (timestamps are
    # unique here); the lost ones are those of the container plus the one straddling into it
    kept = np.isin(whole.timestamp_s, batch.timestamp_s)
    assert batch.equals(whole.take(kept), compare_position=True)
    lost = np.flatnonzero(~kept)
    assert np.all(np.diff(lost) == 1)
    assert set(whole.position[lost].tolist()) <= {offsets[4], bad}
    assert bad not in batch.position
    assert 0 < lost.size <= size  # a handful of frames, never more than the container held
    assert report.rejected["truncated_object"] == 1  # the object straddling into it


def test_container_claiming_an_absurd_size_is_not_allocated():
    stream = b"".join(_can(0x100, bytes([i]) * 8, ts=i) for i in range(100))
    body = _container(stream[:2400], claimed=0xFFFFFFF0) + _container(stream[2400:])
    raw = _header(144 + len(body)) + body
    batch, report = read_blf(raw)
    assert len(batch) == 100 and report.n_rejected == 0
    assert any("claims 4294967280 uncompressed bytes" in w for w in report.warnings)


@pytest.mark.parametrize("error", [-1, -24, +1, +5000])
def test_a_container_claiming_the_wrong_uncompressed_size_is_read_whole(error):
    """The one-call inflate (libdeflate) needs the claimed size; a wrong claim falls back.

    A claim a few bytes short fails libdeflate, the streaming zlib path reads the container
    whole; a claim too large is only a buffer bound: python-can ignores the claim either way.
    """
    stream = b"".join(_can(0x100, bytes([i]) * 8, ts=i) for i in range(60))
    body = (_container(stream[:1200], claimed=1200 + error) + _container(stream[1200:]))
    raw = _header(144 + len(body)) + body
    batch, report = read_blf(raw)
    assert len(batch) == 60 and report.n_rejected == 0 and not report.warnings
    assert_same_frames(batch, data_frames(pycan_messages(raw)))


def test_zip_bomb_container_is_bounded_and_reading_goes_on():
    bomb = _container(b"\x00" * (8 << 20))  # inflates to 8 MiB
    good = _container(b"".join(_can(0x100, bytes([i]) * 8, ts=i) for i in range(10)))
    raw = _header() + bomb + good
    assert len(bomb) < 20_000
    batch, report = read_blf(raw, max_container_bytes=1 << 20)
    assert len(batch) == 10
    assert report.rejected == {"oversized_container": 1}
    assert report.first_position["oversized_container"] == "byte 144"


def test_zlib_stream_ending_early_keeps_the_complete_objects_of_its_container():
    """A deflate stream that stops short keeps the objects it inflated.

    The container's size field agrees (the file is not cut): the container is counted
    corrupt, with a warning, and every complete object before the break is kept in order.
    """
    objs = b"".join(_can(0x100, bytes([i]) * 8, ts=i) for i in range(40))
    payload = zlib.compress(objs)[:-40]  # the last deflate blocks and the checksum missing
    size = 32 + len(payload)
    cut = (struct.pack("<4sHHLL", b"LOBJ", 16, 1, size, 10)
           + struct.pack("<H6xL4x", 2, len(objs)) + payload + b"\x00" * (size % 4))
    after = _container(b"".join(_can(0x200, b"\x02" * 8, ts=50 + i) for i in range(3)))
    batch, report = read_blf(_header() + cut + after)
    ids = batch.arbitration_id.tolist()
    n_first = ids.count(0x100)
    assert 0 < n_first < 40 and ids == [0x100] * n_first + [0x200] * 3
    assert batch.data[:n_first, 0].tolist() == list(range(n_first))  # the first, in order
    assert report.rejected["corrupt_container"] == 1
    assert any("ends early" in w for w in report.warnings)


def test_absurd_compressed_container_size_resynchronises_on_the_next_container():
    first = _container(b"".join(_can(0x100, b"\x01" * 8, ts=i) for i in range(5)))
    second = _container(b"".join(_can(0x200, b"\x02" * 8, ts=i) for i in range(7)))
    broken = bytearray(first)
    broken[8:12] = struct.pack("<L", 0xFFFFFF00)
    raw = _header() + bytes(broken) + second
    batch, report = read_blf(raw, max_container_bytes=1 << 20)
    assert batch.arbitration_id.tolist() == [0x200] * 7
    assert report.rejected == {"corrupt_container": 1}


def test_garbage_between_containers_is_skipped_and_counted():
    a = _container(b"".join(_can(0x100, b"\x01" * 8, ts=i) for i in range(5)))
    b = _container(b"".join(_can(0x200, b"\x02" * 8, ts=i) for i in range(7)))
    raw = _header() + a + b"garbage!" * 50 + b
    batch, report = read_blf(raw)
    assert batch.arbitration_id.tolist() == [0x100] * 5 + [0x200] * 7
    assert report.rejected == {"corrupt_container": 1}


def test_corrupt_object_inside_a_container_resynchronises():
    objs = [_can(0x100 + i, bytes([i]) * 8, ts=i) for i in range(20)]
    broken = bytearray(objs[7])
    broken[8:12] = struct.pack("<L", 5)  # size smaller than a header
    stream = b"".join(objs[:7]) + bytes(broken) + b"".join(objs[8:])
    batch, report = read_blf(_blf(stream, chunk=200))
    assert batch.arbitration_id.tolist() == [0x100 + i for i in range(20) if i != 7]
    assert report.rejected == {"corrupt_object": 1}


def test_unknown_compression_method_is_counted():
    raw = _header() + _container(_can(0x1, b"\x00" * 8), method=2)[:16] + struct.pack(
        "<H6xL4x", 7, 48) + b"\x00" * 48
    fixed = bytearray(raw)
    fixed[144 + 8 : 144 + 12] = struct.pack("<L", 32 + 48)
    batch, report = read_blf(bytes(fixed))
    assert len(batch) == 0 and report.rejected == {"unknown_compression": 1}


def test_broken_gzip_wrapper_counts_the_loss(tmp_path, damaged_source):
    import gzip

    from rigtools.ingest.files import open_source

    raw, whole = damaged_source
    path = tmp_path / "f.blf.gz"
    data = gzip.compress(raw)
    path.write_bytes(data[: len(data) // 2])
    report = IngestReport()
    with open_source(path) as stream:
        batch = concat(list(blf.iter_batches(stream, str(path), report)))
    assert 0 < len(batch) < len(whole)
    assert batch.equals(whole.take(np.arange(len(batch))))
    assert report.rejected["truncated_container"] == 1


@pytest.mark.parametrize("extra", [1, 3, 4, 8])
def test_other_container_padding_is_tolerated_with_a_warning(extra):
    a = _container(b"".join(_can(0x100, b"\x01" * 8, ts=i) for i in range(5)))
    b = _container(b"".join(_can(0x200, b"\x02" * 8, ts=i) for i in range(7)))
    raw = _header() + a + b"\x00" * extra + b
    batch, report = read_blf(raw)
    assert batch.arbitration_id.tolist() == [0x100] * 5 + [0x200] * 7
    assert report.n_rejected == 0
    assert any("unexpected padding" in w for w in report.warnings)


def _no_compiled_walk(buf, pos, max_object, out, filled, *decoding):
    return 0, 0, pos


def _compiled_walk_only(buf, pos, max_object, out, filled, decode, *rest):
    from rigtools.ingest.can.blf_kernels import walk_sound_objects

    return walk_sound_objects(buf, pos, max_object, out, filled, False, *rest)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("slower", [_no_compiled_walk, _compiled_walk_only])
def test_compiled_walk_equals_the_python_walk_on_damaged_files(seed, slower, monkeypatch):
    """Same frames, positions and report with and without the compiled object walk.

    Every damage of the damaged-file corpus (truncations, flipped bytes, moved and repeated
    containers, lying sizes) applied to a python-can file of mixed traffic, small
    containers so that objects straddle them. Compared: the compiled walk decoding the plain
    frames on the way (as ``read`` does) against the Python walk alone, and against the
    compiled walk that leaves every frame to the NumPy decoding of its type.
    """
    from make_damaged_corpus import damages_for

    from rigtools.ingest.can import blf_objects

    intact = _python_can_file(_mixed_messages(900, seed), max_container_size=2000)
    files = {"intact": intact}
    for name, damage in damages_for(Path("x.blf"), intact).items():
        got = damage(intact)
        if got is not None and not got.startswith(b"\x1f\x8b"):  # gzip: the corpus test's
            files[name] = got
    assert len(files) > 10

    def frames(raw: bytes) -> tuple[object, dict]:
        try:
            batch, report = read_blf(raw)
        except RecordingFormatError as exc:
            return repr(exc), {}
        return batch, report.to_dict()

    fast = {name: frames(raw) for name, raw in files.items()}
    monkeypatch.setattr(blf_objects, "walk_sound_objects", slower)
    for name, raw in files.items():
        slow = frames(raw)
        if isinstance(slow[0], str):
            assert fast[name][0] == slow[0], name
            continue
        assert fast[name][0].equals(slow[0], compare_position=True), name
        assert np.array_equal(fast[name][0].channel, slow[0].channel), name
        assert fast[name][1] == slow[1], name
