"""MCAP reader: records whose length field lies, and damaged definitions the summary repeats.

Regression tests for the four defects issue 12's fuzzing pinned (``test_fuzz_mcap.py``):

* (a) an unchunked file whose Message record claims a length past the end of the file (or one
  that grows into the next records): the walk resumes at the next plausible record instead of
  ending there (``lost_sync``, counted once);
* (b) a chunked file whose Chunk record claims a wrong length: the chunk is read with the
  length its own fields imply (its CRC vouches for its records); when those fields are
  damaged too, the walk resumes at the next plausible record;
* (c), (d) a damaged but parseable Schema or Channel record: the copy in the summary section
  (whose CRC checks) wins, before any message of the channel is handed on; a Schema record
  missing before its Channel record holds the channel (its messages are read at the end,
  with the schema found later).

Files are written by rigtools' MCAP writer; what to damage is located by the independent
walker of ``mcap_layout`` (not rigtools' reader). Expected counts come from the writer's
parameters: 2 channels x :data:`N` samples in batches of :data:`BATCH`, so each Message
record carries exactly :data:`BATCH` samples.
"""

from __future__ import annotations

import gzip
import struct
from pathlib import Path

import mcap_layout
import numpy as np
import pytest

from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.errors import NoDataError
from rigtools.ingest import read

T0 = 1_700_000_000.0
N = 2_000
BATCH = 100
FIRST = 7_000


def _chans() -> dict[str, tuple[np.ndarray, float, str, int, float]]:
    rng = np.random.default_rng(3)
    return {
        f"accel_{i}": (rng.standard_normal(N).astype(np.float32), 10_000.0, "g", FIRST, T0)
        for i in (1, 2)
    }


def _write(tmp_path: Path, name: str, data: bytes) -> Path:
    p = tmp_path / name
    p.write_bytes(data)
    return p


def _unchunked(tmp_path: Path) -> bytes:
    return write_accel_mcap(
        tmp_path / "flat.mcap", _chans(), batch=BATCH, use_chunking=False
    ).read_bytes()


def _chunked(tmp_path: Path, compression: str = "zstd") -> bytes:
    return write_accel_mcap(
        tmp_path / "chunked.mcap", _chans(), batch=BATCH, chunk_size=4096, compression=compression
    ).read_bytes()  # type: ignore[arg-type]


def _batches(rec) -> dict[str, set[int]]:
    """Per channel, the batch numbers (0..N/BATCH-1) read whole and equal to what was written."""
    out = {}
    for name, (values, *_rest) in _chans().items():
        ch = rec.channels.get(name)
        got: set[int] = set()
        if ch is not None:
            for k in range(N // BATCH):
                i = FIRST + k * BATCH - ch.first_index
                if 0 <= i and i + BATCH <= ch.values.size and ch.valid[i : i + BATCH].all():
                    assert np.array_equal(
                        ch.values[i : i + BATCH],
                        values[k * BATCH : (k + 1) * BATCH].astype(np.float64),
                    )
                    got.add(k)
        out[name] = got
    return out


def _message_records(data: bytes) -> list[tuple[int, int, int]]:
    """``(offset, content length, channel id)`` of the top-level Message records."""
    return [
        (pos, length, struct.unpack_from("<H", data, pos + 9)[0])
        for op, pos, length in mcap_layout.records(data)
        if op == 0x05
    ]


def _kth(data: bytes, j: int) -> tuple[str, int]:
    """Channel name and batch number of the ``j``-th top-level Message record."""
    msgs = _message_records(data)
    cid = msgs[j][2]
    return f"accel_{cid}", sum(1 for m in msgs[:j] if m[2] == cid)


ALL = set(range(N // BATCH))


# --- (a) unchunked: a Message record whose length lies ---------------------------------------


@pytest.mark.parametrize("claim", ["past_end", "into_next_records"])
def test_unchunked_message_length_lie_loses_that_message_only(tmp_path, claim):
    data = _unchunked(tmp_path)
    msgs = _message_records(data)
    j = len(msgs) // 2
    pos, length, _ = msgs[j]
    b = bytearray(data)
    # past the end: 2**56 more bytes (the fuzz case); into the next records: the record
    # swallows the next two and a half Message records (each 9 + length bytes long)
    new = length + (1 << 56 if claim == "past_end" else 5 * (9 + length) // 2)
    struct.pack_into("<Q", b, pos + 1, new)
    rec = read(_write(tmp_path, "lie.mcap", bytes(b)))
    name, k = _kth(data, j)
    got = _batches(rec)
    for ch in got:
        want = ALL - {k} if ch == name else ALL
        assert got[ch] == want, f"{ch}: batches {sorted(want - got[ch])} lost"
    assert rec.report.rejected["lost_sync"] == 1
    assert rec.report.first_position["lost_sync"] == f"byte {pos}"
    assert "truncated_record" not in rec.report.rejected


def test_unchunked_message_length_shrunk_keeps_every_other_message(tmp_path):
    data = _unchunked(tmp_path)
    msgs = _message_records(data)
    j = len(msgs) // 3
    pos, length, _ = msgs[j]
    b = bytearray(data)
    struct.pack_into("<Q", b, pos + 1, length - 7)  # ends 7 bytes early, inside its payload
    rec = read(_write(tmp_path, "short.mcap", bytes(b)))
    name, k = _kth(data, j)
    got = _batches(rec)
    for ch in got:
        assert got[ch] >= (ALL - {k} if ch == name else ALL)
    assert rec.report.has_losses


def test_unchunked_record_cut_by_the_end_of_the_file_is_still_counted_truncated(tmp_path):
    data = _unchunked(tmp_path)
    msgs = _message_records(data)
    pos, length, _ = msgs[-5]
    rec = read(_write(tmp_path, "cut.mcap", data[: pos + 9 + length // 2]))
    # nothing plausible follows the cut record: the walk ends there as before
    assert rec.report.rejected["truncated_record"] == 1
    assert "lost_sync" not in rec.report.rejected
    assert sum(len(v) for v in _batches(rec).values()) == len(msgs) - 5


# --- (b) chunked: a Chunk record whose length lies -------------------------------------------


@pytest.mark.parametrize("compression", ["zstd", "none"])
@pytest.mark.parametrize("claim", ["past_end", "grown", "shrunk"])
def test_chunk_length_lie_is_read_by_the_chunks_own_fields(tmp_path, compression, claim):
    data = _chunked(tmp_path, compression)
    c = mcap_layout.chunks(data)[0]  # holds the Schema and Channel records, too
    length = c["end"] - c["pos"] - 9
    new = {"past_end": length + (1 << 40), "grown": length + 300, "shrunk": length - 300}[claim]
    b = bytearray(data)
    struct.pack_into("<Q", b, c["pos"] + 1, new)
    rec = read(_write(tmp_path, "lie.mcap", bytes(b)))
    assert _batches(rec) == {"accel_1": ALL, "accel_2": ALL}
    assert not rec.report.rejected
    assert any(
        f"Chunk record at byte {c['pos']} claims {new} bytes" in w for w in rec.report.warnings
    )


def test_chunk_length_and_header_both_damaged_resumes_at_the_next_chunk(tmp_path):
    data = _chunked(tmp_path)
    cs = mcap_layout.chunks(data)
    c = cs[2]
    b = bytearray(data)
    struct.pack_into("<Q", b, c["pos"] + 1, 1 << 50)
    struct.pack_into("<I", b, c["clen_at"], 1 << 30)  # compression name length: no inference
    rec = read(_write(tmp_path, "lie2.mcap", bytes(b)))
    # the lost chunk's messages: decompress it with zstandard (independent of the reader)
    import zstandard

    raw = zstandard.ZstdDecompressor().decompress(
        data[c["records_at"] : c["records_at"] + c["records_len"]]
    )
    lost: dict[str, set[int]] = {"accel_1": set(), "accel_2": set()}
    seen = {1: 0, 2: 0}
    for cc in cs[:3]:
        inner = zstandard.ZstdDecompressor().decompress(
            data[cc["records_at"] : cc["records_at"] + cc["records_len"]]
        )
        p = 0
        while p < len(inner):
            op, n = struct.unpack_from("<BQ", inner, p)
            if op == 0x05:
                cid = struct.unpack_from("<H", inner, p + 9)[0]
                if cc is c:
                    lost[f"accel_{cid}"].add(seen[cid])
                seen[cid] += 1
            p += 9 + n
    assert raw and any(lost.values())
    got = _batches(rec)
    assert got == {k: ALL - v for k, v in lost.items()}
    assert rec.report.rejected["lost_sync"] == 1
    assert "truncated_record" not in rec.report.rejected


def test_gzip_stream_cannot_resync_and_ends_at_the_lie(tmp_path):
    """The resynchronisation reads ahead, which a gzip stream cannot: it ends there, counted."""
    data = _unchunked(tmp_path)
    pos, length, _ = _message_records(data)[10]
    b = bytearray(data)
    struct.pack_into("<Q", b, pos + 1, length + (1 << 56))
    gz = tmp_path / "lie.mcap.gz"
    gz.write_bytes(gzip.compress(bytes(b)))
    rec = read(gz)
    assert rec.report.rejected["truncated_record"] == 1
    assert sum(len(v) for v in _batches(rec).values()) == 10


# --- (c), (d) damaged definitions and the summary's copies -----------------------------------


def _first(data: bytes, op: int, nth: int = 0) -> tuple[int, int]:
    return [(pos, n) for o, pos, n in mcap_layout.records(data) if o == op][nth][:2]


def _damage_schema(data: bytes) -> bytes:
    """The first Schema record with one flipped bit in its FileDescriptorSet.

    Byte 86 of the record (found by the fuzz long profile) is inside the descriptor of a
    field of ``rigtools.AccelBatch``: the schema still parses as a record but no longer
    describes the type, so decoding with it counts every message ``bad_schema`` (see
    :func:`test_damaged_schema_in_a_gzip_stream_keeps_the_first_definition`).
    """
    pos, _n = _first(data, 0x03)
    b = bytearray(data)
    b[pos + 86] ^= 0x01
    return bytes(b)


def test_damaged_schema_is_replaced_by_the_summary_copy(tmp_path):
    rec = read(_write(tmp_path, "schema.mcap", _damage_schema(_unchunked(tmp_path))))
    assert _batches(rec) == {"accel_1": ALL, "accel_2": ALL}
    assert not rec.report.rejected
    assert any("schema id 1" in w and "summary's copy is used" in w for w in rec.report.warnings)


def test_damaged_channel_is_replaced_by_the_summary_copy(tmp_path):
    data = _unchunked(tmp_path)
    pos, n = _first(data, 0x04, 1)
    b = bytearray(data)
    enc = bytes(data[pos : pos + 9 + n]).index(b"protobuf")
    b[pos + enc + 2] ^= 0x01  # "protobuf" -> "pruotobuf": no decoder for that encoding
    rec = read(_write(tmp_path, "channel.mcap", bytes(b)))
    assert _batches(rec) == {"accel_1": ALL, "accel_2": ALL}
    assert not rec.report.rejected
    assert any("channel id 2" in w and "summary's copy is used" in w for w in rec.report.warnings)


def test_damaged_schema_in_a_gzip_stream_keeps_the_first_definition(tmp_path):
    """Without reading ahead the summary cannot be consulted first: the documented limit.

    Also shows that the damage of :func:`_damage_schema` makes the schema unusable.
    """
    gz = tmp_path / "schema.mcap.gz"
    gz.write_bytes(gzip.compress(_damage_schema(_unchunked(tmp_path))))
    with pytest.raises(NoDataError, match=f"bad_schema: {2 * N // BATCH}"):
        read(gz)


def test_schema_missing_before_its_channel_holds_the_channel_until_the_summary(tmp_path):
    data = _unchunked(tmp_path)
    pos, n = _first(data, 0x03)
    dropped = data[:pos] + data[pos + 9 + n :]  # footer offsets now off: summary not preferred
    for name, blob in (("plain", dropped), ("gz", None)):
        if blob is None:
            p = tmp_path / "drop.mcap.gz"
            p.write_bytes(gzip.compress(dropped))
        else:
            p = _write(tmp_path, "drop.mcap", blob)
        rec = read(p)
        assert _batches(rec) == {"accel_1": ALL, "accel_2": ALL}, name
        assert not rec.report.rejected, name
        assert any("read last" in w for w in rec.report.warnings), name


def test_footer_offsets_outside_the_file_are_warned_about(tmp_path):
    data = _unchunked(tmp_path)
    b = bytearray(data)
    fpos = len(data) - 8 - 29
    struct.pack_into("<Q", b, fpos + 9, len(data) + 1000)  # summary start
    rec = read(_write(tmp_path, "footer.mcap", bytes(b)))
    assert _batches(rec) == {"accel_1": ALL, "accel_2": ALL}
    assert any("summary start" in w and "points outside" in w for w in rec.report.warnings)
