"""Vector BLF (binary logging format) CAN logs, read into columnar frame batches.

A BLF file is a 144-byte file header (signature ``LOGG``, sizes, start and stop time as a
Windows ``SYSTEMTIME``) followed by ``LOG_CONTAINER`` objects (``LOBJ``, type 10), each holding
zlib-deflated or stored data in which the log objects themselves (``LOBJ`` headers followed by
a body) sit back to back; an object may straddle two containers.

The reader streams container by container and never holds the whole file: decompressed data
is gathered into blocks of about :data:`PARSE_BYTES` (plus the unfinished object carried over,
as python-can's ``BLFReader`` carries its ``_tail``), the object headers of a block are walked
(arithmetically where consecutive objects share type and size, which is the usual case, with
the signatures checked by NumPy over whole runs; object by object elsewhere), and the frame
fields are gathered with NumPy structured dtypes over all objects of a type at once.

Frames come out exactly as python-can's ``can.BLFReader`` yields them (timestamp bit for bit,
identifier, extended and FD flags, payload, channel numbered from 0 as python-can numbers it,
i.e. the BLF channel minus 1). What python-can yields but carries no data, and what it skips or
chokes on, is counted in the :class:`~rigtools.ingest.recording.IngestReport`:

==========================  ==========================================================
reason                      what
==========================  ==========================================================
``error_frame``             ``CAN_ERROR`` (2), ``CAN_ERROR_EXT`` (73), ``CAN_FD_ERROR_64``
                            (104) objects
``remote_frame``            CAN or CAN FD frames with the RTR flag
``blf_object_type_<n>``     any other object type *n* (bus statistics, markers, other
                            buses); no CAN data
``invalid_length``          ``CAN_FD_MESSAGE_64`` claiming more than 64 valid bytes
``corrupt_object``          an object header that is not where it must be, or claims a
                            size smaller than its own header or larger than
                            ``max_object_bytes``; reading resynchronises on the next
                            ``LOBJ`` signature
``truncated_object``        an object cut short by the end of the file or by a lost
                            container
``truncated_container``     a container cut short by the end of the file, or containers
                            missing before the file size the header states
``corrupt_container``       undecompressable zlib data, a container header that is not a
                            ``LOBJ`` where one must be, or one claiming more than
                            ``max_container_bytes`` of compressed data; reading goes on at
                            the next container
``oversized_container``     a container inflating to more than ``max_container_bytes``
                            (a zip bomb is never allocated)
``unknown_compression``     a container compression method other than 0 and 2
==========================  ==========================================================

Positions are byte offsets of the container, in the (decompressed, for ``.blf.gz``) file,
where the object starts (``position_unit = "byte"``).

Quirks, decided here (python-can's test files show them):

* classic frames with a DLC above 8 (``test_CanMessage.blf`` has DLC 51): python-can keeps the
  DLC and 8 data bytes; here the frame is kept with ``length`` 8 (the payload it has), and a
  DLC above 15, impossible on the bus, is reported once as a warning;
* error frames with DLC 102 (``test_CanErrorFrameExt.blf``): error frames carry no data and are
  counted as ``error_frame`` whatever their DLC;
* BLF channel numbers above 32768 do not fit the batch's int16 channel column: they become -1
  with a warning;
* an object whose size is smaller than the fixed part of its type's structure is counted as
  ``corrupt_object`` (python-can would read the following object's bytes as its fields).
"""

from __future__ import annotations

import datetime
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import BinaryIO, Final

import deflate

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can.blf_objects import FrameColumns, ObjectParser, ParseBlock
from rigtools.ingest.can.blf_records import LOBJ, LOG_CONTAINER, OBJ_BASE
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.recording import IngestReport

__all__ = [
    "MAX_CONTAINER_BYTES",
    "MAX_OBJECT_BYTES",
    "NAME",
    "PARSE_BYTES",
    "READER",
    "BlfHeader",
    "iter_batches",
    "read_header",
    "sniff",
]

NAME = "blf"

#: Largest container accepted, compressed or inflated (bytes). Vector writes 128 KiB.
MAX_CONTAINER_BYTES = 64 << 20
#: Largest object accepted inside containers (bytes); CAN objects are below 200.
MAX_OBJECT_BYTES = 16 << 20
#: Decompressed bytes gathered before a block of objects is parsed (bytes).
PARSE_BYTES = 4 << 20

_FILE_HEADER = struct.Struct("<4sLBBBBBBBBQQLL8H8H")
_CONTAINER = struct.Struct("<H6xL4x")
_READ_STEP = 1 << 20  # largest single read from the stream (bytes)


def sniff(head: bytes) -> bool:
    """True when ``head`` (the first bytes of a file) starts with the BLF signature ``LOGG``."""
    return head[:4] == b"LOGG"


@dataclass(frozen=True)
class BlfHeader:
    """The fields of a BLF file header rigtools uses.

    Attributes
    ----------
    header_size : int
        Bytes of the file header (144 as Vector and python-can write it).
    file_size : int
        File size the writer recorded (bytes); 0 when never updated.
    uncompressed_size : int
        Uncompressed size the writer recorded (bytes).
    object_count : int
        Object count the writer recorded.
    start_timestamp_s : float
        Measurement start (s since the UNIX epoch, UTC; 0 when the header holds none), computed
        as python-can's ``systemtime_to_timestamp`` computes it.
    """

    header_size: int
    file_size: int
    uncompressed_size: int
    object_count: int
    start_timestamp_s: float


def _systemtime_to_timestamp(st: tuple[int, ...]) -> float:
    # Same arithmetic as python-can's can.io.blf.systemtime_to_timestamp (bit-identical).
    try:
        t = datetime.datetime(st[0], st[1], st[3], st[4], st[5], st[6], st[7] * 1000,
                              tzinfo=datetime.UTC)
        return t.timestamp()
    except ValueError:
        return 0.0


def read_header(head: bytes, path: str) -> BlfHeader:
    """Parse a BLF file header.

    Parameters
    ----------
    head : bytes
        At least the first 72 bytes of the file.
    path : str
        File name for error messages.

    Returns
    -------
    BlfHeader

    Raises
    ------
    RecordingFormatError
        Empty input, a signature other than ``LOGG``, a header cut short, or a header size
        outside 72..65536 bytes; the position is byte 0.
    """
    if not head:
        raise RecordingFormatError(path, 0, "a BLF file", "an empty file")
    if head[:4] != b"LOGG":
        raise RecordingFormatError(path, 0, "the BLF signature b'LOGG'", repr(head[:4]))
    if len(head) < _FILE_HEADER.size:
        raise RecordingFormatError(path, 0, f"a {_FILE_HEADER.size}-byte BLF file header",
                                   f"{len(head)} bytes")
    h = _FILE_HEADER.unpack_from(head)
    if not _FILE_HEADER.size <= h[1] <= 65536:
        raise RecordingFormatError(path, 0, "a BLF header size of 72..65536 bytes", str(h[1]))
    return BlfHeader(int(h[1]), int(h[10]), int(h[11]), int(h[12]),
                     _systemtime_to_timestamp(h[14:22]))


class _Source:
    """Forward-only reads of a binary stream with an offset, a push-back and error capture."""

    def __init__(self, stream: BinaryIO) -> None:
        self.stream = stream
        self.offset = 0
        self._back = b""
        self.error: str | None = None

    def read(self, n: int) -> bytes:
        out = b""
        if self._back:
            out, self._back = self._back[:n], self._back[n:]
            n -= len(out)
        if n > 0 and self.error is None:
            try:
                more = self._read_bounded(n)
            except (OSError, EOFError, zlib.error) as exc:  # damaged .gz wrapper
                self.error = f"{type(exc).__name__}: {exc}"
                more = b""
            out = out + more if out else more
        self.offset += len(out)
        return out

    def _read_bounded(self, n: int) -> bytes:
        """``stream.read(n)`` in steps of at most :data:`_READ_STEP` bytes.

        ``BufferedReader.read(n)`` allocates ``n`` bytes before it reads: a container size
        field that lies (tens of MB in a small file) would cost that much memory.
        """
        if n <= _READ_STEP:
            return self.stream.read(n)
        parts = []
        while n > 0:
            part = self.stream.read(min(n, _READ_STEP))
            if not part:
                break
            parts.append(part)
            n -= len(part)
        return b"".join(parts)

    def unread(self, data: bytes) -> None:
        self._back = data + self._back
        self.offset -= len(data)

    def resync(self, max_container: int) -> bool:
        """Skip to the next plausible container header; False at the end of the file."""
        buf = b""
        while True:
            block = self.read(1 << 20)
            if not block:
                return False
            buf += block
            start = 0
            while True:
                i = buf.find(LOBJ, start)
                if i < 0 or i + 16 > len(buf):
                    break
                _, hs, hv, osize, otype = OBJ_BASE.unpack_from(buf, i)
                if otype == LOG_CONTAINER and hs == 16 and hv == 1 and (
                    32 <= osize <= max_container + 32
                ):
                    self.unread(buf[i:])
                    return True
                start = i + 1
            keep = min(len(buf), 15 if i < 0 else len(buf) - i)  # a header may straddle
            buf = buf[len(buf) - keep :]


def _swallowed_header(src: _Source, body: bytes, pad: bytes) -> int:
    """Where a container header starts inside ``body + pad``, when the read overran into it.

    Checked only when what follows is not an object header (nor the end of the file): the
    container's size field lied upwards. Objects inside containers are never containers, so
    the first ``LOBJ`` header of type ``LOG_CONTAINER`` inside the bytes read (it may straddle
    into the bytes after them) marks the overrun. Returns its offset in ``body + pad``, or -1.
    """
    after = src.read(16)
    src.unread(after)
    if not after or after[:4] == LOBJ:
        return -1
    joined = body + pad + after
    end = len(body) + len(pad)
    j = joined.find(LOBJ, 16, end + 3)
    while 0 <= j < end:
        if j + 16 <= len(joined):
            _, hs, hv, size, otype = OBJ_BASE.unpack_from(joined, j)
            if otype == LOG_CONTAINER and hs == 16 and hv == 1 and size >= 32:
                return j
        j = joined.find(LOBJ, j + 1, end + 3)
    return -1


def _inflate_whole(payload: memoryview, claimed: int, bound: int) -> bytearray | None:
    """A sound container's zlib stream inflated in one call of libdeflate, or None.

    libdeflate inflates 2-3x faster than zlib's streaming decompressor, but needs the output
    size up front: the container's claimed size, when it is within ``bound``. Any stream
    libdeflate refuses (damaged, cut short, a wrong claim, a bad Adler-32) returns None, and
    the caller's zlib path decides what was wrong and keeps what it can, as before.
    """
    if not 0 < claimed <= bound:
        return None
    try:
        return deflate.zlib_decompress(payload, claimed)
    except deflate.DeflateError:
        return None


def iter_batches(
    stream: BinaryIO,
    path: str,
    report: IngestReport,
    *,
    batch_frames: int = 250_000,
    max_container_bytes: int = MAX_CONTAINER_BYTES,
    max_object_bytes: int = MAX_OBJECT_BYTES,
) -> Iterator[CanFrameBatch]:
    """Stream the CAN data frames of a BLF file as columnar batches.

    Parameters
    ----------
    stream : BinaryIO
        The file, opened for binary reading (gzip already unwrapped), positioned at byte 0.
    path : str
        File name for messages.
    report : IngestReport
        Receives the counts of everything that is not a CAN data frame, and of the damage.
    batch_frames : int
        Frames per batch yielded (the last batch may be shorter).
    max_container_bytes : int
        Largest container accepted, compressed or inflated (bytes). Decompression is bounded
        by it, whatever size a container claims.
    max_object_bytes : int
        Largest object accepted inside containers (bytes).

    Yields
    ------
    CanFrameBatch
        Data frames in file order; positions are container byte offsets.

    Raises
    ------
    RecordingFormatError
        Empty file, a signature other than ``LOGG``, or a file header cut short (position 0).
    """
    if batch_frames < 1:
        raise ValueError(f"`batch_frames` must be >= 1, was {batch_frames}")
    src = _Source(stream)
    header = read_header(src.read(_FILE_HEADER.size), path)
    rest = src.read(header.header_size - _FILE_HEADER.size)
    if len(rest) < header.header_size - _FILE_HEADER.size:
        report.reject("truncated_container", 1, f"byte {src.offset}")
        return
    parser = ObjectParser(path, report, header.start_timestamp_s, max_object_bytes)
    block = ParseBlock()
    out = FrameColumns()
    warned_claim = warned_padding = False

    def lose() -> None:
        """A container is lost: finish the block, drop its unfinished object, resync after."""
        nonlocal block
        block = parser.parse(block, out, final=True)
        parser.resync = True

    while True:
        offset = src.offset
        base = src.read(16)
        if not base:
            break
        if len(base) < 16:
            report.reject("truncated_container", 1, f"byte {offset}")
            break
        sig, _, _, osize, otype = OBJ_BASE.unpack(base)
        if sig != LOBJ:
            # Padding other than python-can's ``size % 4``: the next object a few bytes on.
            more = src.read(8)
            j = (base + more).find(LOBJ, 1, 12)
            src.unread(base[j:] + more if j > 0 else base[1:] + more)
            if j > 0:
                if not warned_padding:
                    warned_padding = True
                    report.warn(f"{path}: {j} unexpected padding byte(s) before the container "
                                f"at byte {offset + j}")
                continue
        if sig != LOBJ or osize < 32 or osize > max_container_bytes + 32:
            report.reject("corrupt_container", 1, f"byte {offset}")
            lose()
            if sig == LOBJ:
                src.unread(base[1:])
            if not src.resync(max_container_bytes):
                break
            yield from out.take(batch_frames, final=False)
            continue
        body = src.read(osize - 16)
        truncated = len(body) < osize - 16
        pad = src.read(osize % 4)  # padding, as python-can reads it
        if not truncated and otype == LOG_CONTAINER:
            cut = _swallowed_header(src, body, pad)
            if cut >= 0:  # the size field is too large: it swallowed the next container's start
                joined = body + pad
                src.unread(joined[cut:])
                body = joined[:cut] if cut < len(body) else body
                report.warn(f"{path}: container at byte {offset} claims {osize} bytes but the "
                            f"next container starts at byte {offset + 16 + cut}; read up to "
                            "there (nothing lost)")
        if otype != LOG_CONTAINER:
            report.reject(f"blf_object_type_{otype}", 1, f"byte {offset}")
            if truncated:
                report.reject("truncated_container", 1, f"byte {offset}")
                break
            continue
        if len(body) < _CONTAINER.size:
            report.reject("truncated_container", 1, f"byte {offset}")
            break
        method, claimed = _CONTAINER.unpack_from(body)
        payload = memoryview(body)[_CONTAINER.size :]
        if claimed > max_container_bytes and not warned_claim:
            warned_claim = True
            report.warn(f"{path}: container at byte {offset} claims {claimed} uncompressed "
                        f"bytes; decompression bounded to {max_container_bytes}")
        data: bytes | bytearray
        inflated = _inflate_whole(payload, claimed, max_container_bytes) if method == 2 else None
        if method == 0:
            data = bytes(payload)
        elif inflated is not None:
            data = inflated
        elif method == 2:
            z = zlib.decompressobj()
            try:
                data = z.decompress(payload, max_container_bytes)
            except zlib.error:
                report.reject("corrupt_container", 1, f"byte {offset}")
                lose()
                continue
            if z.unconsumed_tail:
                report.reject("oversized_container", 1, f"byte {offset}")
                lose()
                continue
            if not z.eof and not truncated:
                report.reject("corrupt_container", 1, f"byte {offset}")
                report.warn(f"{path}: zlib stream of the container at byte {offset} ends "
                            "early; its complete objects are kept")
                block.add(data, offset)
                lose()
                continue
        else:
            report.reject("unknown_compression", 1, f"byte {offset}")
            lose()
            continue
        block.add(data, offset)
        if truncated:
            report.reject("truncated_container", 1, f"byte {offset}")
            break
        if block.size >= max(PARSE_BYTES, block.need):
            block = parser.parse(block, out, final=False)
            yield from out.take(batch_frames, final=False)
    short = bool(header.file_size) and src.offset < header.file_size
    if (src.error is not None or short) and "truncated_container" not in report.rejected:
        report.reject("truncated_container", 1, f"byte {src.offset}")
    if src.error is not None:
        report.warn(f"{path}: the compressed file stream broke off ({src.error})")
    elif short:
        report.warn(f"{path}: the header states {header.file_size} bytes, the file ends at "
                    f"{src.offset}")
    block = parser.parse(block, out, final=True)
    yield from out.take(batch_frames, final=True)


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = CanLogReader(NAME, sniff, iter_batches)
