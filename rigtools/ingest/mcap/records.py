"""MCAP record layout: magic, opcodes, fixed headers, and parsers that check every length.

Every MCAP record is ``opcode u8, length u64, content``. Inside the content, integers are
little-endian, a string is a ``u32`` byte length followed by UTF-8, and a map is a ``u32``
byte length followed by ``(string, string)`` pairs. Each parser here checks a length against
the end of its record *before* it reads or allocates, and raises
:class:`MalformedRecordError` when a field would run past that end. The container walk
(:mod:`rigtools.ingest.mcap.container`) turns that error into a ``bad_record`` or
``bad_chunk`` count.

Only what the reader uses is parsed: Schema, Channel, Metadata, the message count of
Statistics, the entry count of a MessageIndex and the header of a Chunk. Message records
are unpacked inline by the container with :data:`MESSAGE_HEADER`, because that is the hot
loop.

References
----------
.. [1] Foxglove, "MCAP file format specification", https://mcap.dev/spec (records,
   serialization).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any, Final, NamedTuple

__all__ = [
    "CHUNK_HEAD_MAX_BYTES",
    "FOOTER_AND_MAGIC_BYTES",
    "KNOWN_OPS",
    "MAGIC",
    "MESSAGE_HEADER",
    "MESSAGE_HEADER_BYTES",
    "OP_CHANNEL",
    "OP_CHUNK",
    "OP_DATA_END",
    "OP_FOOTER",
    "OP_HEADER",
    "OP_MESSAGE",
    "OP_MESSAGE_INDEX",
    "OP_METADATA",
    "OP_SCHEMA",
    "OP_STATISTICS",
    "PARSED_OPS",
    "RECORD_HEADER",
    "RECORD_HEADER_BYTES",
    "ChannelRecord",
    "ChunkHeader",
    "MalformedRecordError",
    "SchemaRecord",
    "chunk_content_length",
    "message_index_entry_count",
    "parse_channel",
    "parse_chunk_header",
    "parse_footer",
    "parse_metadata",
    "parse_schema",
    "read_map",
    "read_string",
    "statistics_message_count",
]

MAGIC: Final = b"\x89MCAP0\r\n"

OP_HEADER: Final = 0x01
OP_FOOTER: Final = 0x02
OP_SCHEMA: Final = 0x03
OP_CHANNEL: Final = 0x04
OP_MESSAGE: Final = 0x05
OP_CHUNK: Final = 0x06
OP_MESSAGE_INDEX: Final = 0x07
OP_STATISTICS: Final = 0x0B
OP_METADATA: Final = 0x0C
OP_DATA_END: Final = 0x0F
#: Top-level opcodes whose content the container reads; it skips every other record
#: (MessageIndex too, unless it counts the messages of a refused chunk).
PARSED_OPS: Final = frozenset({OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE,
                               OP_CHUNK, OP_STATISTICS, OP_METADATA, OP_DATA_END})

#: The opcodes the specification defines (Header 0x01 to DataEnd 0x0F).
KNOWN_OPS: Final = frozenset(range(0x01, 0x10))

#: Record header: opcode u8, content length u64 (bytes).
RECORD_HEADER: Final = struct.Struct("<BQ")
RECORD_HEADER_BYTES: Final = RECORD_HEADER.size
#: Message record fields before the payload: channel id u16, sequence u32, log time u64 (ns),
#: publish time u64 (ns).
MESSAGE_HEADER: Final = struct.Struct("<HIQQ")
MESSAGE_HEADER_BYTES: Final = MESSAGE_HEADER.size

# Chunk: message start time u64, message end time u64, uncompressed size u64,
# uncompressed CRC-32 u32, compression name length u32 (then the name, records length u64).
_CHUNK_HEAD: Final = struct.Struct("<QQQII")
# Statistics: message count u64 first; the rest is not used.
_STATS: Final = struct.Struct("<QHIIIIQQ")
# MessageIndex: channel id u16, then the byte length u32 of its (log_time u64, offset u64) array.
_MESSAGE_INDEX_HEAD: Final = 6
_MESSAGE_INDEX_ENTRY: Final = 16
# Footer record with its header: opcode u8, length u64 (20), summary start u64, summary offset
# start u64, summary CRC-32 u32.
_FOOTER: Final = struct.Struct("<BQQQI")
#: A Footer record and the closing magic (bytes).
FOOTER_AND_MAGIC_BYTES: Final = _FOOTER.size + len(MAGIC)
#: Compression names longer than this are taken for damage when a chunk's length is inferred.
_MAX_COMPRESSION_NAME: Final = 255
#: Bytes of a chunk record's content that :func:`chunk_content_length` needs at most.
CHUNK_HEAD_MAX_BYTES: Final = 32 + _MAX_COMPRESSION_NAME + 8
_U16: Final = struct.Struct("<H")
_U32: Final = struct.Struct("<I")
_U64: Final = struct.Struct("<Q")


class MalformedRecordError(Exception):
    """A record shorter than its own fields; the message names the field that runs past it.

    Internal to the MCAP reader: the container counts the record and goes on.
    """


class SchemaRecord(NamedTuple):
    """An MCAP Schema record, as decoders see it.

    Attributes
    ----------
    id : int
        Schema id (0 is "no schema" in MCAP and never reaches a decoder).
    name : str
        Schema name, e.g. ``"rigtools.AccelBatch"``.
    encoding : str
        Schema encoding: ``"protobuf"``, ``"jsonschema"``, ``"ros2msg"``, ...
    data : bytes
        Schema data (a FileDescriptorSet, a JSON Schema, a message definition).
    """

    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class ChannelRecord:
    """An MCAP Channel record: id, schema id (0: none), topic, message encoding, metadata."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str] = field(default_factory=dict)


class ChunkHeader(NamedTuple):
    """The fields of a Chunk record ahead of its compressed records.

    Attributes
    ----------
    uncompressed_size : int
        Size the records state for themselves once decompressed (bytes).
    uncompressed_crc : int
        CRC-32 of the decompressed records; 0 when the writer gave none.
    compression : str
        ``""``, ``"zstd"``, ``"lz4"`` or whatever the writer named.
    records_offset : int
        Offset of the compressed records in the chunk record's content (bytes).
    records_size : int
        Length of the compressed records (bytes); checked to fit in the content.
    """

    uncompressed_size: int
    uncompressed_crc: int
    compression: str
    records_offset: int
    records_size: int


def read_string(buf: Any, pos: int, end: int) -> tuple[str, int]:
    """A length-prefixed UTF-8 string at ``buf[pos:end]`` and the position after it.

    Raises
    ------
    MalformedRecordError
        The length prefix or the string runs past ``end``.
    """
    if pos + 4 > end:
        raise MalformedRecordError("string length")
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    if n > end - pos:
        raise MalformedRecordError(f"string of {n} bytes")
    return str(buf[pos : pos + n], "utf-8", "replace"), pos + n


def read_map(buf: Any, pos: int, end: int) -> tuple[dict[str, str], int]:
    """A length-prefixed string-to-string map at ``buf[pos:end]`` and the position after it.

    Raises
    ------
    MalformedRecordError
        The length prefix, the map or one of its strings runs past its end.
    """
    if pos + 4 > end:
        raise MalformedRecordError("map length")
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    stop = pos + n
    if stop > end:
        raise MalformedRecordError(f"map of {n} bytes")
    out: dict[str, str] = {}
    while pos < stop:
        k, pos = read_string(buf, pos, stop)
        v, pos = read_string(buf, pos, stop)
        out[k] = v
    return out, stop


def parse_schema(buf: Any, pos: int, end: int) -> SchemaRecord:
    """The Schema record whose content is ``buf[pos:end]`` (its id may be 0: no schema).

    Raises
    ------
    MalformedRecordError
        A field runs past ``end``.
    """
    if pos + 2 > end:
        raise MalformedRecordError("schema id")
    (sid,) = _U16.unpack_from(buf, pos)
    name, p = read_string(buf, pos + 2, end)
    enc, p = read_string(buf, p, end)
    if p + 4 > end:
        raise MalformedRecordError("schema data length")
    (n,) = _U32.unpack_from(buf, p)
    if n > end - p - 4:
        raise MalformedRecordError(f"schema data of {n} bytes")
    return SchemaRecord(sid, name, enc, bytes(buf[p + 4 : p + 4 + n]))


def parse_channel(buf: Any, pos: int, end: int) -> ChannelRecord:
    """The Channel record whose content is ``buf[pos:end]``.

    Raises
    ------
    MalformedRecordError
        A field runs past ``end``.
    """
    if pos + 4 > end:
        raise MalformedRecordError("channel and schema ids")
    (cid,) = _U16.unpack_from(buf, pos)
    (sid,) = _U16.unpack_from(buf, pos + 2)
    topic, p = read_string(buf, pos + 4, end)
    enc, p = read_string(buf, p, end)
    meta, p = read_map(buf, p, end)
    return ChannelRecord(cid, sid, topic, enc, meta)


def parse_metadata(buf: bytes) -> tuple[str, dict[str, str]]:
    """Name and key/values of the Metadata record whose content is ``buf``.

    Raises
    ------
    MalformedRecordError
        A field runs past the end of ``buf``.
    """
    name, p = read_string(buf, 0, len(buf))
    meta, _ = read_map(buf, p, len(buf))
    return name, meta


def statistics_message_count(buf: bytes) -> int | None:
    """The message count of a Statistics record's content; None when it is too short."""
    if len(buf) < _STATS.size:
        return None
    count: int = _STATS.unpack_from(buf, 0)[0]
    return count


def message_index_entry_count(buf: bytes) -> int:
    """How many ``(log_time, offset)`` entries a MessageIndex record's content holds.

    Entries the stated array length claims beyond the end of ``buf`` are not counted; a
    content too short for its own header holds none.
    """
    if len(buf) < _MESSAGE_INDEX_HEAD:
        return 0
    (nbytes,) = _U32.unpack_from(buf, 2)
    return min(nbytes, len(buf) - _MESSAGE_INDEX_HEAD) // _MESSAGE_INDEX_ENTRY


def parse_chunk_header(content: bytes) -> ChunkHeader:
    """The header fields of a Chunk record, with its compressed records checked to fit.

    Raises
    ------
    MalformedRecordError
        The content is shorter than a chunk header, its compression name does not fit, or
        the records it claims run past its end.
    """
    n = len(content)
    if n < _CHUNK_HEAD.size:
        raise MalformedRecordError(f"record of {n} bytes is shorter than a chunk header")
    _start, _end, usize, crc, clen = _CHUNK_HEAD.unpack_from(content, 0)
    off = _CHUNK_HEAD.size
    if clen > n - off - 8:
        raise MalformedRecordError(f"compression name of {clen} bytes does not fit")
    compression = str(content[off : off + clen], "ascii", "replace")
    off += clen
    (rlen,) = _U64.unpack_from(content, off)
    off += 8
    if rlen > n - off:
        raise MalformedRecordError(f"records of {rlen} bytes claimed, {n - off} left in the "
                                   "chunk record")
    return ChunkHeader(usize, crc, compression, off, rlen)


def chunk_content_length(head: Any) -> int | None:
    """The content length a chunk record's own fields imply: its header and compressed records.

    ``head`` is the start of the content (at least up to the records length field, at most
    :data:`CHUNK_HEAD_MAX_BYTES` are used). None when ``head`` is too short for those fields
    or the compression name is implausibly long. Lets the walk read a chunk whose record
    length field is damaged (bytes).
    """
    n = len(head)
    if n < _CHUNK_HEAD.size + 8:
        return None
    clen = _CHUNK_HEAD.unpack_from(head, 0)[4]
    off = _CHUNK_HEAD.size + clen
    if clen > _MAX_COMPRESSION_NAME or off + 8 > n:
        return None
    (rlen,) = _U64.unpack_from(head, off)
    return int(off + 8 + rlen)


def parse_footer(tail: Any) -> tuple[int, int, int, bytes] | None:
    """Summary start, summary offset start, summary CRC and CRC'd footer bytes of a file's end.

    ``tail`` is the last :data:`FOOTER_AND_MAGIC_BYTES` bytes of the file. None when they are
    not a Footer record (opcode 0x02, length 20) followed by the magic. The fourth item is the
    part of the Footer the summary CRC covers after the summary section (opcode, length and the
    two offsets), as the specification defines it [1]_.
    """
    if len(tail) != FOOTER_AND_MAGIC_BYTES or bytes(tail[_FOOTER.size :]) != MAGIC:
        return None
    op, length, start, offset_start, crc = _FOOTER.unpack_from(tail, 0)
    if op != OP_FOOTER or length != _FOOTER.size - RECORD_HEADER_BYTES:
        return None
    return start, offset_start, crc, bytes(tail[: _FOOTER.size - 4])
