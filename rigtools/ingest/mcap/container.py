"""The MCAP container walk: records from the first byte on, chunks unpacked, messages out.

The file is read from the start, record by record (opcode u8, length u64, content). Every
length is checked against what remains before anything is read or allocated
(:mod:`rigtools.ingest.mcap.source`, :mod:`rigtools.ingest.mcap.records`). Chunks are held
against their size limits *before* they are decompressed, decompressed with a bounded
output and checked against their CRC (:mod:`rigtools.ingest.mcap.decompress`). Nothing
depends on the summary section, so files without a summary or indexes, and files cut short,
are read as far as they are intact.

:class:`ContainerScanner` hands on messages a :class:`MessageBlock` at a time (one per
chunk), which lets payload decoders work on a whole chunk at once. :func:`iter_messages` is
the same walk one :class:`RawMessage` at a time.

Two things make the walk fast without changing what it finds:

* Inside a chunk, a run of Message records of one length is read with array operations
  (:mod:`rigtools.ingest.mcap.walk`, which also holds :class:`MessageBlock`).
* When the stream can be read at a position without moving (a regular file, a ``BytesIO``),
  the next chunk is read, decompressed and CRC-checked in a worker thread while the records of
  the current one are parsed (decompression and CRC release the GIL; when the worker is the
  slower side, the walk checks the CRC itself). At most two chunks are in flight. The worker
  only computes; the walk applies every outcome (refusal, tally, warning) at the same point
  and in the same order as when it reads the chunk itself.

Every loss is counted in the :class:`~rigtools.ingest.recording.IngestReport`; the reasons
are listed in :mod:`rigtools.ingest.mcap`.

Messages of a refused chunk are counted by the entries of the message indexes that follow
it when the file has them; otherwise the chunk counts as one. A message whose channel is not
defined where it appears (its Channel record was in a refused chunk) is held, and read at the
end of the file if the summary's repeated Channel records define it. Likewise a Channel
record naming a schema not defined yet (its Schema record damaged or missing) is held, and
its messages with it, until the Schema record comes (later, or in the summary): a channel is
never handed on with a schema still to come.

Damaged length fields and definitions (issue 12) are handled when the stream can be read at a
position (a regular file, a ``BytesIO``; not a ``gzip`` stream, which ends at the first lie
as before, counted ``truncated_record``):

* **Resynchronisation.** A record is read only if its length ends at the end of the file or
  at a record header whose length fits in the file. Otherwise: a Chunk record is read with the
  length its own fields imply (header and compressed records; its CRC then vouches for the
  records) when that length leads to a plausible record; any other record is skipped up to the
  first position after it where :data:`_SYNC_RECORDS` plausible records (a defined opcode
  first, lengths within the file) follow each other, counted once as ``lost_sync``. A length
  that grew over intact records is caught by searching its claimed content for such a chain.
  A record reading as a Footer without the closing magic after it is resynchronised past too.
  A chunk both of whose lengths end past the file is a cut chunk: the walk ends there as
  before, and the records inside a cut uncompressed chunk are not read.
* **The summary first.** Before the walk, the Footer is read and, when the summary CRC checks,
  the Schema and Channel records of the summary are kept: a data-section copy that differs
  (damaged, yet parseable) is replaced by them, with a warning, before any message of the
  channel is handed on. Without a summary CRC (0) or when it fails, which copy is damaged
  cannot be told and the first definition is kept, as in a stream. A Footer whose offsets point
  outside the file is warned about.

The settling of definitions (the summary first, channels and messages held) is in
:mod:`rigtools.ingest.mcap.definitions`, the resynchronisation in
:mod:`rigtools.ingest.mcap.resync`; :class:`ContainerScanner` combines them with the walk.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, BinaryIO, Final, NamedTuple, TypeAlias

from rigtools.errors import RecordingFormatError
from rigtools.ingest.mcap.decompress import (
    ChunkDecompressor,
    ChunkRefusedError,
    check_chunk_crc,
    check_chunk_size,
)
from rigtools.ingest.mcap.definitions import MAX_DEFERRED_BYTES, DefinitionTable
from rigtools.ingest.mcap.records import (
    KNOWN_OPS,
    MAGIC,
    MESSAGE_HEADER,
    MESSAGE_HEADER_BYTES,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_FOOTER,
    OP_HEADER,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    OP_METADATA,
    OP_SCHEMA,
    OP_STATISTICS,
    PARSED_OPS,
    RECORD_HEADER,
    RECORD_HEADER_BYTES,
    ChannelRecord,
    MalformedRecordError,
    SchemaRecord,
    message_index_entry_count,
    parse_chunk_header,
    statistics_message_count,
)
from rigtools.ingest.mcap.resync import RecordResync
from rigtools.ingest.mcap.source import ByteSource
from rigtools.ingest.mcap.walk import ChunkRecordWalk, MessageBlock, ScannedMessage
from rigtools.ingest.recording import IngestReport

__all__ = [
    "DIRECT_BLOCK_MESSAGES",
    "MAX_DEFERRED_BYTES",
    "MAX_RECORD_BYTES",
    "PIPELINE_MIN_CHUNK_BYTES",
    "ContainerScanner",
    "MessageBlock",
    "RawMessage",
    "ScannedMessage",
    "iter_messages",
]

#: Top-level records longer than this (2 GiB) are skipped and counted ``oversized_record``.
MAX_RECORD_BYTES: Final = 2 << 30
#: Messages found directly in the data section (outside chunks) go on in blocks of this many.
DIRECT_BLOCK_MESSAGES: Final = 4096
#: Chunk records at least this long (64 KiB) are read and decompressed one chunk ahead in a
#: worker thread when the stream allows it; smaller ones cost less than the hand-over.
PIPELINE_MIN_CHUNK_BYTES = 64 << 10
_MAX_WARNINGS_PER_REASON: Final = 5
#: A run of equal Message records is read with array operations when it has at least this many.
_RUN_MIN: Final = 8
#: How many top-level records the look-ahead for the next chunk steps over at most.
_LOOKAHEAD_RECORDS: Final = 64

#: The outcome of a chunk record's content: its uncompressed records (None when it has none
#: or is refused), the refusal (reason, detail) if any, and the CRC still to check (None when
#: checked or not to be checked).
_ChunkOutcome: TypeAlias = tuple[Any, tuple[str, str] | None, int | None]


def _chunk_outcome(content: Any, decompressor: ChunkDecompressor, validate_crcs: bool,
                   check_crc: bool = True) -> _ChunkOutcome:
    """Header, size limits, decompression and (unless ``check_crc`` is False) CRC of a chunk.

    No side effects: runs in the walk or, one chunk ahead, in the worker thread. A CRC left
    unchecked is handed back, for the walk to check before it uses the records.
    """
    try:
        head = parse_chunk_header(content)
    except MalformedRecordError as exc:
        return None, ("bad_chunk", str(exc)), None
    try:
        check_chunk_size(head.uncompressed_size, head.records_size)
        if head.uncompressed_size == 0:
            return None, None, None
        off = head.records_offset
        data = decompressor.decompress(
            head.compression, memoryview(content)[off : off + head.records_size],
            head.uncompressed_size)
        crc = head.uncompressed_crc if validate_crcs and head.uncompressed_crc != 0 else None
        if crc is not None and check_crc:
            check_chunk_crc(data, crc)
            crc = None
    except ChunkRefusedError as exc:
        return None, (exc.reason, exc.detail), None
    return data, None, crc



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


class ContainerScanner(DefinitionTable, RecordResync, ChunkRecordWalk):
    """Stream an MCAP file's records from the start; yield messages chunk by chunk.

    Parameters
    ----------
    stream : binary file object
        Positioned at the start of the MCAP data.
    path : str
        For messages and errors.
    report : IngestReport
        Receives the losses and warnings.
    validate_crcs : bool
        Check chunk CRCs.

    Attributes
    ----------
    schemas : dict of int to SchemaRecord
        Schemas by id, as far as the walk has come (first definition kept, unless the
        CRC-checked summary holds another: see the module docstring).
    channels : dict of int to ChannelRecord
        Channels by id, likewise; a channel whose schema is not defined yet is not here
        until it is (or until the end of the file).
    metadata : dict of str to dict
        Key/values of the Metadata records, by record name.
    statistics_message_count : int or None
        The message count of the Statistics record, once read.
    n_message_records : int
        Message records found (read or counted), to cross-check the Statistics record.
    """

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
        self._src = ByteSource(stream)
        self._decompressor = ChunkDecompressor()
        self._pending: tuple[str, str] | None = None
        self._pending_count = 0
        self._warned: dict[str, int] = {}
        self._deferred: list[tuple[ScannedMessage, str]] = []
        self._deferred_bytes = 0
        # the chunk read ahead: (position, record length, outcome in the worker)
        self._ahead: tuple[int, int, Future[_ChunkOutcome | None]] | None = None
        self._worker: ThreadPoolExecutor | None = None
        self._worker_decompressor = ChunkDecompressor()
        self._worker_crc = True
        # Schema and Channel records of the summary section when its CRC checks (seekable
        # streams only): they win over a differing copy in the data section
        self._summary_schemas: dict[int, SchemaRecord] = {}
        self._summary_channels: dict[int, ChannelRecord] = {}
        # Channel records waiting for the Schema record they name (their messages are held)
        self._unsettled: dict[int, ChannelRecord] = {}
        # no plausible record starts at or after this position (a search found none)
        self._no_sync_from = 1 << 64

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

    def _malformed(self, kind: str, where: str, exc: MalformedRecordError) -> None:
        self.report.reject("bad_record", 1, where)
        self._warn("bad_record", f"{self.path}: malformed {kind} record at {where}: {exc}")

    # -- chunks --------------------------------------------------------------------------

    def _chunk(self, outcome: _ChunkOutcome, pos: int) -> MessageBlock | None:
        """Apply a chunk's outcome: count a refusal, or walk its records."""
        data, refusal, crc = outcome
        if crc is not None:
            try:
                check_chunk_crc(data, crc)
            except ChunkRefusedError as exc:
                refusal, data = (exc.reason, exc.detail), None
        if refusal is not None:
            self._refuse_chunk(refusal[0], pos, refusal[1])
            return None
        if data is None:
            return None
        buf = memoryview(data)
        return self._chunk_records(buf, pos, _RUN_MIN)

    # -- the stream ----------------------------------------------------------------------

    def blocks(self) -> Iterator[MessageBlock]:
        """Yield :class:`MessageBlock` in file order.

        One block per chunk (with the chunk's uncompressed data as ``buf``), and blocks of the
        messages found directly in the data section (``buf`` None).

        Raises
        ------
        RecordingFormatError
            The file is empty or does not start with the MCAP magic.
        """
        try:
            yield from self._walk()
        finally:
            self._stop_worker()

    def _walk(self) -> Iterator[MessageBlock]:
        src = self._src
        head = src.read(len(MAGIC))
        if head != MAGIC:
            raise RecordingFormatError(
                self.path, 0, f"the MCAP magic {MAGIC!r}",
                "an empty file" if not head else repr(head),
            )
        peek = src.can_peek
        size = src.size or 0
        look, unpack_hdr = src.look, RECORD_HEADER.unpack
        if peek:
            self._read_summary()
        direct: list[ScannedMessage] = []
        direct_pos = ""
        data_end = False
        first = True
        while True:
            pos = src.pos
            hdr = src.read(RECORD_HEADER_BYTES)
            if len(hdr) < RECORD_HEADER_BYTES:
                self._flush_pending()
                want = "a Footer" if data_end else "a DataEnd record and Footer"
                self._ended(pos, data_end, "a record header" if hdr else want,
                            f"{len(hdr)} bytes" if hdr else "the end of the file")
                break
            op, length = RECORD_HEADER.unpack(hdr)
            if first and op != OP_HEADER:
                self.report.warn(f"{self.path}: the first record is opcode 0x{op:02x}, not a "
                                 "Header")
            first = False
            if op != OP_MESSAGE_INDEX:
                self._flush_pending()
            if peek and op == OP_FOOTER and not self._is_footer(pos, length):
                # a damaged opcode that reads 0x02 would end the walk
                nxt = self._scan(pos + 1, size)
                if nxt is not None:
                    self._lost_sync(pos, nxt, f"it reads as a Footer of {length} bytes, but no "
                                    "closing magic follows it")
                    src.seek(nxt)
                    continue
            elif peek:
                # fast path of _sync: a known record whose length ends at the end of the file
                # or at a record header whose length fits in the file
                q = pos + RECORD_HEADER_BYTES + length
                left = size - q - RECORD_HEADER_BYTES
                if op == OP_CHUNK or op not in KNOWN_OPS or q > size or (
                        q != size and (left < 0 or unpack_hdr(look(q, RECORD_HEADER_BYTES))[1]
                                       > left)):
                    length, jump = self._sync(pos, op, length)
                    if jump is not None:
                        src.seek(jump)
                        continue
            rem = src.remaining()
            if rem is not None and length > rem:
                self._ended(pos, data_end, f"a record of {length} bytes (opcode 0x{op:02x})",
                            f"{rem} bytes left in the file")
                break
            if op not in PARSED_OPS and not (op == OP_MESSAGE_INDEX and self._pending):
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
            outcome: _ChunkOutcome | None = None
            if op == OP_CHUNK:
                fut = self._chunk_future(pos, length)
                if fut is not None:
                    # the worker is the slower side when its chunk is not ready yet: the walk
                    # then checks the next chunk's CRC itself (it releases the GIL too)
                    self._worker_crc = fut.done()
                    self._look_ahead(pos + RECORD_HEADER_BYTES + length)
                    outcome = fut.result()
            if outcome is not None:
                content = b""
                got = src.skip(length)
            else:
                content = src.read(length)
                got = len(content)
            if got < length:
                self._ended(pos, data_end, f"a record of {length} bytes (opcode 0x{op:02x})",
                            f"{got} bytes")
                break
            where = f"byte {pos}"
            if op == OP_MESSAGE:
                self.n_message_records += 1
                if length < MESSAGE_HEADER_BYTES:
                    self.report.reject("bad_record", 1, where)
                    continue
                cid, seq, lt, pt = MESSAGE_HEADER.unpack_from(content, 0)
                payload = memoryview(content)[MESSAGE_HEADER_BYTES:]
                if cid not in self.channels:
                    self._defer(cid, seq, lt, pt, payload, where)
                    continue
                if not direct:
                    direct_pos = where
                direct.append((cid, seq, lt, pt, payload, -1))
                if len(direct) >= DIRECT_BLOCK_MESSAGES:
                    yield MessageBlock.from_messages(direct_pos, direct)
                    direct = []
                continue
            if direct:
                yield MessageBlock.from_messages(direct_pos, direct)
                direct = []
            if op == OP_CHUNK:
                if outcome is None:
                    outcome = _chunk_outcome(content, self._decompressor, self.validate_crcs)
                del content
                block = self._chunk(outcome, pos)
                del outcome
                if block is not None:
                    yield block
                del block
            elif op == OP_SCHEMA:
                self._schema(content, 0, length, where)
            elif op == OP_CHANNEL:
                self._channel(content, 0, length, where)
            elif op == OP_METADATA:
                self._metadata(content, where)
            elif op == OP_MESSAGE_INDEX:
                if self._pending is not None:
                    self._pending_count += message_index_entry_count(content)
            elif op == OP_STATISTICS:
                count = statistics_message_count(content)
                if count is not None:
                    self.statistics_message_count = count
            elif op == OP_DATA_END:
                data_end = True
            elif op == OP_FOOTER:
                if src.read(len(MAGIC)) != MAGIC:
                    self.report.warn(f"{self.path}: no closing magic after the Footer at {where}")
                break
        self._stop_worker()
        if direct:
            yield MessageBlock.from_messages(direct_pos, direct)
        self._flush_pending()
        late = self._release_deferred()
        if late:
            yield MessageBlock.from_messages("the end of the file (deferred messages)", late)
        self._cross_check()

    # -- the chunk read ahead ------------------------------------------------------------

    def _chunk_future(self, pos: int, length: int) -> Future[_ChunkOutcome | None] | None:
        """The worker's outcome of the chunk record at ``pos`` (asked for now if need be).

        None when the chunk is read in the walk: the stream cannot be read ahead, or the
        chunk is too small to be worth the hand-over.
        """
        ahead, self._ahead = self._ahead, None
        if ahead is not None:
            if ahead[0] == pos and ahead[1] == length:
                return ahead[2]
            ahead[2].cancel()
        if PIPELINE_MIN_CHUNK_BYTES <= length and self._src.can_peek:
            return self._submit(pos, length)
        return None

    def _look_ahead(self, start: int) -> None:
        """Find the next chunk record from ``start`` and have the worker read it.

        Reads record headers only, without moving the stream; stops at the first chunk, at
        the end of the data section, or after :data:`_LOOKAHEAD_RECORDS` records.
        """
        src = self._src
        rem = src.remaining()
        if rem is None:
            return
        end = src.pos + rem
        p = start
        for _ in range(_LOOKAHEAD_RECORDS):
            if end - p < RECORD_HEADER_BYTES:
                return
            op, length = RECORD_HEADER.unpack(src.look(p, RECORD_HEADER_BYTES))
            if length > end - p - RECORD_HEADER_BYTES:
                return
            if op == OP_CHUNK:
                if PIPELINE_MIN_CHUNK_BYTES <= length <= MAX_RECORD_BYTES:
                    self._ahead = (p, length, self._submit(p, length))
                return
            if op in (OP_DATA_END, OP_FOOTER):
                return
            p += RECORD_HEADER_BYTES + length

    def _submit(self, pos: int, length: int) -> Future[_ChunkOutcome | None]:
        if self._worker is None:
            self._worker = ThreadPoolExecutor(max_workers=1,
                                              thread_name_prefix="rigtools-mcap-chunk")
        return self._worker.submit(self._read_chunk_ahead, pos, length, self._worker_crc)

    def _read_chunk_ahead(self, pos: int, length: int, check_crc: bool
                          ) -> _ChunkOutcome | None:
        """In the worker: the chunk record's content read at ``pos``, and its outcome.

        None when the content cannot be read whole (the walk then reads it itself).
        """
        content = self._src.peek(pos + RECORD_HEADER_BYTES, length)
        if len(content) < length:
            return None
        return _chunk_outcome(content, self._worker_decompressor, self.validate_crcs, check_crc)

    def _stop_worker(self) -> None:
        if self._ahead is not None:
            self._ahead[2].cancel()
            self._ahead = None
        if self._worker is not None:
            # wait for a chunk still being read: the stream may be closed right after
            self._worker.shutdown(wait=True, cancel_futures=True)
            self._worker = None

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
        Receives the losses (see :mod:`rigtools.ingest.mcap` for the reasons).
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
    sc = ContainerScanner(stream, path, report, validate_crcs)
    for block in sc.blocks():
        for cid, seq, lt, pt, data, _start in block.messages():
            ch = sc.channels[cid]
            sch = sc.schemas.get(ch.schema_id)
            yield RawMessage(cid, ch.topic, sch.name if sch else "", sch.encoding if sch else "",
                             ch.message_encoding, lt, pt, seq, bytes(data))
