"""The record walk inside a chunk, and the :class:`MessageBlock` it hands messages on in.

A chunk's uncompressed records are walked by :class:`ChunkRecordWalk` (a part of
:class:`~rigtools.ingest.mcap.container.ContainerScanner`). A run of Message records of one
length is read with array operations: the walk guesses that the next records lie at equal
strides, reads opcode and length at each guessed offset, and takes the run up to the first
record that is not a Message of that length (each record's own length vouches for where the
next one starts, so the guess is checked record by record). Anything else is walked one record
at a time.

Channels taking turns (one message of each in a fixed order, as loggers of several sensors
write them) make a pattern of up to :data:`_MAX_PERIOD` records that repeats: when the records
from a position on are Message records whose lengths repeat with such a period, every further
period is checked (opcode and length of each of its records) and taken with array operations
the same way.

A :class:`MessageBlock` holds the messages of one chunk (the chunk's uncompressed data as a
common buffer, the message header fields as columns), or of a stretch of the data section.
"""

from __future__ import annotations

import functools
from typing import Any, Final, TypeAlias

import numpy as np

from rigtools.ingest.mcap.records import (
    MESSAGE_HEADER,
    MESSAGE_HEADER_BYTES,
    OP_CHANNEL,
    OP_MESSAGE,
    OP_SCHEMA,
    RECORD_HEADER,
    RECORD_HEADER_BYTES,
    ChannelRecord,
)
from rigtools.ingest.recording import IngestReport

__all__ = [
    "ChunkRecordWalk",
    "MessageBlock",
    "ScannedMessage",
]

#: The first guess checks this many records; each further one eight times more.
_RUN_PROBE: Final = 16
#: After a guess that did not pay, this many records are walked one by one before the next.
_RUN_BACKOFF: Final = 8
#: Channels taking turns: patterns of up to this many Message records repeating are read with
#: array operations too.
_MAX_PERIOD: Final = 8

#: A message as :meth:`MessageBlock.messages` hands it on: (channel_id, sequence, log_time
#: (ns), publish_time (ns), payload, offset of the payload in its block's buffer, or -1 when
#: the block has no common buffer).
ScannedMessage: TypeAlias = tuple[int, int, int, int, memoryview, int]


class MessageBlock:
    """Messages found together (one chunk, or a stretch of the data section), as columns.

    Attributes
    ----------
    where : str
        Where the block was found, for tallies (``"byte 1234"``).
    buf : memoryview or None
        The common buffer of a chunk block (its uncompressed records); None otherwise.
    channel_id, sequence : numpy.ndarray
        int64, one per message, in file order.
    log_time, publish_time : numpy.ndarray
        uint64 (ns).
    start, end : numpy.ndarray or None
        int64 byte range of each payload in ``buf`` (None when ``buf`` is None).
    """

    __slots__ = ("_payloads", "buf", "channel_id", "end", "log_time", "publish_time",
                 "sequence", "start", "where")

    def __init__(self, where: str, buf: Any, channel_id: np.ndarray, sequence: np.ndarray,
                 log_time: np.ndarray, publish_time: np.ndarray, start: np.ndarray | None,
                 end: np.ndarray | None, payloads: list[Any] | None = None) -> None:
        self.where = where
        self.buf = buf
        self.channel_id = channel_id
        self.sequence = sequence
        self.log_time = log_time
        self.publish_time = publish_time
        self.start = start
        self.end = end
        self._payloads = payloads

    @classmethod
    def from_messages(cls, where: str, msgs: list[ScannedMessage]) -> MessageBlock:
        """A block without a common buffer, from message tuples (payloads kept as given)."""
        return cls(where, None,
                   np.fromiter((m[0] for m in msgs), np.int64, len(msgs)),
                   np.fromiter((m[1] for m in msgs), np.int64, len(msgs)),
                   np.fromiter((m[2] for m in msgs), np.uint64, len(msgs)),
                   np.fromiter((m[3] for m in msgs), np.uint64, len(msgs)),
                   None, None, [m[4] for m in msgs])

    def __len__(self) -> int:
        return int(self.channel_id.shape[0])

    def messages(self) -> list[ScannedMessage]:
        """The messages as tuples, in file order (payloads are views into ``buf``)."""
        cols = (self.channel_id.tolist(), self.sequence.tolist(), self.log_time.tolist(),
                self.publish_time.tolist())
        if self.buf is None or self.start is None or self.end is None:
            payloads = self._payloads or []
            return [(c, s, lt, pt, p, -1) for c, s, lt, pt, p in zip(*cols, payloads,
                                                                       strict=True)]
        buf = self.buf
        return [(c, s, lt, pt, buf[a:b], a) for c, s, lt, pt, a, b in
                zip(*cols, self.start.tolist(), self.end.tolist(), strict=True)]

    def take(self, idx: np.ndarray | slice) -> MessageBlock:
        """The messages at positions ``idx`` (ascending, or a slice): a block of the same buffer."""
        if self._payloads is None:
            payloads = None
        elif isinstance(idx, slice):
            payloads = self._payloads[idx]
        else:
            payloads = [self._payloads[i] for i in idx.tolist()]
        return MessageBlock(self.where, self.buf, self.channel_id[idx], self.sequence[idx],
                            self.log_time[idx], self.publish_time[idx],
                            None if self.start is None else self.start[idx],
                            None if self.end is None else self.end[idx], payloads)

    def by_channel(self) -> list[tuple[int, MessageBlock]]:
        """The block split by channel id, channels in order of first appearance."""
        cids = self.channel_id
        n = cids.shape[0]
        order = list(dict.fromkeys(cids.tolist()))
        p = len(order)
        if p <= 1:
            return [(order[0], self)] if order else []
        if (cids[p:] == cids[: n - p]).all():
            # channels taking turns (one logger's interleaved channels): strided views
            return [(c, self.take(slice(j, None, p))) for j, c in enumerate(order)]
        return [(c, self.take(np.flatnonzero(cids == c))) for c in order]


@functools.lru_cache(maxsize=64)
def _run_dtype(stride: int) -> np.dtype:
    """Record header and message header fields of Message records ``stride`` bytes apart."""
    return np.dtype({"names": ["op", "len", "cid", "seq", "lt", "pt"],
                     "formats": ["u1", "<u8", "<u2", "<u4", "<u8", "<u8"],
                     "offsets": [0, 1, 9, 11, 15, 23], "itemsize": stride})


def _columns(one: tuple[list[int], ...]) -> tuple[np.ndarray, ...]:
    """Message columns from lists (cid, seq, log time, publish time, payload start, end)."""
    cid, seq, lt, pt, a, b = one
    return (np.array(cid, np.int64), np.array(seq, np.int64), np.array(lt, np.uint64),
            np.array(pt, np.uint64), np.array(a, np.int64), np.array(b, np.int64))


class ChunkRecordWalk:
    """The walk of a chunk's uncompressed records into a :class:`MessageBlock`.

    A part of :class:`~rigtools.ingest.mcap.container.ContainerScanner`, which provides the
    attributes and the record, deferral and warning methods declared here.
    """

    path: str
    report: IngestReport
    channels: dict[int, ChannelRecord]
    n_message_records: int

    def _schema(self, buf: Any, pos: int, end: int, where: str) -> None:
        raise NotImplementedError

    def _channel(self, buf: Any, pos: int, end: int, where: str) -> None:
        raise NotImplementedError

    def _defer(self, cid: int, seq: int, lt: int, pt: int, data: Any, where: str) -> None:
        raise NotImplementedError

    def _warn(self, reason: str, text: str) -> None:
        raise NotImplementedError

    def _chunk_records(self, buf: memoryview, cpos: int, run_min: int) -> MessageBlock | None:
        """The messages of a chunk's uncompressed records, as one block (None when none)."""
        channels = self.channels
        unpack_hdr, unpack_msg = RECORD_HEADER.unpack_from, MESSAGE_HEADER.unpack_from
        hsize, msize = RECORD_HEADER_BYTES, MESSAGE_HEADER_BYTES
        n = len(buf)
        pos = 0
        n_msg = 0
        cols: list[tuple[np.ndarray, ...]] = []
        # messages found one by one, since the last run: cid, seq, lt, pt, payload start, end
        one: tuple[list[int], ...] = ([], [], [], [], [], [])
        quiet = 0
        while pos < n:
            if n - pos < hsize:
                self._bad_in_chunk(cpos, pos, f"{n - pos} stray bytes at the end")
                break
            op, length = unpack_hdr(buf, pos)
            body = pos + hsize
            if length > n - body:
                self._bad_in_chunk(cpos, pos, f"record of {length} bytes, {n - body} left")
                break
            stop = body + length
            if op == OP_MESSAGE:
                if quiet:
                    quiet -= 1
                elif length >= msize and n - stop >= (run_min - 1) * (stop - pos):
                    k = self._run_length(buf, pos, stop - pos, length)
                    taken = 0
                    if k >= run_min:
                        if one[0]:
                            cols.append(_columns(one))
                            one = ([], [], [], [], [], [])
                        self._take_run(buf, cpos, pos, stop - pos, k, cols)
                        taken, pos = k, pos + k * (stop - pos)
                    else:
                        got = self._pattern_run(buf, cpos, pos, run_min, cols, one)
                        if got is not None:
                            one = ([], [], [], [], [], [])
                            taken, pos = got
                    if taken:
                        n_msg += taken
                        continue
                    quiet = _RUN_BACKOFF
                n_msg += 1
                if length < msize:
                    self.report.reject("bad_record", 1, f"chunk at byte {cpos} +{pos}")
                else:
                    cid, seq, lt, pt = unpack_msg(buf, body)
                    if cid in channels:
                        one[0].append(cid)
                        one[1].append(seq)
                        one[2].append(lt)
                        one[3].append(pt)
                        one[4].append(body + msize)
                        one[5].append(stop)
                    else:
                        self._defer(cid, seq, lt, pt, buf[body + msize : stop],
                                    f"chunk at byte {cpos} +{pos}")
            elif op == OP_SCHEMA:
                self._schema(buf, body, stop, f"chunk at byte {cpos} +{pos}")
            elif op == OP_CHANNEL:
                self._channel(buf, body, stop, f"chunk at byte {cpos} +{pos}")
            pos = stop
        self.n_message_records += n_msg
        if one[0]:
            cols.append(_columns(one))
        if not cols:
            return None
        if len(cols) == 1:
            c = cols[0]
        else:
            c = tuple(np.concatenate(parts) for parts in zip(*cols, strict=True))
        cid, seq, lt, pt, start, end = c
        return MessageBlock(f"byte {cpos}", buf, cid, seq, lt, pt, start, end)

    @staticmethod
    def _run_length(buf: memoryview, pos: int, stride: int, length: int) -> int:
        """How many Message records of content ``length`` follow each other from ``pos``.

        The record at ``pos`` is one. Records are checked in windows growing eightfold, so a
        wrong guess costs a few records' worth of work.
        """
        count = (len(buf) - pos) // stride
        dt = _run_dtype(stride)
        k, w = 0, _RUN_PROBE
        while k < count:
            m = min(w, count - k)
            recs = np.frombuffer(buf, dt, m, pos + k * stride)
            ok = (recs["op"] == OP_MESSAGE) & (recs["len"] == length)
            if not ok.all():
                return k + int(ok.argmin())
            k += m
            w *= 8
        return k

    def _pattern_run(self, buf: memoryview, cpos: int, pos: int, run_min: int,
                     cols: list[tuple[np.ndarray, ...]], one: tuple[list[int], ...]
                     ) -> tuple[int, int] | None:
        """Read channels taking turns: a pattern of Message records repeating from ``pos``.

        The next records are walked one by one (at most ``2 * _MAX_PERIOD``); when the first
        ``p`` of them (``2 <= p <= _MAX_PERIOD``) are Message records whose lengths the next
        ``p`` repeat, every further period is checked with array operations (opcode and
        length of each of its records: each record's length vouches for where the next one
        starts) and the periods that pass are taken at once. ``one`` (the messages found
        one by one so far) is flushed to ``cols`` first.

        Returns
        -------
        (int, int) or None
            Messages taken and the position after them; None when no pattern of at least
            ``run_min`` messages starts at ``pos`` (nothing is taken then).
        """
        n = len(buf)
        hsize, msize = RECORD_HEADER_BYTES, MESSAGE_HEADER_BYTES
        unpack_hdr = RECORD_HEADER.unpack_from
        offs: list[int] = []
        lens: list[int] = []
        p = pos
        while len(offs) < 2 * _MAX_PERIOD and n - p >= hsize:
            op, length = unpack_hdr(buf, p)
            if op != OP_MESSAGE or length < msize or length > n - p - hsize:
                break
            offs.append(p - pos)
            lens.append(length)
            p += hsize + length
        for period in range(2, len(offs) // 2 + 1):
            if lens[:period] != lens[period : 2 * period]:
                continue
            size = offs[period]
            k = self._pattern_length(buf, pos, size, offs[:period], lens[:period])
            if k * period < run_min or k < 2:
                return None
            if one[0]:
                cols.append(_columns(one))
            self._take_pattern(buf, cpos, pos, size, k, offs[:period], cols)
            return k * period, pos + k * size
        return None

    @staticmethod
    def _pattern_length(buf: memoryview, pos: int, size: int, offs: list[int],
                        lens: list[int]) -> int:
        """How many periods of ``size`` bytes from ``pos`` hold the pattern's records."""
        count = (len(buf) - pos) // size
        names = [f"{x}{j}" for j in range(len(offs)) for x in ("op", "len")]
        formats = ["u1", "<u8"] * len(offs)
        offsets = [o + d for o in offs for d in (0, 1)]
        dt = np.dtype({"names": names, "formats": formats, "offsets": offsets,
                       "itemsize": size})
        k, w = 0, _RUN_PROBE
        while k < count:
            m = min(w, count - k)
            recs = np.frombuffer(buf, dt, m, pos + k * size)
            ok = np.ones(m, bool)
            for j, length in enumerate(lens):
                ok &= recs[f"op{j}"] == OP_MESSAGE
                ok &= recs[f"len{j}"] == length
            if not ok.all():
                return k + int(ok.argmin())
            k += m
            w *= 8
        return k

    def _take_pattern(self, buf: memoryview, cpos: int, pos: int, size: int, k: int,
                      offs: list[int], cols: list[tuple[np.ndarray, ...]]) -> None:
        """Columns of ``k`` periods of the pattern's records from ``pos`` (checked).

        In file order. ``offs``: offset of each of the pattern's records in its period.
        """
        hdr = RECORD_HEADER_BYTES + MESSAGE_HEADER_BYTES
        period = len(offs)
        cid = np.empty((k, period), np.int64)  # (k, period) in row-major order is file order
        seq = np.empty((k, period), np.int64)
        lt = np.empty((k, period), np.uint64)
        pt = np.empty((k, period), np.uint64)
        start = np.empty((k, period), np.int64)
        end = np.empty((k, period), np.int64)
        first = np.arange(k, dtype=np.int64)
        first *= size
        first += pos + hdr
        for j, off in enumerate(offs):
            # the headers of the pattern's j-th records: size bytes apart, hdr bytes each
            recs = np.ndarray((k,), _run_dtype(hdr), buf, pos + off, (size,))
            stop = offs[j + 1] if j + 1 < period else size
            cid[:, j] = recs["cid"]
            seq[:, j] = recs["seq"]
            lt[:, j] = recs["lt"]
            pt[:, j] = recs["pt"]
            np.add(first, off, out=start[:, j])
            np.add(first, stop - hdr, out=end[:, j])
        self._keep_known(buf, cpos, cid.reshape(-1), seq.reshape(-1), lt.reshape(-1),
                         pt.reshape(-1), start.reshape(-1), end.reshape(-1), cols)

    def _take_run(self, buf: memoryview, cpos: int, pos: int, stride: int, k: int,
                  cols: list[tuple[np.ndarray, ...]]) -> None:
        """Columns of ``k`` Message records ``stride`` bytes apart from ``pos`` (checked)."""
        recs = np.frombuffer(buf, _run_dtype(stride), k, pos)
        cid = recs["cid"].astype(np.int64)
        seq = recs["seq"].astype(np.int64)
        lt = recs["lt"].astype(np.uint64)
        pt = recs["pt"].astype(np.uint64)
        start = np.arange(k, dtype=np.int64)
        start *= stride
        start += pos + RECORD_HEADER_BYTES + MESSAGE_HEADER_BYTES
        end = start + (stride - RECORD_HEADER_BYTES - MESSAGE_HEADER_BYTES)
        self._keep_known(buf, cpos, cid, seq, lt, pt, start, end, cols)

    def _keep_known(self, buf: memoryview, cpos: int, cid: np.ndarray, seq: np.ndarray,
                    lt: np.ndarray, pt: np.ndarray, start: np.ndarray, end: np.ndarray,
                    cols: list[tuple[np.ndarray, ...]]) -> None:
        """Add message columns to ``cols``; those of channels not (yet) defined are held."""
        hdr = RECORD_HEADER_BYTES + MESSAGE_HEADER_BYTES
        unknown = [c for c in np.unique(cid).tolist() if c not in self.channels]
        if unknown:
            later = np.isin(cid, unknown)
            for i in np.flatnonzero(later).tolist():
                self._defer(int(cid[i]), int(seq[i]), int(lt[i]), int(pt[i]),
                            buf[int(start[i]) : int(end[i])],
                            f"chunk at byte {cpos} +{int(start[i]) - hdr}")
            keep = ~later
            cid, seq, lt, pt, start, end = (cid[keep], seq[keep], lt[keep], pt[keep],
                                            start[keep], end[keep])
            if not cid.shape[0]:
                return
        cols.append((cid, seq, lt, pt, start, end))

    def _bad_in_chunk(self, cpos: int, pos: int, detail: str) -> None:
        where = f"chunk at byte {cpos} +{pos}"
        self.report.reject("bad_chunk_record", 1, where)
        self._warn("bad_chunk_record", f"{self.path}: {where}: {detail}; the rest of the chunk "
                   "is not used")
