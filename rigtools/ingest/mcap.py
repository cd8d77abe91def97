"""MCAP reader: a streaming container parser and the ingest of rig messages into a Recording.

Two layers:

* the container (:func:`iter_messages`): the file is read from the start, record by record
  (opcode u8, length u64, content), every length checked against what remains before
  anything is read or allocated. Chunks are checked against stated size limits
  (:data:`MAX_CHUNK_UNCOMPRESSED_BYTES`, :data:`MAX_CHUNK_RATIO`) *before* decompressing,
  decompressed with a bounded output (zstd, lz4 frame) and checked against their CRC. Nothing
  depends on the summary section, so files without summary or indexes, and files cut short,
  are read as far as they are intact;
* the ingest (:func:`ingest`): messages are decoded per channel by the decoders of
  :mod:`rigtools.ingest.mcap_decoders` and handed to a
  :class:`~rigtools.ingest.builder.RecordingBuilder` chunk by chunk.

Every message is either decoded or counted in the :class:`IngestReport` (``units`` is
``"messages"``) under one of these reasons:

=========================  ===================================================================
reason                     what happened
=========================  ===================================================================
``no_decoder``             no decoder for the channel's message encoding and schema
``not_in_mapping``         a mapping was given and does not name the topic
``bad_schema``             the schema names a known type but does not parse or differs
``decode_error``           the payload does not decode under its schema
``unknown_channel``        a message names a channel id no Channel record in the file defines
``absurd_chunk_size``      a chunk claims an uncompressed size beyond the limits
``chunk_crc_mismatch``     a chunk's data does not match its ``uncompressed_crc``
``chunk_decompression_``   the compressed data of a chunk does not decompress
``error``
``chunk_size_mismatch``    a chunk decompresses to another size than it states
``unknown_compression``    a chunk compression other than ``""``, ``zstd``, ``lz4``
``bad_chunk``              a chunk record too short for its own header fields
``bad_chunk_record``       a record inside a chunk runs past the chunk's end
``bad_record``             a record too short for its own fields
``oversized_record``       a top-level record longer than :data:`MAX_RECORD_BYTES` (skipped)
``truncated_record``       the file ends inside a record, or before its DataEnd record
=========================  ===================================================================

Messages of a refused chunk are counted by the entries of the message indexes that follow
it when the file has them; otherwise the chunk counts as one. A message whose channel is not
defined where it appears (its Channel record was in a refused chunk) is held, and read at the
end of the file if the summary's repeated Channel records define it.
"""

from __future__ import annotations

import io
import math
import os
import stat
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, BinaryIO, Final, NamedTuple

import numpy as np

from rigtools.errors import MappingError, RecordingFormatError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap_decoders import (
    Decoder,
    PayloadDecodeError,
    SchemaRecord,
    SchemaUnusableError,
    decoder_for,
    get_field,
    message_stamp_ns,
)
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.timebase import indices_from_stamps

__all__ = [
    "KIND",
    "MAGIC",
    "MAX_CHUNK_RATIO",
    "MAX_CHUNK_UNCOMPRESSED_BYTES",
    "MAX_DEFERRED_BYTES",
    "MAX_RECORD_BYTES",
    "NAME",
    "RUN_METADATA_NAME",
    "ChannelRecord",
    "RawMessage",
    "ingest",
    "iter_messages",
    "sniff",
]

NAME: Final = "mcap"
KIND: Final = "mcap"
MAGIC: Final = b"\x89MCAP0\r\n"
#: Name of the Metadata record holding run metadata (keys ``run_id``, ``rig``, ``gear_set``,
#: ``conditions.<name_with_unit>``; values as strings).
RUN_METADATA_NAME: Final = "rigtools.run"

#: A chunk may claim at most this many bytes uncompressed (1 GiB) ...
MAX_CHUNK_UNCOMPRESSED_BYTES: Final = 1 << 30
#: ... and, above :data:`FREE_CHUNK_BYTES`, at most this many times its compressed size.
MAX_CHUNK_RATIO: Final = 1000
#: Chunks up to this uncompressed size (16 MiB) are decompressed whatever their ratio.
FREE_CHUNK_BYTES: Final = 16 << 20
#: Top-level records longer than this (2 GiB) are skipped and counted ``oversized_record``.
MAX_RECORD_BYTES: Final = 2 << 30
#: Read size for streams whose length is unknown (gzip): allocation follows the data read.
_READ_PIECE: Final = 1 << 20
#: Messages naming a channel not (yet) defined are held, up to this many payload bytes
#: (64 MiB), until the summary's repeated Channel records may define it.
MAX_DEFERRED_BYTES: Final = 64 << 20

_OP_HEADER, _OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE = 0x01, 0x02, 0x03, 0x04, 0x05
_OP_CHUNK, _OP_MESSAGE_INDEX, _OP_STATISTICS, _OP_METADATA, _OP_DATA_END = (
    0x06, 0x07, 0x0B, 0x0C, 0x0F)
_PARSED_OPS: Final = frozenset({_OP_HEADER, _OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE,
                                _OP_CHUNK, _OP_STATISTICS, _OP_METADATA, _OP_DATA_END})

_HDR = struct.Struct("<BQ")
_MSG = struct.Struct("<HIQQ")
_CHUNK_HEAD = struct.Struct("<QQQII")
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_STATS = struct.Struct("<QHIIIIQQ")
_MAX_WARNINGS_PER_REASON = 5


class RawMessage(NamedTuple):
    """One MCAP Message record with what its channel and schema say about it.

    Attributes
    ----------
    channel_id : int
    topic : str
    schema_name, schema_encoding : str
        Empty for schemaless channels.
    message_encoding : str
    log_time, publish_time : int
        Nanoseconds (the file's clock, usually the UNIX epoch).
    sequence : int
    data : bytes
        The payload.
    """

    channel_id: int
    topic: str
    schema_name: str
    schema_encoding: str
    message_encoding: str
    log_time: int
    publish_time: int
    sequence: int
    data: bytes


@dataclass(frozen=True)
class ChannelRecord:
    """An MCAP Channel record: id, schema id (0: none), topic, message encoding, metadata."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str] = field(default_factory=dict)


def sniff(head: bytes) -> bool:
    r"""True when ``head`` starts with the MCAP magic ``\x89MCAP0\r\n``."""
    return head[:8] == MAGIC


# --------------------------------------------------------------------------------------
# Byte source
# --------------------------------------------------------------------------------------


def _known_size(stream: BinaryIO) -> int | None:
    """Bytes from the current position to the end, when cheap to know; else None."""
    if isinstance(stream, io.BytesIO):
        with stream.getbuffer() as b:
            return len(b) - stream.tell()
    if isinstance(stream, io.BufferedReader | io.FileIO):
        st = os.fstat(stream.fileno())
        if stat.S_ISREG(st.st_mode):
            return max(0, st.st_size - stream.tell())
    return None


class _Source:
    """Sequential reads with a position, never allocating more than the data that exists."""

    def __init__(self, stream: BinaryIO) -> None:
        self._f = stream
        self.pos = 0
        self._size = _known_size(stream)
        self._seekable = self._size is not None

    def remaining(self) -> int | None:
        return None if self._size is None else self._size - self.pos

    def read(self, n: int) -> bytes:
        rem = self.remaining()
        if rem is not None:
            n = min(n, rem)
            data = self._f.read(n)
            if len(data) == n:
                self.pos += n
                return data
            pieces, got = [data], len(data)
        else:
            pieces, got = [], 0
        while got < n:
            piece = self._f.read(min(_READ_PIECE, n - got))
            if not piece:
                break
            pieces.append(piece)
            got += len(piece)
        self.pos += got
        return pieces[0] if len(pieces) == 1 else b"".join(pieces)

    def skip(self, n: int) -> int:
        rem = self.remaining()
        if rem is not None:
            n = min(n, rem)
            if self._seekable:
                self._f.seek(n, io.SEEK_CUR)
            else:
                self._f.read(n)
            self.pos += n
            return n
        got = 0
        while got < n:
            piece = self._f.read(min(_READ_PIECE, n - got))
            if not piece:
                break
            got += len(piece)
        self.pos += got
        return got


# --------------------------------------------------------------------------------------
# Record field helpers (all bounds-checked; _MalformedError when a field runs past the record)
# --------------------------------------------------------------------------------------


class _MalformedError(Exception):
    """A record shorter than its fields (internal; turned into a ``bad_record`` count)."""


def _str(buf: Any, pos: int, end: int) -> tuple[str, int]:
    if pos + 4 > end:
        raise _MalformedError("string length")
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    if n > end - pos:
        raise _MalformedError(f"string of {n} bytes")
    return str(buf[pos : pos + n], "utf-8", "replace"), pos + n


def _map(buf: Any, pos: int, end: int) -> tuple[dict[str, str], int]:
    if pos + 4 > end:
        raise _MalformedError("map length")
    (n,) = _U32.unpack_from(buf, pos)
    pos += 4
    stop = pos + n
    if stop > end:
        raise _MalformedError(f"map of {n} bytes")
    out: dict[str, str] = {}
    while pos < stop:
        k, pos = _str(buf, pos, stop)
        v, pos = _str(buf, pos, stop)
        out[k] = v
    return out, stop


# --------------------------------------------------------------------------------------
# The container scanner
# --------------------------------------------------------------------------------------

#: A message as the scanner hands it on: (channel_id, sequence, log_time, publish_time, data,
#: offset of data in its block's buffer, or -1 when the block has no common buffer).
_Msg = tuple[int, int, int, int, memoryview, int]


class _Scanner:
    """Stream an MCAP file's records from the start; yield messages chunk by chunk."""

    def __init__(self, stream: BinaryIO, path: str, report: IngestReport,
                 validate_crcs: bool = True) -> None:
        self.path = path
        self.report = report
        self.validate_crcs = validate_crcs
        self.schemas: dict[int, SchemaRecord] = {}
        self.channels: dict[int, ChannelRecord] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        self.statistics_message_count: int | None = None
        self.n_message_records = 0
        self._src = _Source(stream)
        self._pending: tuple[str, str] | None = None
        self._pending_count = 0
        self._warned: dict[str, int] = {}
        self._zstd: Any = None
        self._deferred: list[tuple[_Msg, str]] = []
        self._deferred_bytes = 0

    # -- accounting ----------------------------------------------------------------------

    def _warn(self, reason: str, text: str) -> None:
        n = self._warned.get(reason, 0)
        self._warned[reason] = n + 1
        if n < _MAX_WARNINGS_PER_REASON:
            self.report.warn(text)
        elif n == _MAX_WARNINGS_PER_REASON:
            self.report.warn(f"{reason}: further occurrences not listed (see the tallies)")

    def _refuse_chunk(self, reason: str, pos: int, detail: str) -> None:
        """Refuse a chunk; its messages are counted once the following indexes are seen."""
        self._flush_pending()
        self._pending = (reason, f"byte {pos}")
        self._pending_count = 0
        self._warn(reason, f"{self.path}: chunk at byte {pos} not used ({reason}): {detail}")

    def _flush_pending(self) -> None:
        if self._pending is not None:
            reason, where = self._pending
            n = self._pending_count
            self.report.reject(reason, n if n > 0 else 1, where)
            self.n_message_records += n
            self._pending = None
            self._pending_count = 0

    # -- records -------------------------------------------------------------------------

    def _schema(self, buf: Any, pos: int, end: int, where: str) -> None:
        try:
            if pos + 2 > end:
                raise _MalformedError("schema id")
            (sid,) = _U16.unpack_from(buf, pos)
            name, p = _str(buf, pos + 2, end)
            enc, p = _str(buf, p, end)
            if p + 4 > end:
                raise _MalformedError("schema data length")
            (n,) = _U32.unpack_from(buf, p)
            if n > end - p - 4:
                raise _MalformedError(f"schema data of {n} bytes")
            data = bytes(buf[p + 4 : p + 4 + n])
        except _MalformedError as exc:
            self.report.reject("bad_record", 1, where)
            self._warn("bad_record", f"{self.path}: malformed Schema record at {where}: {exc}")
            return
        if sid == 0:
            return
        rec = SchemaRecord(sid, name, enc, data)
        old = self.schemas.setdefault(sid, rec)
        if old != rec:
            self._warn("schema_redefined", f"{self.path}: schema id {sid} redefined at {where}"
                       "; the first definition is kept")

    def _channel(self, buf: Any, pos: int, end: int, where: str) -> None:
        try:
            if pos + 4 > end:
                raise _MalformedError("channel and schema ids")
            (cid,) = _U16.unpack_from(buf, pos)
            (sid,) = _U16.unpack_from(buf, pos + 2)
            topic, p = _str(buf, pos + 4, end)
            enc, p = _str(buf, p, end)
            meta, p = _map(buf, p, end)
        except _MalformedError as exc:
            self.report.reject("bad_record", 1, where)
            self._warn("bad_record", f"{self.path}: malformed Channel record at {where}: {exc}")
            return
        rec = ChannelRecord(cid, sid, topic, enc, meta)
        old = self.channels.setdefault(cid, rec)
        if old != rec:
            self._warn("channel_redefined", f"{self.path}: channel id {cid} redefined at "
                       f"{where}; the first definition is kept")

    def _metadata(self, buf: bytes, where: str) -> None:
        try:
            name, p = _str(buf, 0, len(buf))
            meta, _ = _map(buf, p, len(buf))
        except _MalformedError as exc:
            self.report.reject("bad_record", 1, where)
            self._warn("bad_record", f"{self.path}: malformed Metadata record at {where}: {exc}")
            return
        self.metadata.setdefault(name, {}).update(meta)

    def _statistics(self, buf: bytes) -> None:
        if len(buf) >= _STATS.size:
            self.statistics_message_count = _STATS.unpack_from(buf, 0)[0]

    def _message_index(self, buf: bytes) -> None:
        # channel_id u16, then an array (u32 byte length) of (log_time u64, offset u64).
        if self._pending is not None and len(buf) >= 6:
            (nbytes,) = _U32.unpack_from(buf, 2)
            self._pending_count += min(nbytes, len(buf) - 6) // 16

    # -- chunks --------------------------------------------------------------------------

    def _decompress(self, compression: str, comp: memoryview, usize: int,
                    pos: int) -> memoryview | bytes | None:
        if compression == "":
            if len(comp) != usize:
                self._refuse_chunk("chunk_size_mismatch", pos, f"uncompressed chunk of "
                                   f"{len(comp)} bytes states {usize}")
                return None
            return comp
        import zstandard

        try:
            if compression == "zstd":
                if self._zstd is None:
                    self._zstd = zstandard.ZstdDecompressor()
                reader = self._zstd.stream_reader(comp, read_across_frames=True)
                parts, got = [], 0
                while got < usize:
                    piece = reader.read(usize - got)
                    if not piece:
                        break
                    parts.append(piece)
                    got += len(piece)
                extra = reader.read(1)
                data = parts[0] if len(parts) == 1 else b"".join(parts)
            elif compression == "lz4":
                import lz4.frame

                d = lz4.frame.LZ4FrameDecompressor()
                data = d.decompress(comp, max_length=usize)
                extra = b"" if d.eof else b"?"
            else:
                self._refuse_chunk("unknown_compression", pos,
                                   f"compression {compression!r} (known: '', 'zstd', 'lz4')")
                return None
        except (zstandard.ZstdError, RuntimeError, ValueError, OSError) as exc:
            # ZstdError from zstandard; RuntimeError from lz4.frame on corrupt frames.
            self._refuse_chunk("chunk_decompression_error", pos,
                               f"{compression} data does not decompress: {exc}")
            return None
        if len(data) != usize or extra:
            self._refuse_chunk("chunk_size_mismatch", pos, f"{compression} data decompresses to "
                               f"{'more than ' if extra else ''}{len(data)} bytes, the chunk "
                               f"states {usize}")
            return None
        return data

    def _chunk(self, content: bytes, pos: int) -> tuple[Any, list[_Msg]]:
        n = len(content)
        if n < _CHUNK_HEAD.size:
            self._refuse_chunk("bad_chunk", pos, f"record of {n} bytes is shorter than a chunk "
                               "header")
            return None, []
        _start, _end, usize, crc, clen = _CHUNK_HEAD.unpack_from(content, 0)
        off = _CHUNK_HEAD.size
        if clen > n - off - 8:
            self._refuse_chunk("bad_chunk", pos, f"compression name of {clen} bytes does not fit")
            return None, []
        compression = str(content[off : off + clen], "ascii", "replace")
        off += clen
        (rlen,) = _U64.unpack_from(content, off)
        off += 8
        if rlen > n - off:
            self._refuse_chunk("bad_chunk", pos, f"records of {rlen} bytes claimed, {n - off} "
                               "left in the chunk record")
            return None, []
        limit = min(MAX_CHUNK_UNCOMPRESSED_BYTES, max(FREE_CHUNK_BYTES, MAX_CHUNK_RATIO * rlen))
        if usize > limit:
            self._refuse_chunk("absurd_chunk_size", pos, f"claims {usize} bytes uncompressed "
                               f"from {rlen} compressed; the limit is {limit} (at most "
                               f"{MAX_CHUNK_UNCOMPRESSED_BYTES} bytes, and {MAX_CHUNK_RATIO}x "
                               f"the compressed size above {FREE_CHUNK_BYTES})")
            return None, []
        if usize == 0:
            return None, []
        data = self._decompress(compression, memoryview(content)[off : off + rlen], usize, pos)
        if data is None:
            return None, []
        if self.validate_crcs and crc != 0:
            got = zlib.crc32(data)
            if got != crc:
                self._refuse_chunk("chunk_crc_mismatch", pos, f"CRC-32 of the uncompressed "
                                   f"data is 0x{got:08x}, the chunk states 0x{crc:08x}")
                return None, []
        buf = memoryview(data)
        return buf, self._chunk_records(buf, pos)

    def _chunk_records(self, buf: memoryview, cpos: int) -> list[_Msg]:
        out: list[_Msg] = []
        append = out.append
        channels = self.channels
        unpack_hdr, unpack_msg = _HDR.unpack_from, _MSG.unpack_from
        n = len(buf)
        pos = 0
        n_msg = 0
        while pos < n:
            if n - pos < 9:
                self._bad_in_chunk(cpos, pos, f"{n - pos} stray bytes at the end")
                break
            op, length = unpack_hdr(buf, pos)
            body = pos + 9
            if length > n - body:
                self._bad_in_chunk(cpos, pos, f"record of {length} bytes, {n - body} left")
                break
            stop = body + length
            if op == _OP_MESSAGE:
                n_msg += 1
                if length < 22:
                    self.report.reject("bad_record", 1, f"chunk at byte {cpos} +{pos}")
                else:
                    cid, seq, lt, pt = unpack_msg(buf, body)
                    if cid in channels:
                        append((cid, seq, lt, pt, buf[body + 22 : stop], body + 22))
                    else:
                        self._defer(cid, seq, lt, pt, buf[body + 22 : stop],
                                    f"chunk at byte {cpos} +{pos}")
            elif op == _OP_SCHEMA:
                self._schema(buf, body, stop, f"chunk at byte {cpos} +{pos}")
            elif op == _OP_CHANNEL:
                self._channel(buf, body, stop, f"chunk at byte {cpos} +{pos}")
            pos = stop
        self.n_message_records += n_msg
        return out

    def _bad_in_chunk(self, cpos: int, pos: int, detail: str) -> None:
        where = f"chunk at byte {cpos} +{pos}"
        self.report.reject("bad_chunk_record", 1, where)
        self._warn("bad_chunk_record", f"{self.path}: {where}: {detail}; the rest of the chunk "
                   "is not used")

    def _defer(self, cid: int, seq: int, lt: int, pt: int, data: Any, where: str) -> None:
        """Hold a message whose channel is not defined yet.

        Its Channel record may have been in a refused chunk; indexed files repeat every
        Channel record in the summary.
        """
        if self._deferred_bytes + len(data) > MAX_DEFERRED_BYTES:
            self._unknown_channel(cid, where)
            return
        self._deferred_bytes += len(data)
        self._deferred.append(((cid, seq, lt, pt, memoryview(bytes(data)), -1), where))

    def _release_deferred(self) -> list[_Msg]:
        out = []
        for msg, where in self._deferred:
            if msg[0] in self.channels:
                out.append(msg)
            else:
                self._unknown_channel(msg[0], where)
        if out:
            self.report.warn(f"{self.path}: {len(out)} message(s) came before the Channel "
                             "record defining their channel (found in the summary); they were "
                             "read last")
        self._deferred = []
        self._deferred_bytes = 0
        return out

    def _unknown_channel(self, cid: int, where: str) -> None:
        self.report.reject("unknown_channel", 1, where)
        self._warn("unknown_channel", f"{self.path}: message at {where} names channel id {cid}, "
                   "which no Channel record in the file defines")

    # -- the stream ----------------------------------------------------------------------

    def blocks(self) -> Iterator[tuple[str, Any, list[_Msg]]]:
        """Yield ``(position, buffer, messages)`` in file order.

        One block per chunk (with the chunk's uncompressed data as ``buffer``), and blocks
        of the messages found directly in the data section (``buffer`` None).

        Raises
        ------
        RecordingFormatError
            The file is empty or does not start with the MCAP magic.
        """
        src = self._src
        head = src.read(8)
        if head != MAGIC:
            raise RecordingFormatError(
                self.path, 0, f"the MCAP magic {MAGIC!r}",
                "an empty file" if not head else repr(head),
            )
        direct: list[_Msg] = []
        direct_pos = ""
        data_end = False
        first = True
        while True:
            pos = src.pos
            hdr = src.read(9)
            if len(hdr) < 9:
                self._flush_pending()
                want = "a Footer" if data_end else "a DataEnd record and Footer"
                self._ended(pos, data_end, "a record header" if hdr else want,
                            f"{len(hdr)} bytes" if hdr else "the end of the file")
                break
            op, length = _HDR.unpack(hdr)
            if first and op != _OP_HEADER:
                self.report.warn(f"{self.path}: the first record is opcode 0x{op:02x}, not a "
                                 "Header")
            first = False
            if op != _OP_MESSAGE_INDEX:
                self._flush_pending()
            rem = src.remaining()
            if rem is not None and length > rem:
                self._ended(pos, data_end, f"a record of {length} bytes (opcode 0x{op:02x})",
                            f"{rem} bytes left in the file")
                break
            if op not in _PARSED_OPS and not (op == _OP_MESSAGE_INDEX and self._pending):
                if src.skip(length) < length:
                    self._ended(pos, data_end, f"a record of {length} bytes (opcode "
                                f"0x{op:02x})", "the end of the file")
                    break
                continue
            if length > MAX_RECORD_BYTES:
                self.report.reject("oversized_record", 1, f"byte {pos}")
                self._warn("oversized_record", f"{self.path}: record at byte {pos} (opcode "
                           f"0x{op:02x}) of {length} bytes exceeds {MAX_RECORD_BYTES}; skipped")
                if src.skip(length) < length:
                    self._ended(pos, data_end, f"a record of {length} bytes",
                                "the end of the file")
                    break
                continue
            content = src.read(length)
            if len(content) < length:
                self._ended(pos, data_end, f"a record of {length} bytes (opcode 0x{op:02x})",
                            f"{len(content)} bytes")
                break
            where = f"byte {pos}"
            if op == _OP_MESSAGE:
                self.n_message_records += 1
                if length < 22:
                    self.report.reject("bad_record", 1, where)
                    continue
                cid, seq, lt, pt = _MSG.unpack_from(content, 0)
                if cid not in self.channels:
                    self._defer(cid, seq, lt, pt, memoryview(content)[22:], where)
                    continue
                if not direct:
                    direct_pos = where
                direct.append((cid, seq, lt, pt, memoryview(content)[22:], -1))
                if len(direct) >= 4096:
                    yield direct_pos, None, direct
                    direct = []
                continue
            if direct:
                yield direct_pos, None, direct
                direct = []
            if op == _OP_CHUNK:
                buf, msgs = self._chunk(content, pos)
                del content
                if msgs:
                    yield where, buf, msgs
                del buf, msgs
            elif op == _OP_SCHEMA:
                self._schema(content, 0, length, where)
            elif op == _OP_CHANNEL:
                self._channel(content, 0, length, where)
            elif op == _OP_METADATA:
                self._metadata(content, where)
            elif op == _OP_MESSAGE_INDEX:
                self._message_index(content)
            elif op == _OP_STATISTICS:
                self._statistics(content)
            elif op == _OP_DATA_END:
                data_end = True
            elif op == _OP_FOOTER:
                if src.read(8) != MAGIC:
                    self.report.warn(f"{self.path}: no closing magic after the Footer at {where}")
                break
        if direct:
            yield direct_pos, None, direct
        self._flush_pending()
        late = self._release_deferred()
        if late:
            yield "the end of the file (deferred messages)", None, late
        self._cross_check()

    def _ended(self, pos: int, data_end: bool, expected: str, found: str) -> None:
        """The file ends early: a loss in the data section, a warning in the summary."""
        if data_end:
            self.report.warn(f"{self.path}: the file ends at byte {pos} inside its summary "
                             f"section (expected {expected}, found {found}); no data lost")
            return
        self.report.reject("truncated_record", 1, f"byte {pos}")
        self.report.warn(f"{self.path}: the file is cut at byte {pos}: expected {expected}, "
                         f"found {found}; everything before it was read")

    def _cross_check(self) -> None:
        n = self.statistics_message_count
        if n is not None and n != self.n_message_records and not self.report.rejected.get(
                "truncated_record"):
            self.report.warn(f"{self.path}: the Statistics record counts {n} messages, "
                             f"{self.n_message_records} Message records were found")


# --------------------------------------------------------------------------------------
# Container layer: public iteration
# --------------------------------------------------------------------------------------


def iter_messages(stream: BinaryIO, path: str, report: IngestReport,
                  *, validate_crcs: bool = True) -> Iterator[RawMessage]:
    """Iterate over the Message records of an MCAP stream, in file order.

    Parameters
    ----------
    stream : binary file object
        Positioned at the start of the MCAP data (a file, ``gzip`` stream or ``BytesIO``).
    path : str
        For messages and errors.
    report : IngestReport
        Receives the losses (see the module docstring for the reasons).
    validate_crcs : bool
        Check chunk CRCs (default). A mismatching chunk's messages are counted, not yielded.

    Yields
    ------
    RawMessage
        Every intact message whose channel is defined, with its payload bytes, in file
        order (but for messages whose Channel record only the summary holds: those last).

    Raises
    ------
    RecordingFormatError
        The stream is empty or does not start with the MCAP magic.
    """
    sc = _Scanner(stream, path, report, validate_crcs)
    for _where, _buf, msgs in sc.blocks():
        for cid, seq, lt, pt, data, _start in msgs:
            ch = sc.channels[cid]
            sch = sc.schemas.get(ch.schema_id)
            yield RawMessage(cid, ch.topic, sch.name if sch else "", sch.encoding if sch else "",
                             ch.message_encoding, lt, pt, seq, bytes(data))


# --------------------------------------------------------------------------------------
# Ingest: handlers per channel
# --------------------------------------------------------------------------------------


class _Handler:
    """Turns the messages of one channel into builder input; subclasses per payload kind."""

    def __init__(self, ctx: _Context, channel: ChannelRecord) -> None:
        self.ctx = ctx
        self.channel = channel

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        raise NotImplementedError

    def finish(self) -> None:
        """Hand anything collected over the whole file to the builder."""

    def _decode_error(self, exc: Exception, where: str, n: int = 1) -> None:
        self.ctx.report.reject("decode_error", n, where)
        self.ctx.warn_once("decode_error", self.channel.id,
                           f"{self.ctx.path}: topic {self.channel.topic!r}: payload does not "
                           f"decode ({exc}); such messages are counted as decode_error")


class _Reject(_Handler):
    def __init__(self, ctx: _Context, channel: ChannelRecord, reason: str) -> None:
        super().__init__(ctx, channel)
        self.reason = reason

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        self.ctx.report.reject(self.reason, len(msgs), where)


@dataclass
class _BatchAcc:
    """Per-message decoded batches of one (channel, unit, rate), within one chunk."""

    firsts: list[int] = field(default_factory=list)
    stamps: list[int] = field(default_factory=list)
    counts: list[int] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)


class _BatchHandler(_Handler):
    """rigtools.AccelBatch: the sample counter gives the index; one builder block per chunk."""

    def __init__(self, ctx: _Context, channel: ChannelRecord, decoder: Decoder,
                 spec: UniformSpec | None) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode
        self.decode_many = decoder.decode_many
        self.spec = spec
        self.rate_warned = False

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        if buf is not None and self.decode_many is not None and len(msgs) > 1:
            starts = np.fromiter((m[5] for m in msgs), np.int64, len(msgs))
            ends = starts + np.fromiter((len(m[4]) for m in msgs), np.int64, len(msgs))
            cols = self.decode_many(buf, starts, ends)
            if cols is not None:
                self.ctx.report.decoded += len(msgs)
                self._flush(cols.channel, cols.unit, cols.sample_rate_Hz,
                            [(cols.first_sample_index, cols.values, cols.stamp_ns)])
                return
        decode = self.decode
        accs: dict[tuple[str, str, float], _BatchAcc] = {}
        n_ok = 0
        for m in msgs:
            try:
                b = decode(m[4])
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            n_ok += 1
            key = (b.channel, b.unit, b.sample_rate_Hz)
            acc = accs.get(key)
            if acc is None:
                acc = accs[key] = _BatchAcc()
            acc.firsts.append(b.first_sample_index)
            acc.stamps.append(b.stamp_ns)
            acc.counts.append(b.values.shape[0])
            acc.values.append(b.values)
        self.ctx.report.decoded += n_ok
        for (name, unit, rate), acc in accs.items():
            firsts = np.asarray(acc.firsts, np.int64)
            stamps = np.asarray(acc.stamps, np.uint64)
            blocks = []
            # Runs of consecutive batches of equal width go to the builder as one 2-D block
            # (row starts = counters), in arrival order; empty batches add nothing.
            counts = acc.counts
            i = 0
            while i < len(counts):
                j = i + 1
                while j < len(counts) and counts[j] == counts[i]:
                    j += 1
                if counts[i]:
                    vals = np.concatenate(acc.values[i:j]).reshape(j - i, counts[i])
                    blocks.append((firsts[i:j], vals, stamps[i:j]))
                i = j
            acc.values.clear()
            self._flush(name, unit, rate, blocks)

    def _flush(self, name: str, unit: str, rate: float,
               blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
        """Hand 2-D blocks (row counters, float32 rows, row stamps in ns) to the builder."""
        spec = self.spec
        conversion: tuple[tuple[float, float], ...] = ()
        if spec is not None:
            if not self.rate_warned and not math.isclose(rate, spec.sample_rate_Hz,
                                                         rel_tol=1e-9):
                self.rate_warned = True
                self.ctx.report.warn(f"topic {self.channel.topic!r}: batches state "
                                     f"{rate} Hz, the mapping {spec.sample_rate_Hz} Hz; the "
                                     "mapping's rate is used")
            name, rate = spec.channel, spec.sample_rate_Hz
            unit = spec.unit if spec.unit is not None else unit
            if spec.scale != 1.0 or spec.offset != 0.0:
                conversion = ((spec.scale, spec.offset),)
        elif not name:
            name = self.channel.topic.lstrip("/") or f"channel_{self.channel.id}"
        for starts, values, stamps_ns in blocks:
            # the stamp of values[0] of each row, on the row's counter: places index 0 on the
            # logger clock (the builder drops both if the block's unit or rate differ)
            self.ctx.builder.add_samples(name, unit, rate, starts, values, stamp_index=starts,
                                         stamps_s=stamps_ns.astype(np.float64) * 1e-9,
                                         conversion=conversion)


class _ImuHandler(_Handler):
    """sensor_msgs/msg/Imu: three channels ``<topic>/linear_acceleration.x|y|z``."""

    def __init__(self, ctx: _Context, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode
        self.rows: list[tuple[int, float, float, float]] = []
        self.log_times: list[int] = []

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        decode = self.decode
        rows, logs = self.rows, self.log_times
        n0 = len(rows)
        for m in msgs:
            try:
                rows.append(decode(m[4]))
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            logs.append(m[2])
        self.ctx.report.decoded += len(rows) - n0

    def finish(self) -> None:
        if not self.rows:
            return
        topic = self.channel.topic
        arr = np.asarray(self.rows, np.float64)
        stamps_ns = np.asarray([r[0] for r in self.rows], np.int64)
        if not np.any(stamps_ns):
            self.ctx.report.warn(f"topic {topic!r}: Imu header stamps are all zero; the "
                                 "MCAP log times are used instead")
            stamps_ns = np.asarray(self.log_times, np.int64)
        t = stamps_ns.astype(np.float64) * 1e-9
        rate = _estimate_rate(np.sort(stamps_ns))
        if rate is None:
            self.ctx.report.reject("no_sample_rate", len(self.rows), f"topic {topic!r}")
            self.ctx.report.warn(f"topic {topic!r}: too few distinct Imu stamps to estimate "
                                 "a sample rate; give it in a mapping")
            return
        self.ctx.report.warn(
            f"topic {topic!r}: sample rate {rate:g} Hz estimated from the median Imu header "
            "stamp interval; give sample_rate_Hz in a mapping to fix it"
        )
        index = indices_from_stamps(t, rate)
        index -= index.min()
        for k, axis in enumerate("xyz", start=1):
            self.ctx.builder.add_samples(f"{topic}/linear_acceleration.{axis}", "m/s^2", rate,
                                         index, arr[:, k], stamp_index=index, stamps_s=t)


def _estimate_rate(sorted_stamps_ns: np.ndarray) -> float | None:
    """1 / median positive stamp interval, to 3 significant digits (Hz)."""
    d = np.diff(sorted_stamps_ns)
    d = d[d > 0]
    if d.size == 0:
        return None
    fs = 1e9 / float(np.median(d))
    digits = 2 - math.floor(math.log10(fs))
    return float(round(fs, digits))


class _SlowValueHandler(_Handler):
    """rigtools.SlowValue JSON points: slow signals named by the payload (or the mapping)."""

    def __init__(self, ctx: _Context, channel: ChannelRecord, decoder: Decoder,
                 spec: SlowSpec | None) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode
        self.spec = spec
        self.points: dict[str, tuple[str, list[int], list[float]]] = {}

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        decode = self.decode
        spec = self.spec
        for m in msgs:
            try:
                p = decode(m[4])
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            name = spec.name if spec is not None else p.name
            unit = spec.unit if spec is not None and spec.unit is not None else p.unit
            entry = self.points.get(name)
            if entry is None:
                entry = self.points[name] = (unit, [], [])
            elif entry[0] != unit:
                self.ctx.report.reject("inconsistent_unit", 1, where)
                self.ctx.warn_once("inconsistent_unit", name, f"slow signal {name!r}: a point "
                                   f"in {unit!r} after points in {entry[0]!r}; not used")
                continue
            entry[1].append(p.stamp_ns)
            entry[2].append(p.value)
            self.ctx.report.decoded += 1

    def finish(self) -> None:
        for name, (unit, stamps, values) in self.points.items():
            v = np.asarray(values, np.float64)
            if self.spec is not None:
                v = v * self.spec.scale + self.spec.offset
            self.ctx.builder.add_slow(name, unit, np.asarray(stamps, np.float64) * 1e-9, v)


class _ScalarHandler(_Handler):
    """A ROS 2 message with one numeric field: a slow signal named after the topic."""

    def __init__(self, ctx: _Context, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode
        self.t: list[int] = []
        self.v: list[float] = []

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        for m in msgs:
            try:
                self.v.append(self.decode(m[4]))
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            self.t.append(m[2])
            self.ctx.report.decoded += 1

    def finish(self) -> None:
        if self.v:
            unit = self.channel.metadata.get("unit", "")
            self.ctx.builder.add_slow(self.channel.topic, unit,
                                      np.asarray(self.t, np.float64) * 1e-9,
                                      np.asarray(self.v, np.float64))


class _MappedHandler(_Handler):
    """Any decodable message: the mapping's dotted fields become uniform or slow signals."""

    def __init__(self, ctx: _Context, channel: ChannelRecord, decoder: Decoder,
                 specs: list[UniformSpec | SlowSpec]) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode
        self.specs = specs
        self.stamps: list[int] = []
        self.cols: list[list[Any]] = [[] for _ in specs]

    def add(self, msgs: list[_Msg], where: str, buf: Any = None) -> None:
        for m in msgs:
            try:
                obj = self.decode(m[4])
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            row = []
            for spec in self.specs:
                try:
                    row.append(get_field(obj, spec.field or ""))
                except KeyError as exc:
                    raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                                       "a field path that exists in the messages",
                                       repr(spec.field), str(exc)) from None
            stamp = message_stamp_ns(obj)
            self.stamps.append(m[2] if stamp is None else stamp)
            for col, val in zip(self.cols, row, strict=True):
                col.append(val)
            self.ctx.report.decoded += 1

    def _numbers(self, spec: UniformSpec | SlowSpec, vals: list[Any]) -> list[np.ndarray]:
        try:
            out = [np.asarray(v, np.float64).ravel() for v in vals]
        except (TypeError, ValueError):
            raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                               "a numeric field", f"{spec.field!r} = {vals[0]!r}") from None
        return out

    def finish(self) -> None:
        if not self.stamps:
            return
        t = np.asarray(self.stamps, np.float64) * 1e-9
        for spec, vals in zip(self.specs, self.cols, strict=True):
            arrays = self._numbers(spec, vals)
            unit = spec.unit if spec.unit is not None else self.channel.metadata.get("unit", "")
            if isinstance(spec, SlowSpec):
                if any(a.size != 1 for a in arrays):
                    raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                                       "a scalar field for a slow signal", repr(spec.field))
                v = np.concatenate(arrays) * spec.scale + spec.offset
                self.ctx.builder.add_slow(spec.name, unit, t, v)
                continue
            rate = spec.sample_rate_Hz
            counts = np.asarray([a.size for a in arrays], np.int64)
            idx0 = indices_from_stamps(t, rate)
            idx0 -= idx0.min()
            starts = np.cumsum(counts) - counts
            index = np.arange(int(counts.sum()), dtype=np.int64)
            index += np.repeat(idx0 - starts, counts)
            values = np.concatenate(arrays) * spec.scale + spec.offset
            keep = counts > 0
            self.ctx.builder.add_samples(spec.channel, unit, rate, index, values,
                                         stamp_index=idx0[keep], stamps_s=t[keep])


@dataclass
class _Context:
    path: str
    builder: RecordingBuilder
    report: IngestReport
    scanner: _Scanner
    by_topic: dict[str, list[UniformSpec | SlowSpec]]
    mapping_source: str
    _warned: set[tuple[str, object]] = field(default_factory=set)

    def warn_once(self, reason: str, key: object, text: str) -> None:
        if (reason, key) not in self._warned:
            self._warned.add((reason, key))
            self.report.warn(text)

    def handler_for(self, ch: ChannelRecord) -> _Handler:
        schema = self.scanner.schemas.get(ch.schema_id) if ch.schema_id else None
        sname = schema.name if schema else "(none)"
        senc = schema.encoding if schema else "(none)"
        if self.by_topic and ch.topic not in self.by_topic:
            self.warn_once("not_in_mapping", ch.id, f"{self.path}: topic {ch.topic!r} is not "
                           "in the mapping; its messages are counted as not_in_mapping")
            return _Reject(self, ch, "not_in_mapping")
        specs = self.by_topic.get(ch.topic, [])
        try:
            dec = decoder_for(ch.message_encoding, schema)
            if specs and (dec is None or dec.kind not in ("batch", "slow")):
                dec = decoder_for(ch.message_encoding, schema, generic=True)
        except SchemaUnusableError as exc:
            self.warn_once("bad_schema", ch.id, f"{self.path}: topic {ch.topic!r}: schema "
                           f"{sname!r} ({senc}) not usable: {exc}; its messages are counted "
                           "as bad_schema")
            return _Reject(self, ch, "bad_schema")
        if dec is None:
            self.warn_once("no_decoder", ch.id, f"{self.path}: no decoder for topic "
                           f"{ch.topic!r} (channel {ch.id}): message encoding "
                           f"{ch.message_encoding!r}, schema {sname!r} ({senc}); its messages "
                           "are counted as no_decoder")
            return _Reject(self, ch, "no_decoder")
        if specs:
            return self._mapped(ch, dec, specs)
        if dec.kind == "batch":
            return _BatchHandler(self, ch, dec, None)
        if dec.kind == "slow":
            return _SlowValueHandler(self, ch, dec, None)
        if dec.kind == "imu":
            return _ImuHandler(self, ch, dec)
        return _ScalarHandler(self, ch, dec)

    def _mapped(self, ch: ChannelRecord, dec: Decoder,
                specs: list[UniformSpec | SlowSpec]) -> _Handler:
        if dec.kind == "batch":
            bad = [s for s in specs if not isinstance(s, UniformSpec) or s.field != "values"]
            if bad or len(specs) != 1:
                raise MappingError(self.mapping_source, f"topic {ch.topic!r}",
                                   "one [[uniform]] entry with field = \"values\" for a "
                                   "rigtools.AccelBatch topic",
                                   ", ".join(f"{type(s).__name__} field {s.field!r}"
                                             for s in specs))
            return _BatchHandler(self, ch, dec, specs[0])  # type: ignore[arg-type]
        if dec.kind == "slow":
            bad = [s for s in specs if not isinstance(s, SlowSpec) or s.field != "value"]
            if bad or len(specs) != 1:
                raise MappingError(self.mapping_source, f"topic {ch.topic!r}",
                                   "one [[slow]] entry with field = \"value\" for a "
                                   "rigtools.SlowValue topic",
                                   ", ".join(f"{type(s).__name__} field {s.field!r}"
                                             for s in specs))
            return _SlowValueHandler(self, ch, dec, specs[0])  # type: ignore[arg-type]
        return _MappedHandler(self, ch, dec, specs)


def ingest(
    stream: BinaryIO,
    path: str,
    builder: RecordingBuilder,
    report: IngestReport,
    mapping: ChannelMapping | None,
) -> dict[str, str]:
    """Read an MCAP stream into a builder.

    Parameters
    ----------
    stream : binary file object
        The MCAP data, from its first byte.
    path : str
        Source path, for messages and errors.
    builder : RecordingBuilder
        Receives uniform channels and slow signals.
    report : IngestReport
        Receives the tallies (``units`` set to ``"messages"``).
    mapping : ChannelMapping or None
        When it has MCAP entries (``topic`` and ``field``), only the topics it names are
        read, into the channels it names; otherwise every topic with a known decoder is
        read (see :mod:`rigtools.ingest.mcap_decoders`).

    Returns
    -------
    dict of str to str
        The key/values of the Metadata record named ``rigtools.run`` (``run_id``, ``rig``,
        ``gear_set``, ``conditions.<name_with_unit>``); empty when there is none.

    Raises
    ------
    RecordingFormatError
        Empty file, or no MCAP magic at byte 0.
    MappingError
        The mapping names a field a topic's messages do not have, or a non-numeric one.
    """
    report.units = "messages"
    scanner = _Scanner(stream, path, report)
    by_topic: dict[str, list[UniformSpec | SlowSpec]] = {}
    if mapping is not None:
        for spec in (*mapping.uniform, *mapping.slow):
            if spec.topic is not None:
                by_topic.setdefault(spec.topic, []).append(spec)
    ctx = _Context(path, builder, report, scanner, by_topic, mapping.source or "<mapping>"
                   if mapping is not None else "<mapping>")
    handlers: dict[int, _Handler] = {}
    for where, buf, msgs in scanner.blocks():
        groups: dict[int, list[_Msg]] = {}
        for m in msgs:
            g = groups.get(m[0])
            if g is None:
                groups[m[0]] = [m]
            else:
                g.append(m)
        for cid, group in groups.items():
            h = handlers.get(cid)
            if h is None:
                h = handlers[cid] = ctx.handler_for(scanner.channels[cid])
            h.add(group, where, buf)
    for h in handlers.values():
        h.finish()
    seen = {ch.topic for ch in scanner.channels.values()}
    for topic in sorted(set(by_topic) - seen):
        report.warn(f"{path}: the mapping names topic {topic!r}, which the file does not have")
    return dict(scanner.metadata.get(RUN_METADATA_NAME, {}))
