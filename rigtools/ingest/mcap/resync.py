"""Resynchronisation of the MCAP walk past a record whose length field lies.

A part of :class:`~rigtools.ingest.mcap.container.ContainerScanner` (seekable streams only),
which provides the attributes and the warning method declared here. :class:`RecordResync`
checks a record's length against the records around it (:meth:`RecordResync._sync`): a Chunk
record is read with the length its own fields imply when that one leads to a plausible record;
any other record is skipped up to the first position where :data:`_SYNC_RECORDS` plausible
records follow each other (:meth:`RecordResync._scan`, with array operations), counted once as
``lost_sync``.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from rigtools.ingest.mcap.records import (
    CHUNK_HEAD_MAX_BYTES,
    FOOTER_AND_MAGIC_BYTES,
    KNOWN_OPS,
    MAGIC,
    OP_CHUNK,
    OP_FOOTER,
    RECORD_HEADER,
    RECORD_HEADER_BYTES,
    chunk_content_length,
)
from rigtools.ingest.mcap.source import ByteSource
from rigtools.ingest.recording import IngestReport

__all__ = ["RecordResync"]

#: A position is taken for the start of a record when this many records follow each other
#: from it (known opcode, length within the file), or fewer ending at the Footer or the end.
_SYNC_RECORDS: Final = 4
#: The search for the next plausible record reads the file in pieces of this many bytes.
_SCAN_BYTES: Final = 256 << 10
_KNOWN_OPS_ARRAY: Final = np.array(sorted(KNOWN_OPS), np.uint8)


class RecordResync:
    """The check of a record's length against the records around it, and the resynchronisation.

    A part of :class:`~rigtools.ingest.mcap.container.ContainerScanner`, which provides the
    attributes and the warning method declared here.
    """

    path: str
    report: IngestReport
    _src: ByteSource
    _no_sync_from: int

    def _warn(self, reason: str, text: str) -> None:
        raise NotImplementedError

    def _sync(self, pos: int, op: int, length: int) -> tuple[int, int | None]:
        """Check a record's length against the records around it; resynchronise if it lies.

        Returns the length to read the record with and None, or the position of the next
        plausible record (the walk goes on there) when this one is not read. Called when the
        walk's fast check fails (the record is a Chunk, has an opcode the specification does
        not define, or its length does not end at the end of the file or at a record header
        whose length fits). Three cases:

        * A Chunk record whose length does not lead to a plausible record while the length
          its own fields imply (header + compressed records) does: read with the latter (the
          chunk's CRC still vouches for its records).
        * A length past the end of the file, or an unknown opcode whose length does not lead
          to a plausible record: the walk resumes at the first position after ``pos`` where
          :data:`_SYNC_RECORDS` plausible records follow each other (counted ``lost_sync``).
        * Any other record (but a Chunk) whose length leads to no plausible record: if such a
          chain starts inside its claimed content, its length lied (grew) and the walk
          resumes there; otherwise the next record is the damaged one and this one is read.
        """
        src = self._src
        total = src.size
        assert total is not None
        body = pos + RECORD_HEADER_BYTES
        fits = length <= total - body
        if op == OP_CHUNK and not (fits and self._chain(body + length, 2)):
            implied = chunk_content_length(
                src.look(body, min(CHUNK_HEAD_MAX_BYTES, total - body)))
            if implied is not None and implied > total - body and not fits:
                return length, None  # both lengths end past the file: a cut chunk
            if implied is not None and implied <= total - body and \
                    self._chain(body + implied, 2):
                self._warn("chunk_length", f"{self.path}: the Chunk record at byte {pos} "
                           f"claims {length} bytes, its own fields {implied}; read with the "
                           "latter")
                return implied, None
        plausible_op = op in KNOWN_OPS or op >= 0x80
        if not fits or not (plausible_op or self._chain(body + length, 2)):
            nxt = self._scan(pos + 1, total)
            if nxt is None:
                return length, None
            self._lost_sync(pos, nxt, f"its header (opcode 0x{op:02x}, {length} bytes) does "
                            f"not fit the file ({total - body} bytes left)")
            return length, nxt
        if op != OP_CHUNK and not self._chain(body + length, 1):
            nxt = self._scan(body, body + length)
            if nxt is not None:
                self._lost_sync(pos, nxt, f"its length ({length} bytes) leads to no record, "
                                f"one starts at byte {nxt}")
                return length, nxt
        return length, None

    def _is_footer(self, pos: int, length: int) -> bool:
        """True when the record at ``pos`` has a Footer's length and the magic follows it."""
        end = pos + RECORD_HEADER_BYTES + length
        return length == FOOTER_AND_MAGIC_BYTES - len(MAGIC) - RECORD_HEADER_BYTES and \
            self._src.look(end, len(MAGIC)) == MAGIC

    def _chain(self, p: int, n: int, known_first: bool = False) -> bool:
        """True when ``n`` plausible records follow each other from ``p``.

        Plausible: a length within the file, and (for the first record when ``known_first``)
        an opcode the specification defines; other opcodes are allowed further on, as a
        writer may add records of its own. Fewer are enough when they end at a Footer or
        exactly at the end of the file.
        """
        src = self._src
        total = src.size
        assert total is not None
        for i in range(n):
            if p == total:
                return True
            if total - p < RECORD_HEADER_BYTES:
                return False
            op, length = RECORD_HEADER.unpack(src.look(p, RECORD_HEADER_BYTES))
            if length > total - p - RECORD_HEADER_BYTES or (
                    known_first and i == 0 and op not in KNOWN_OPS):
                return False
            if op == OP_FOOTER:
                return self._is_footer(p, length)
            p += RECORD_HEADER_BYTES + length
        return True

    def _scan(self, start: int, stop: int) -> int | None:
        """The first position in ``[start, stop)`` where a chain of plausible records starts.

        A search to the end of the file that finds none is remembered: no later search from
        beyond its start reads the file again (the walk stays linear in the file size).
        """
        src = self._src
        to_end = stop == src.size
        if to_end and start >= self._no_sync_from:
            return None
        total = src.size
        assert total is not None
        p = start
        while p < stop:
            n = min(_SCAN_BYTES, stop - p)
            # candidates: a defined opcode and a length within the file (array operations)
            buf = src.peek(p, n + RECORD_HEADER_BYTES - 1)
            m = min(n, len(buf) - RECORD_HEADER_BYTES + 1)
            if m <= 0:
                break
            ops = np.frombuffer(buf, np.uint8, m)
            lengths = np.ndarray((m,), "<u8", buf, 1, (1,))
            room = np.arange(total - p - RECORD_HEADER_BYTES, total - p - RECORD_HEADER_BYTES - m,
                             -1, dtype=np.int64).astype(np.uint64)
            cand = np.flatnonzero(np.isin(ops, _KNOWN_OPS_ARRAY) & (lengths <= room))
            for i in cand.tolist():
                if self._chain(p + i, _SYNC_RECORDS, known_first=True):
                    return p + i
            p += n
        if to_end:
            self._no_sync_from = min(self._no_sync_from, start)
        return None

    def _lost_sync(self, pos: int, nxt: int, why: str) -> None:
        self.report.reject("lost_sync", 1, f"byte {pos}")
        self._warn("lost_sync", f"{self.path}: the record at byte {pos} is not read: {why}; "
                   f"bytes {pos} to {nxt} skipped, the walk goes on at the next plausible "
                   f"record (byte {nxt})")
