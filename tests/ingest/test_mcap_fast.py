"""MCAP reader fast paths: each must give exactly what the plain path gives, damage included.

* the chunk read ahead in a worker thread (``PIPELINE_MIN_CHUNK_BYTES``) against the walk
  reading every chunk itself;
* runs of equal Message records, and patterns of channels taking turns, read with array
  operations (``_RUN_MIN``) against the record by record walk;
* one-shot zstd decompression against the bounded streaming decompression;
* the protobuf AccelBatch decoding of messages sharing one byte layout against message by
  message decoding and the protobuf library.
"""

from __future__ import annotations

import io
import struct
import zlib
from pathlib import Path

import mcap_layout
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.ingest import read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.mcap import MAGIC, container, ingest, iter_messages
from rigtools.ingest.mcap.container import ContainerScanner, MessageBlock
from rigtools.ingest.mcap.decoders import (
    accel_batch_file_descriptor_set,
    decode_accel_batch_protobuf,
    decode_accel_batches_protobuf,
    encode_accel_batch_protobuf,
)
from rigtools.ingest.mcap.decompress import ChunkDecompressor, ChunkRefusedError
from rigtools.ingest.recording import IngestReport

T0 = 1_700_000_000.0
_HDR = struct.Struct("<BQ")
_NEVER = 1 << 62


# --- helpers --------------------------------------------------------------------------------


def _s(text: str) -> bytes:
    b = text.encode()
    return struct.pack("<I", len(b)) + b


def _rec(op: int, content: bytes) -> bytes:
    return _HDR.pack(op, len(content)) + content




def _chans(n=20_000, n_ch=3, seed=0):
    rng = np.random.default_rng(seed)
    return {f"accel_{i}": (rng.standard_normal(n).astype(np.float32), 10_000.0, "g", 0, T0)
            for i in range(1, n_ch + 1)}


def _outcome(path: Path, *, pipeline: bool, runs: bool = True, source: str = "file"):
    """What the reader makes of a file: messages, the ingest's report, and ``read``'s result."""
    saved = container.PIPELINE_MIN_CHUNK_BYTES, container._RUN_MIN
    container.PIPELINE_MIN_CHUNK_BYTES = 0 if pipeline else _NEVER
    container._RUN_MIN = container._RUN_MIN if runs else _NEVER
    try:
        data = path.read_bytes()

        def stream():
            return open(path, "rb") if source == "file" else io.BytesIO(data)

        rep = IngestReport(units="messages")
        with stream() as f:
            msgs = [(m.channel_id, m.topic, m.log_time, m.publish_time, m.sequence, m.data)
                    for m in iter_messages(f, str(path), rep)]
        rep2 = IngestReport(units="messages")
        with stream() as f:
            ingest(f, str(path), RecordingBuilder(str(path), rep2), rep2, None)
        try:
            rec = read(path)
            whole = (rec.report.to_dict(), rec.channels)
        except Exception as exc:  # e.g. NoDataError: the same one either way
            whole = (repr(exc), {})
        return msgs, rep.to_dict(), rep2.to_dict(), whole
    finally:
        container.PIPELINE_MIN_CHUNK_BYTES, container._RUN_MIN = saved


def _assert_same(a, b) -> None:
    assert a[0] == b[0]
    assert a[1] == b[1]
    assert a[2] == b[2]
    assert a[3][0] == b[3][0]
    assert a[3][1].keys() == b[3][1].keys()
    assert all(a[3][1][k].equals(b[3][1][k]) for k in a[3][1])


# --- the chunk read ahead -------------------------------------------------------------------


@pytest.fixture(scope="module", params=["zstd", "lz4", "none"])
def intact(request, tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp(f"fast_{request.param}")
    return write_accel_mcap(d / "intact.mcap", _chans(), batch=500, chunk_size=32 << 10,
                            compression=request.param)


def _damage(data: bytes, kind: str) -> bytes:
    out = bytearray(data)
    cs = mcap_layout.chunks(data)
    c = cs[2]
    if kind == "flip_in_records":
        out[c["records_at"] + c["records_len"] // 2] ^= 0x01
    elif kind == "flip_in_first_chunk":  # it holds the Channel records
        out[cs[0]["records_at"] + 40] ^= 0x10
    elif kind == "wrong_crc":
        struct.pack_into("<I", out, c["crc_at"], 0x12345678)
    elif kind == "size_one_more":
        struct.pack_into("<Q", out, c["usize_at"],
                         struct.unpack_from("<Q", out, c["usize_at"])[0] + 1)
    elif kind == "absurd_size":
        struct.pack_into("<Q", out, c["usize_at"], 2**62)
    elif kind == "unknown_compression":
        clen = struct.unpack_from("<I", out, c["clen_at"])[0]
        if clen == 0:
            return bytes(out)
        out[c["comp_at"]] ^= 0x20
    elif kind == "compression_name_too_long":
        struct.pack_into("<I", out, c["clen_at"], 1 << 30)
    elif kind == "cut_in_chunk":
        return bytes(out[: c["pos"] + 9 + 200])
    elif kind == "cut_after_chunk":
        return bytes(out[: c["end"] + 5])
    elif kind == "chunk_length_past_end":
        struct.pack_into("<Q", out, c["pos"] + 1, len(out))
    return bytes(out)


_DAMAGE = ["intact", "flip_in_records", "flip_in_first_chunk", "wrong_crc", "size_one_more",
           "absurd_size", "unknown_compression", "compression_name_too_long", "cut_in_chunk",
           "cut_after_chunk", "chunk_length_past_end"]


@pytest.mark.parametrize("kind", _DAMAGE)
def test_read_ahead_gives_what_the_plain_walk_gives(intact, tmp_path, kind, monkeypatch):
    p = tmp_path / "d.mcap"
    p.write_bytes(_damage(intact.read_bytes(), kind))
    submitted = []
    orig = ContainerScanner._submit
    monkeypatch.setattr(ContainerScanner, "_submit",
                        lambda self, pos, length: submitted.append(pos) or orig(self, pos, length))
    plain = _outcome(p, pipeline=False)
    assert not submitted
    ahead = _outcome(p, pipeline=True)
    assert submitted  # the worker did read chunks
    _assert_same(plain, ahead)
    _assert_same(plain, _outcome(p, pipeline=True, source="bytesio"))
    if kind == "intact":
        assert not plain[1]["rejected"] and plain[0]


@pytest.mark.parametrize("kind", ["intact", "wrong_crc", "flip_in_records"])
@pytest.mark.parametrize("worker_crc", [True, False])
def test_read_ahead_crc_checked_by_either_side(intact, tmp_path, kind, worker_crc, monkeypatch):
    """Whether the worker or the walk checks a chunk's CRC changes nothing."""
    p = tmp_path / "d.mcap"
    p.write_bytes(_damage(intact.read_bytes(), kind))
    plain = _outcome(p, pipeline=False)
    orig = ContainerScanner._read_chunk_ahead
    monkeypatch.setattr(ContainerScanner, "_read_chunk_ahead",
                        lambda self, pos, length, _crc: orig(self, pos, length, worker_crc))
    _assert_same(plain, _outcome(p, pipeline=True))


def test_worker_stops_when_the_consumer_stops_early(intact):
    rep = IngestReport(units="messages")
    with open(intact, "rb") as f:
        sc = ContainerScanner(f, str(intact), rep)
        saved = container.PIPELINE_MIN_CHUNK_BYTES
        container.PIPELINE_MIN_CHUNK_BYTES = 0
        try:
            gen = sc.blocks()
            next(gen)
            assert sc._worker is not None
            gen.close()
        finally:
            container.PIPELINE_MIN_CHUNK_BYTES = saved
    assert sc._worker is None and sc._ahead is None


# --- runs of equal Message records ----------------------------------------------------------


def _schema_channels(cids) -> bytes:
    out = _rec(0x03, struct.pack("<H", 1) + _s("rigtools.AccelBatch") + _s("protobuf")
               + struct.pack("<I", len(accel_batch_file_descriptor_set()))
               + accel_batch_file_descriptor_set())
    for cid in cids:
        out += _rec(0x04, struct.pack("<HH", cid, 1) + _s(f"/a/{cid}") + _s("protobuf")
                    + struct.pack("<I", 0))
    return out


def _message(cid: int, seq: int, payload: bytes) -> bytes:
    return _rec(0x05, struct.pack("<HIQQ", cid, seq, 1000 + seq, 2000 + seq) + payload)


def _file(inner: bytes, *, compression: str = "", crc: bool = True, before: bytes = b"",
          after: bytes = b"") -> bytes:
    if compression == "zstd":
        import zstandard

        comp = zstandard.ZstdCompressor().compress(inner)
    else:
        comp = inner
    chunk = struct.pack("<QQQI", 0, 0, len(inner), zlib.crc32(inner) if crc else 0) \
        + _s(compression) + struct.pack("<Q", len(comp)) + comp
    return (MAGIC + _rec(0x01, _s("") + _s("t")) + before + _rec(0x06, chunk) + after
            + _rec(0x0F, struct.pack("<I", 0)) + _rec(0x02, bytes(20)) + MAGIC)


# one item: ("m", cid, payload length) a message, ("s",) a Schema, ("c", cid) a Channel,
# ("x", n) an unknown record, ("short",) a message shorter than its header
_item = st.one_of(
    st.tuples(st.just("m"), st.sampled_from([1, 2, 3, 9]), st.sampled_from([0, 5, 40, 41])),
    st.tuples(st.just("s")),
    st.tuples(st.just("c"), st.sampled_from([3, 9])),
    st.tuples(st.just("x"), st.integers(0, 30)),
    st.tuples(st.just("short")),
)
_runs = st.lists(st.tuples(_item, st.integers(1, 40)), min_size=1, max_size=12)


def _inner(runs, tail: bytes = b"") -> bytes:
    out, seq = b"", 0
    for item, count in runs:
        for _ in range(count):
            seq += 1
            if item[0] == "m":
                out += _message(item[1], seq, bytes([seq % 251]) * item[2])
            elif item[0] == "s":
                out += _schema_channels([])
            elif item[0] == "c":
                out += _rec(0x04, struct.pack("<HH", item[1], 1) + _s(f"/a/{item[1]}")
                            + _s("protobuf") + struct.pack("<I", 0))
            elif item[0] == "x":
                out += _rec(0x42, bytes(item[1]))
            else:
                out += _rec(0x05, struct.pack("<HI", 1, seq))
    return out + tail


def _scan(data: bytes, runs: bool):
    saved = container._RUN_MIN
    container._RUN_MIN = container._RUN_MIN if runs else _NEVER
    try:
        rep = IngestReport(units="messages")
        sc = ContainerScanner(io.BytesIO(data), "x", rep)
        msgs = [(m[0], m[1], m[2], m[3], bytes(m[4]), m[5], b.where)
                for b in sc.blocks() for m in b.messages()]
        return msgs, rep.to_dict(), sc.n_message_records, sorted(sc.channels)
    finally:
        container._RUN_MIN = saved


@settings(max_examples=120, deadline=None)
@given(_runs, st.sampled_from([b"", b"\x05\x00", _HDR.pack(0x05, 10**6)]))
def test_array_walk_of_chunk_records_equals_the_record_by_record_walk(runs, tail):
    data = _file(_inner(runs, tail), before=_schema_channels([1, 2]))
    assert _scan(data, runs=True) == _scan(data, runs=False)


@pytest.mark.parametrize("n", [7, 8, 16, 17, 200])
def test_long_runs_broken_anywhere(n):
    for brk in sorted({0, 1, n // 2, n - 1, n}):
        runs = [(("m", 1, 40), brk), (("m", 2, 41), 1), (("m", 1, 40), n - brk)]
        data = _file(_inner(runs), before=_schema_channels([1, 2]))
        assert _scan(data, runs=True) == _scan(data, runs=False)


# channels taking turns: one period of ("m", cid, payload length) messages, repeated
_period = st.lists(st.tuples(st.just("m"), st.sampled_from([1, 2, 3, 9]),
                             st.sampled_from([0, 5, 40, 41, 97])), min_size=2, max_size=9)


@settings(max_examples=150, deadline=None)
@given(_period, st.integers(1, 60), st.lists(st.tuples(_item, st.integers(1, 3)), max_size=3),
       st.integers(0, 200), st.sampled_from([b"", b"\x05\x00", _HDR.pack(0x05, 10**6)]))
def test_channels_taking_turns_equal_the_record_by_record_walk(period, reps, breaks, at, tail):
    """Patterns of 2 to 9 records repeating, broken anywhere, give what the walk gives.

    9 is past the longest period read at once; the breaks are other records, and channels
    are defined late or never.
    """
    runs = [(item, 1) for item in period] * reps
    at = min(at, len(runs))
    runs = runs[:at] + breaks + runs[at:]
    data = _file(_inner(runs, tail), before=_schema_channels([1, 2]))
    assert _scan(data, runs=True) == _scan(data, runs=False)


@pytest.mark.parametrize("p", [2, 3, 8])
def test_channels_taking_turns_are_read_as_patterns(p, monkeypatch):
    """The pattern path really takes the records (no record walked one by one after it)."""
    from rigtools.ingest.mcap import walk as mcap_walk

    period = [("m", 1 + (j % 2), 40 + j) for j in range(p)]
    data = _file(_inner([(item, 1) for item in period] * 50), before=_schema_channels([1, 2]))
    taken = []
    orig = mcap_walk.ChunkRecordWalk._take_pattern

    def spy(self, buf, cpos, pos, size, k, offs, cols):
        taken.append(k * len(offs))
        return orig(self, buf, cpos, pos, size, k, offs, cols)

    monkeypatch.setattr(mcap_walk.ChunkRecordWalk, "_take_pattern", spy)
    got = _scan(data, runs=True)
    assert taken == [50 * p]
    monkeypatch.setattr(mcap_walk.ChunkRecordWalk, "_take_pattern", orig)
    assert got == _scan(data, runs=False)


def test_messages_before_their_channel_in_a_run_are_held_as_in_the_walk():
    # channel 9 is defined only after its first messages; 3 never
    runs = [(("m", 9, 40), 30), (("c", 9), 1), (("m", 9, 40), 20), (("m", 3, 40), 25)]
    data = _file(_inner(runs), before=_schema_channels([1]))
    got = _scan(data, runs=True)
    assert got == _scan(data, runs=False)
    assert got[1]["rejected"] == {"unknown_channel": 25}
    assert sum(1 for m in got[0] if m[0] == 9) == 50


def test_message_block_splits_by_channel_in_order_of_appearance():
    cid = np.array([4, 2, 7, 4, 2, 7, 4, 2], np.int64)
    n = len(cid)
    times = np.arange(n, dtype=np.uint64)
    blk = MessageBlock("here", memoryview(bytes(100)), cid, np.arange(n), times, times,
                       np.arange(n) * 10, np.arange(n) * 10 + 5)
    got = [(c, g.sequence.tolist(), g.start.tolist()) for c, g in blk.by_channel()]
    assert got == [(4, [0, 3, 6], [0, 30, 60]), (2, [1, 4, 7], [10, 40, 70]), (7, [2, 5], [20, 50])]
    cid[5] = 4  # no longer taking turns
    got = [(c, g.sequence.tolist()) for c, g in blk.by_channel()]
    assert got == [(4, [0, 3, 5, 6]), (2, [1, 4, 7]), (7, [2])]


# --- one-shot zstd --------------------------------------------------------------------------


def _streaming_reference(comp: bytes, usize: int):
    """The bounded streaming decompression every chunk went through before."""
    import zstandard

    try:
        reader = zstandard.ZstdDecompressor().stream_reader(comp, read_across_frames=True)
        parts, got = [], 0
        while got < usize:
            piece = reader.read(usize - got)
            if not piece:
                break
            parts.append(piece)
            got += len(piece)
        extra = bool(reader.read(1))
    except zstandard.ZstdError:
        return "chunk_decompression_error"
    data = b"".join(parts)
    if len(data) != usize or extra:
        return "chunk_size_mismatch"
    return data


def test_one_shot_zstd_agrees_with_streaming_on_odd_frames():
    import zstandard

    data = bytes(range(256)) * 40
    sized = zstandard.ZstdCompressor().compress(data)
    unsized = zstandard.ZstdCompressor(write_content_size=False).compress(data)
    skippable = b"\x50\x2a\x4d\x18" + struct.pack("<I", 4) + b"abcd"
    cases = {
        "sized": (sized, len(data)),
        "unsized": (unsized, len(data)),
        "two frames": (sized + sized, 2 * len(data)),
        "two frames, one counted": (sized + sized, len(data)),
        "skippable first": (skippable + sized, len(data)),
        "junk after": (sized + b"junk", len(data)),
        "unsized, junk after": (unsized + b"junk", len(data)),
        "truncated": (sized[:-7], len(data)),
        "unsized, truncated": (unsized[:-7], len(data)),
        "states less": (sized, len(data) + 1),
        "states more": (sized, len(data) - 1),
        "unsized, states less": (unsized, len(data) + 1),
        "unsized, states more": (unsized, len(data) - 1),
        "not zstd": (b"definitely not a zstd frame", len(data)),
        "empty": (b"", len(data)),
    }
    d = ChunkDecompressor()
    for label, (comp, usize) in cases.items():
        want = _streaming_reference(comp, usize)
        try:
            got = bytes(d.decompress("zstd", memoryview(comp), usize))
        except ChunkRefusedError as exc:
            got = exc.reason
        assert got == want, label


def test_zstd_frame_stating_another_size_is_not_decompressed_in_one_go(monkeypatch):
    import zstandard

    bomb = zstandard.ZstdCompressor().compress(bytes(64 << 20))
    calls = []
    d = ChunkDecompressor()
    orig = d._zstd_streaming
    monkeypatch.setattr(d, "_zstd_streaming", lambda c, u: calls.append(u) or orig(c, u))
    with pytest.raises(ChunkRefusedError, match="chunk_size_mismatch"):
        d.decompress("zstd", memoryview(bomb), 1000)
    assert calls == [1000]  # the bounded path, never a 64 MiB output


# --- AccelBatch messages of one layout ------------------------------------------------------


def _pb_class():
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    fds = descriptor_pb2.FileDescriptorSet.FromString(accel_batch_file_descriptor_set())
    pool = descriptor_pool.DescriptorPool()
    for f in fds.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("rigtools.AccelBatch"))


def _lay_out(msgs: list[bytes], gaps: list[int]):
    buf, starts, ends = b"", [], []
    for m, g in zip(msgs, gaps, strict=True):
        buf += b"\xee" * g
        starts.append(len(buf))
        buf += m
        ends.append(len(buf))
    return memoryview(buf), np.array(starts), np.array(ends)


@settings(max_examples=80, deadline=None)
@given(
    channel=st.text(max_size=20), unit=st.sampled_from(["g", "m/s^2", ""]),
    rate=st.floats(1.0, 1e6), k=st.integers(0, 40), m=st.integers(2, 30),
    width=st.integers(1, 9), step=st.integers(1, 2**20), even=st.booleans(),
    data=st.data(),
)
def test_same_layout_decoding_equals_message_by_message_and_protobuf(
        channel, unit, rate, k, m, width, step, even, data):
    lo = 0 if width == 1 else 1 << (7 * (width - 1))
    hi = min((1 << (7 * width)) - 1, 2**63 - 1)
    firsts = data.draw(st.lists(st.integers(max(lo, 1), hi), min_size=m, max_size=m))
    stamps = data.draw(st.lists(st.integers(1 << 56, 2**63), min_size=m, max_size=m))
    rng = np.random.default_rng(m)
    vals = [rng.standard_normal(k).astype(np.float32) for _ in range(m)]
    msgs = [encode_accel_batch_protobuf(channel, unit, rate, f, s, v)
            for f, s, v in zip(firsts, stamps, vals, strict=True)]
    gaps = [7] * m if even else data.draw(st.lists(st.integers(0, 9), min_size=m, max_size=m))
    buf, s, e = _lay_out(msgs, gaps)
    cols = decode_accel_batches_protobuf(buf, s, e)
    if k == 0:
        assert cols is None  # no values field: left to the message by message path
        return
    assert cols is not None
    cls = _pb_class()
    for i in range(m):
        one = decode_accel_batch_protobuf(buf[s[i] : e[i]])
        ref = cls.FromString(msgs[i])
        assert (cols.channel, cols.unit, cols.sample_rate_Hz) == (
            one.channel, one.unit, one.sample_rate_Hz) == (ref.channel, ref.unit,
                                                           ref.sample_rate_Hz)
        assert int(cols.first_sample_index[i]) == one.first_sample_index == ref.first_sample_index
        assert int(cols.stamp_ns[i]) == one.stamp_ns == ref.stamp_ns
        assert np.array_equal(cols.values[i].view(np.uint32), one.values.view(np.uint32))
        assert np.array_equal(cols.values[i], np.asarray(ref.values, np.float32))


def test_layouts_of_one_length_and_prefix_are_not_confused():
    # same channel bytes, same total length, but the counter and stamp varints trade a byte
    a = [encode_accel_batch_protobuf("ch", "g", 10.0, 300 + i, 1 << 49, np.ones(4, np.float32))
         for i in range(5)]  # counter 2 bytes, stamp 8 bytes
    b = [encode_accel_batch_protobuf("ch", "g", 10.0, 20_000 + i, 1 << 42, np.ones(4, np.float32))
         for i in range(5)]  # counter 3 bytes, stamp 7 bytes
    assert len(a[0]) == len(b[0])
    for group in (a, b, a, b):
        buf, s, e = _lay_out(group, [3] * 5)
        cols = decode_accel_batches_protobuf(buf, s, e)
        assert cols is not None
        singles = [decode_accel_batch_protobuf(x) for x in group]
        assert cols.first_sample_index.tolist() == [x.first_sample_index for x in singles]
        assert cols.stamp_ns.tolist() == [x.stamp_ns for x in singles]


@pytest.mark.parametrize("odd", ["counter_wider", "other_unit", "extra_field", "no_counter",
                                 "counter_2_63"])
def test_one_odd_message_leaves_the_group_to_the_general_paths(odd):
    msgs = [encode_accel_batch_protobuf("a", "g", 10.0, 1000 + 8 * i, 5 + i, np.ones(8, np.float32))
            for i in range(6)]
    if odd == "counter_wider":  # same length: the stamp gets shorter
        msgs[3] = encode_accel_batch_protobuf("a", "g", 10.0, 1 << 20, 1, np.ones(8, np.float32))
    elif odd == "other_unit":
        msgs[3] = encode_accel_batch_protobuf("a", "G", 10.0, 1024, 8, np.ones(8, np.float32))
    elif odd == "extra_field":
        msgs[3] = msgs[3][:-2] + b"\x38\x01"  # same length, not a plain AccelBatch
    elif odd == "no_counter":
        msgs[3] = encode_accel_batch_protobuf("a", "g", 10.0, 0, 8, np.ones(8, np.float32))
    else:
        msgs[3] = encode_accel_batch_protobuf("a", "g", 10.0, 2**63, 8, np.ones(8, np.float32))
    buf, s, e = _lay_out(msgs, [4] * 6)
    cols = decode_accel_batches_protobuf(buf, s, e)
    try:
        singles = [decode_accel_batch_protobuf(m) for m in msgs]
    except Exception:
        singles = None
    if cols is None:
        return  # declined: decoded message by message
    assert singles is not None
    assert cols.first_sample_index.tolist() == [x.first_sample_index for x in singles]
    assert cols.unit == singles[0].unit and all(x.unit == cols.unit for x in singles)


def test_values_go_where_out_says():
    msgs = [encode_accel_batch_protobuf("a", "g", 10.0, 8 * i + 8, 5, np.full(8, i, np.float32))
            for i in range(6)]
    slab = np.full(100, -1.0, np.float32)
    buf, s, e = _lay_out(msgs, [4] * 6)
    cols = decode_accel_batches_protobuf(buf, s, e,
                                         lambda m, k: slab[10 : 10 + m * k].reshape(m, k))
    assert cols is not None and np.shares_memory(cols.values, slab)
    assert slab[10:58].tolist() == [float(i) for i in range(6) for _ in range(8)]
    assert slab[:10].tolist() == [-1.0] * 10 and slab[58:].tolist() == [-1.0] * 42


def test_full_read_of_a_larger_file_equals_the_plain_paths(tmp_path):
    p = write_accel_mcap(tmp_path / "big.mcap", _chans(n=200_000, n_ch=4), batch=1024,
                         chunk_size=256 << 10)
    fast = _outcome(p, pipeline=True, runs=True)
    plain = _outcome(p, pipeline=False, runs=False)
    _assert_same(fast, plain)
    rec = read(p)
    assert sum(len(c) for c in rec.channels.values()) == 800_000 and not rec.report.has_losses


def test_values_cut_from_many_slabs_are_the_same(tmp_path, monkeypatch):
    from rigtools.ingest.mcap import handlers as mcap_handlers

    p = write_accel_mcap(tmp_path / "s.mcap", _chans(n=50_000, n_ch=2), batch=700,
                         chunk_size=16 << 10)
    ref = read(p)
    monkeypatch.setattr(mcap_handlers, "SLAB_VALUES", 5000)
    monkeypatch.setattr(mcap_handlers, "MIN_SLAB_VALUES", 1000)
    got = read(p)
    assert got.channels.keys() == ref.channels.keys()
    assert all(got.channels[k].equals(ref.channels[k]) for k in ref.channels)
    assert got.report.to_dict() == ref.report.to_dict()


def test_file_source_reads_by_position_and_never_past_the_data(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    from rigtools.ingest.mcap.source import WINDOW_BYTES, ByteSource

    data = bytes(range(256)) * (3 * WINDOW_BYTES // 256 + 11)
    p = tmp_path / "bytes.bin"
    p.write_bytes(b"skip" + data)
    with open(p, "rb") as f:
        f.read(4)  # the source starts where the stream is
        src = ByteSource(f)
        assert src.can_peek and src.remaining() == len(data)
        assert src.read(5) == data[:5]
        assert src.skip(WINDOW_BYTES + 3) == WINDOW_BYTES + 3
        with ThreadPoolExecutor(1) as ex:  # reading at a position from another thread
            assert ex.submit(src.peek, 7, 100).result() == data[7:107]
        assert src.look(1, 4) == data[1:5]
        assert src.read(9) == data[WINDOW_BYTES + 8 : WINDOW_BYTES + 17]
        assert src.read(2 * WINDOW_BYTES) == data[WINDOW_BYTES + 17 : 3 * WINDOW_BYTES + 17]
        assert src.read(2**62) == data[3 * WINDOW_BYTES + 17 :]  # a claim beyond the data
        assert src.pos == len(data) and src.read(9) == b"" and src.skip(9) == 0
        assert src.peek(len(data) - 2, 10) == data[-2:]
    # a file cut after it was opened: reads end early instead of failing
    p.write_bytes(b"skip" + data)
    with open(p, "rb") as f:
        src = ByteSource(f)
        with open(p, "r+b") as g:
            g.truncate(1000)
        assert src.read(5000) == (b"skip" + data)[:1000]
