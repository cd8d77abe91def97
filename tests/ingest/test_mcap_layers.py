"""MCAP reader layers one by one: record parsers, byte source, bounded decompression."""

from __future__ import annotations

import gzip
import io
import pickle
import struct

import pytest

from rigtools.ingest import mcap
from rigtools.ingest.mcap.decompress import (
    FREE_CHUNK_BYTES,
    MAX_CHUNK_RATIO,
    MAX_CHUNK_UNCOMPRESSED_BYTES,
    ChunkDecompressor,
    ChunkRefusedError,
    check_chunk_crc,
    check_chunk_size,
    chunk_size_limit,
)
from rigtools.ingest.mcap.records import (
    MalformedRecordError,
    message_index_entry_count,
    parse_channel,
    parse_chunk_header,
    parse_metadata,
    parse_schema,
    statistics_message_count,
)
from rigtools.ingest.mcap.source import READ_PIECE_BYTES, ByteSource


def _s(text: str) -> bytes:
    b = text.encode()
    return struct.pack("<I", len(b)) + b


def _map(d: dict[str, str]) -> bytes:
    body = b"".join(_s(k) + _s(v) for k, v in d.items())
    return struct.pack("<I", len(body)) + body


def test_reader_package_reexports_the_layer_constants():
    assert mcap.MAX_CHUNK_RATIO == MAX_CHUNK_RATIO
    assert mcap.MAX_CHUNK_UNCOMPRESSED_BYTES == MAX_CHUNK_UNCOMPRESSED_BYTES
    assert mcap.FREE_CHUNK_BYTES == FREE_CHUNK_BYTES
    assert set(mcap.__all__) >= {"NAME", "READER", "sniff", "ingest", "iter_messages"}


def test_record_parsers_read_well_formed_records():
    schema = struct.pack("<H", 3) + _s("rigtools.SlowValue") + _s("jsonschema") + _s("{}")
    rec = parse_schema(schema, 0, len(schema))
    assert (rec.id, rec.name, rec.encoding, rec.data) == (3, "rigtools.SlowValue",
                                                           "jsonschema", b"{}")
    channel = struct.pack("<HH", 7, 3) + _s("/slow/x") + _s("json") + _map({"unit": "rpm"})
    ch = parse_channel(channel, 0, len(channel))
    assert (ch.id, ch.schema_id, ch.topic, ch.message_encoding, ch.metadata) == (
        7, 3, "/slow/x", "json", {"unit": "rpm"})
    assert parse_metadata(_s("rigtools.run") + _map({"rig": "fzg-1"})) == (
        "rigtools.run", {"rig": "fzg-1"})
    assert statistics_message_count(struct.pack("<QHIIIIQQ", 42, 0, 0, 0, 0, 0, 0, 0)) == 42
    assert statistics_message_count(b"\x00" * 10) is None
    index = struct.pack("<HI", 1, 3 * 16) + b"\x00" * 32  # claims 3 entries, holds 2
    assert message_index_entry_count(index) == 2
    assert message_index_entry_count(b"\x01") == 0


@pytest.mark.parametrize(("cut", "field"), [
    (1, "schema id"), (5, "string length"), (10, "string of 18 bytes"),
    (40, "schema data length"), (43, "schema data of 2 bytes"),
])
def test_schema_parser_names_the_field_that_runs_past_the_record(cut, field):
    schema = struct.pack("<H", 3) + _s("rigtools.SlowValue") + _s("jsonschema") + _s("{}")
    with pytest.raises(MalformedRecordError, match=f"^{field}$"):
        parse_schema(schema, 0, cut)


def test_chunk_header_parser_checks_every_length():
    def chunk(clen: int, name: bytes, rlen: int, records: bytes) -> bytes:
        return struct.pack("<QQQII", 0, 0, len(records), 0, clen) + name + \
            struct.pack("<Q", rlen) + records

    head = parse_chunk_header(chunk(4, b"zstd", 3, b"abc"))
    assert (head.compression, head.records_size, head.uncompressed_size) == ("zstd", 3, 3)
    assert head.records_offset == 32 + 4 + 8
    with pytest.raises(MalformedRecordError, match="shorter than a chunk header"):
        parse_chunk_header(b"\x00" * 27)
    with pytest.raises(MalformedRecordError, match="compression name of 99 bytes"):
        parse_chunk_header(chunk(99, b"zstd", 3, b"abc"))
    with pytest.raises(MalformedRecordError, match="records of 4 bytes claimed, 3 left"):
        parse_chunk_header(chunk(4, b"zstd", 4, b"abc"))


@pytest.mark.parametrize("wrap", ["bytesio", "gzip"])
def test_byte_source_never_reads_past_the_data(wrap):
    data = bytes(range(256)) * (3 * READ_PIECE_BYTES // 256 + 7)
    stream = io.BytesIO(data) if wrap == "bytesio" else gzip.GzipFile(
        fileobj=io.BytesIO(gzip.compress(data)))
    src = ByteSource(stream)
    assert src.remaining() == (len(data) if wrap == "bytesio" else None)
    assert src.read(5) == data[:5]
    assert src.skip(READ_PIECE_BYTES + 3) == READ_PIECE_BYTES + 3
    assert src.read(2**62) == data[READ_PIECE_BYTES + 8 :]  # a claim far beyond the data
    assert src.pos == len(data)
    assert src.read(9) == b"" and src.skip(9) == 0


def test_chunk_size_limit_is_the_free_size_then_the_ratio_then_the_cap():
    assert chunk_size_limit(1) == FREE_CHUNK_BYTES
    assert chunk_size_limit(20_000) == 20_000 * MAX_CHUNK_RATIO  # 20 MB: above free, below cap
    assert chunk_size_limit(2**40) == MAX_CHUNK_UNCOMPRESSED_BYTES
    check_chunk_size(FREE_CHUNK_BYTES, 1)
    with pytest.raises(ChunkRefusedError, match=r"^absurd_chunk_size: claims"):
        check_chunk_size(FREE_CHUNK_BYTES + 1, 1)


def test_decompressor_refuses_what_is_not_exactly_the_stated_size():
    import lz4.frame
    import zstandard

    d = ChunkDecompressor()
    data = b"rig" * 1000
    z = memoryview(zstandard.ZstdCompressor().compress(data))
    l4 = memoryview(lz4.frame.compress(data))
    assert d.decompress("zstd", z, len(data)) == data
    assert d.decompress("lz4", l4, len(data)) == data
    assert d.decompress("", memoryview(data), len(data)) == data
    for comp, payload in (("zstd", z), ("lz4", l4), ("", memoryview(data))):
        with pytest.raises(ChunkRefusedError, match=r"^chunk_size_mismatch: ") as exc:
            d.decompress(comp, payload, len(data) - 1)
        assert exc.value.reason == "chunk_size_mismatch"
    with pytest.raises(ChunkRefusedError, match=r"^unknown_compression: compression 'bz2'"):
        d.decompress("bz2", z, len(data))
    with pytest.raises(ChunkRefusedError, match=r"^chunk_decompression_error: zstd data"):
        d.decompress("zstd", memoryview(b"not zstd at all"), len(data))


def test_crc_check_and_refusal_survive_pickling():
    check_chunk_crc(b"abc", 0x352441C2)
    with pytest.raises(ChunkRefusedError, match="0x352441c2, the chunk states 0x00000001") as e:
        check_chunk_crc(b"abc", 1)
    again = pickle.loads(pickle.dumps(e.value))
    assert (again.reason, again.detail, str(again)) == (e.value.reason, e.value.detail,
                                                        str(e.value))
