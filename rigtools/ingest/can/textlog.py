"""The line-accounting engine of the text CAN log readers (ASC, TRC, CSV).

python-can parses each dialect; rigtools feeds it the file line by line and knows, for each
message, which line produced it. A line python-can passes over is classified by the format's
:class:`TextLogDialect`: header, comment and trigger-block lines are expected; time-stamped
lines that are not CAN frames are *events*, tallied in one warning; every other line python-can
could not turn into a message is counted ``unparsable_line`` with its line number (python-can
itself skips them silently, STYLE.md anti-pattern 1). When python-can raises on a line, the
line is counted and the parser restarted on the next one with the header replayed.
"""

from __future__ import annotations

import re
import zlib
from collections import deque
from collections.abc import Iterable, Iterator
from typing import Any, BinaryIO, Final, TypeAlias

import can
import numpy as np

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can.asc_lines import FrameLines
from rigtools.ingest.can.frames import CanFrameBatch, concat, from_messages
from rigtools.ingest.recording import IngestReport

__all__ = ["EVENT", "OK", "FastRuns", "TextLogDialect", "head_lines", "read_text_log"]

_HEAD_BYTES: Final[int] = 8192
#: Bytes read from the stream at a time (at most).
_BLOCK_BYTES: Final[int] = 1 << 16
#: Bytes read at a time for a dialect with a vectorised line parser.
_FAST_BLOCK_BYTES: Final[int] = 1 << 20
#: python-can errors tolerated before its first message; past that the file is refused.
_MAX_ERRORS_BEFORE_DATA: Final[int] = 20
#: Consecutive python-can errors after which the rest of the file is counted, not parsed.
_MAX_ERRORS_IN_ROW: Final[int] = 1000
#: Largest CAN identifier (29-bit extended); python-can parses any hex number of a line.
_MAX_CAN_ID: Final[int] = 0x1FFFFFFF
#: Largest standard (11-bit) identifier; a standard frame above it is a damaged line.
_MAX_STD_ID: Final[int] = 0x7FF
#: Exceptions python-can raises on malformed lines (int()/float() parsing, tuple unpacking,
#: missing columns, an unsupported dialect).
_PARSE_ERRORS: Final = (ValueError, IndexError, KeyError, TypeError, NotImplementedError,
                        OverflowError)

#: Runs of lines of one block a dialect parsed itself: the block's parsed lines, the line
#: number of its first line, and ``(lo, hi, start_s)`` of each run (python-can's time origin).
FastRuns: TypeAlias = tuple[FrameLines, int, list[tuple[int, int, float]]]

#: Line kind returned by :meth:`TextLogDialect.classify`: an expected header or comment line.
OK: Final[str] = "ok"
#: Line kind returned by :meth:`TextLogDialect.classify`: a logged event that is no CAN frame.
EVENT: Final[str] = "event"


def head_lines(head: bytes) -> list[str] | None:
    """Stripped non-blank lines of a sniffing head (latin-1), or None for binary content."""
    if b"\x00" in head:
        return None
    text = head.decode("latin-1")
    if text.startswith("\xef\xbb\xbf"):  # UTF-8 BOM seen through latin-1
        text = text[3:]
    lines = [s.strip() for s in re.split(r"\r\n|\r|\n", text)]
    return [s for s in lines if s]


class TextLogDialect:
    """One text CAN log format, as seen by :func:`read_text_log` (template method hooks).

    A subclass says how to build the python-can reader, how to recognise the lines
    python-can passes over, what to replay when python-can must be restarted after an
    error, and when a message's payload is shorter than its DLC says.
    """

    #: Format name, e.g. ``"asc"``.
    name: str = "text"
    #: What a file of this format is, for error messages.
    expected: str = "a text CAN log"

    def __init__(self) -> None:
        self.reader: Any = None

    def sniff(self, head: bytes) -> bool:
        """Content check (the module's ``sniff``)."""
        raise NotImplementedError

    def make_reader(self, lines: Iterable[str]) -> Iterable[can.Message]:
        """A python-can reader over ``lines``; kept in ``self.reader``."""
        raise NotImplementedError

    def prefilter(
        self, lines: Iterator[tuple[int | None, str]]
    ) -> Iterator[tuple[int | None, str]]:
        """Rewrite the stream of ``(line number, text)`` pairs before python-can sees it.

        Synthetic lines carry ``None`` as line number. Default: unchanged.
        """
        return lines

    def classify(self, text: str) -> str:
        """Kind of a line python-can turned into no message.

        Returns ``"ok"`` (header, comment), ``"event"`` (a logged non-CAN event) or a
        rejection reason (``"unparsable_line"``, ``"error_frame"``).
        """
        raise NotImplementedError

    def replay(self) -> list[str]:
        """Lines that restore python-can's header state when it is restarted mid-file."""
        return []

    def payload_short(self, msg: can.Message) -> bool:
        """True when a data frame carries fewer bytes than its DLC announces."""
        return len(msg.data) < min(8, int(msg.dlc))

    def frame_lines(self, block: bytes) -> FrameLines | None:
        """The lines of ``block`` parsed without python-can, or None (no such parser).

        A dialect that has one returns, per line, whether it is a data frame python-can
        would read exactly so, and its fields; those lines never reach python-can.
        """
        return None

    def fast_start_s(self) -> float | None:
        """python-can's time origin for the lines :meth:`frame_lines` parsed, or None.

        Asked when such lines are due, after python-can has read every line before them
        (its state is theirs). None: not now (python-can is still in the header, or the
        file's dialect is one :meth:`frame_lines` does not read), the lines go to python-can.
        """
        return None

    def hint(self) -> str:
        """Extra explanation for the error raised when python-can reads nothing."""
        return ""

    def finish(self, report: IngestReport, path: str, last_line: tuple[int, str] | None) -> None:
        """Format-specific checks once every line has been read."""


class _LineFeed:
    """Decoded lines of a binary stream, handed to python-can one at a time.

    Every real line handed out is remembered in :attr:`pending` with its 1-based line
    number until the engine settles it; replayed (synthetic) lines are not numbered.
    Blank lines are numbered but never handed out.
    """

    def __init__(self, stream: BinaryIO, dialect: TextLogDialect) -> None:
        self._stream = stream
        self._dialect = dialect
        #: The dialect parses lines itself (:meth:`TextLogDialect.frame_lines`).
        self._fast = type(dialect).frame_lines is not TextLogDialect.frame_lines
        #: Runs of lines the dialect parsed itself, in file order, for the engine:
        #: ``(lines, first line number of the block, [(lo, hi, start_s), ...])``.
        self.fast: list[FastRuns] = []
        #: Set once the rest of the file is only counted: every line goes the slow way.
        self.draining = False
        self._replay: deque[str] = deque()
        self.pending: list[tuple[int, str]] = []
        self.head = bytearray()
        self.n_lines = 0
        self.non_utf8 = 0
        self.first_non_utf8 = 0
        self.read_error: str | None = None
        self.first_line: tuple[int, str] | None = None
        self.last_line: tuple[int, str] | None = None
        self._source = dialect.prefilter(self._decoded())

    def _decoded(self) -> Iterator[tuple[int | None, str]]:
        number = 0
        for chunk in self._chunks():
            frames: FrameLines | None = None
            if self._fast and not self.draining:
                body = chunk.replace(b"\r\n", b"\n").replace(b"\r", b"\n") if (
                    b"\r" in chunk) else chunk
                if not body.endswith(b"\n"):
                    body += b"\n"
                frames = self._dialect.frame_lines(body)
            if frames is not None and bool(frames.plain.any()):
                yield from self._mixed_lines(body, frames, number)
                number += frames.plain.size
                continue
            for text in self._chunk_lines(chunk, number + 1):
                number += 1
                self.n_lines = number
                if text and not text.isspace():
                    item = (number, text)
                    self.last_line = item
                    if self.first_line is None:
                        self.first_line = item
                    yield item

    def _mixed_lines(self, body: bytes, frames: FrameLines,
                     number: int) -> Iterator[tuple[int | None, str]]:
        """The lines of a block some of which the dialect parsed (``frames``).

        A run of lines the dialect parsed becomes a batch in :attr:`fast` when it is reached
        (python-can has then read every line before it); the other lines are handed out as
        :meth:`_decoded` hands them. ``number`` is the line number before the block.
        """
        plain = frames.plain
        ends = frames.line_end
        starts = np.empty_like(ends)
        starts[0] = 0
        starts[1:] = ends[:-1] + 1
        n = plain.size
        i = 0
        for j in [*np.flatnonzero(~plain).tolist(), n]:
            if j > i:  # lines i..j-1 parsed by the dialect
                start_s = None if self.draining else self._dialect.fast_start_s()
                if start_s is not None:
                    if self.fast and self.fast[-1][0] is frames:
                        self.fast[-1][2].append((i, j, start_s))
                    else:
                        self.fast.append((frames, number + 1, [(i, j, start_s)]))
                    self._seen(number + i + 1, self._text(body, starts, ends, i, number))
                    if j - 1 > i:
                        self._seen(number + j, self._text(body, starts, ends, j - 1, number))
                    self.n_lines = number + j
                else:
                    for k in range(i, j):
                        self.n_lines = number + k + 1
                        item = (number + k + 1, self._text(body, starts, ends, k, number))
                        self._seen(*item)
                        yield item
            if j == n:
                break
            self.n_lines = number + j + 1
            text = self._text(body, starts, ends, j, number)
            if text and not text.isspace():
                item = (number + j + 1, text)
                self._seen(*item)
                yield item
            i = j + 1

    def _seen(self, number: int, text: str) -> None:
        item = (number, text)
        self.last_line = item
        if self.first_line is None:
            self.first_line = item

    def _text(self, body: bytes, starts: np.ndarray, ends: np.ndarray, k: int,
              number: int) -> str:
        """Line ``k`` of a block decoded as :meth:`_chunk_lines` decodes it."""
        text = self._decode(body[int(starts[k]) : int(ends[k])], number + k + 1)
        if number + k == 0 and text.startswith("\ufeff"):
            text = text[1:]
        return text

    def _chunks(self) -> Iterator[bytes]:
        """Blocks of the stream that end with a line feed (the last one may not)."""
        tail = b""
        # read1 returns what one underlying read gives: a truncated gzip stream then loses
        # only the last piece, where read() would drop the whole block on the error
        read = getattr(self._stream, "read1", self._stream.read)
        try:
            size = _FAST_BLOCK_BYTES if self._fast else _BLOCK_BYTES
            while block := read(size):
                if len(self.head) < _HEAD_BYTES:
                    self.head += block[: _HEAD_BYTES - len(self.head)]
                data = tail + block
                cut = data.rfind(b"\n") + 1
                if cut:
                    yield data[:cut]
                tail = data[cut:]
        except (OSError, EOFError, zlib.error) as exc:  # truncated gzip, I/O error
            self.read_error = f"{type(exc).__name__}: {exc}"
        if tail:
            yield tail

    def _chunk_lines(self, chunk: bytes, first_number: int) -> list[str]:
        """Decoded lines of a block; CR LF, LF and a lone CR all end a line."""
        if b"\r" in chunk:
            chunk = chunk.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
        try:
            lines = chunk.decode("utf-8").split("\n")
        except UnicodeDecodeError:
            lines = [self._decode(part, first_number + i)
                     for i, part in enumerate(chunk.split(b"\n"))]
        if chunk.endswith(b"\n"):
            lines.pop()
        if first_number == 1 and lines and lines[0].startswith("\ufeff"):
            lines[0] = lines[0][1:]
        return lines

    def _decode(self, part: bytes, number: int) -> str:
        try:
            return part.decode("utf-8")
        except UnicodeDecodeError:
            self.non_utf8 += 1
            if not self.first_non_utf8:
                self.first_non_utf8 = number
        try:
            return part.decode("cp1252")
        except UnicodeDecodeError:
            return part.decode("latin-1")

    def replay(self, lines: Iterable[str]) -> None:
        """Queue synthetic lines to be handed out before the next real one."""
        self._replay.extend(lines)

    def __iter__(self) -> _LineFeed:
        return self

    def __next__(self) -> str:
        if self._replay:
            return self._replay.popleft() + "\n"
        number, text = next(self._source)
        if number is not None:
            self.pending.append((number, text))
        return text + "\n"

    def rest(self) -> Iterator[tuple[int, str]]:
        """The real lines not yet handed out."""
        self.draining = True
        for number, text in self._source:
            if number is not None:
                yield number, text

    def close(self) -> None:
        """python-can closes its file when done; the stream belongs to the caller."""

    @property
    def closed(self) -> bool:
        return False


def _check_batch_frames(batch_frames: int) -> int:
    if isinstance(batch_frames, bool) or not isinstance(batch_frames, int) or batch_frames < 1:
        raise ValueError(f"`batch_frames` must be an integer >= 1, was {batch_frames!r}")
    return batch_frames


def read_text_log(
    dialect: TextLogDialect,
    stream: BinaryIO,
    path: str,
    report: IngestReport,
    *,
    batch_frames: int = 100_000,
) -> Iterator[CanFrameBatch]:
    """Frames of a text CAN log, parsed by python-can, with every line accounted for.

    Each non-blank line ends up in exactly one of: a frame of a yielded batch; an
    ``error_frame`` or ``remote_frame`` rejection; an ``unparsable_line`` rejection (a
    line python-can skipped or raised on, or whose payload is shorter than its DLC); an
    expected header/comment line; a logged event (counted in one warning).

    When python-can raises on a line, that line is counted and python-can is restarted on
    the next line with the header replayed. Up to ``_MAX_ERRORS_BEFORE_DATA`` such errors
    are tolerated before the first message; if nothing is read the file is refused.
    After ``_MAX_ERRORS_IN_ROW`` consecutive errors the rest of the file is counted
    ``unparsable_line`` and a warning is recorded.

    Parameters
    ----------
    dialect : TextLogDialect
        The format.
    stream : BinaryIO
        Binary stream (already gzip-unwrapped), read line by line.
    path : str
        File name, for errors and positions.
    report : IngestReport
        Receives rejections and warnings.
    batch_frames : int
        Frames per yielded batch.

    Yields
    ------
    CanFrameBatch
        Data frames with their 1-based line numbers (``position_unit="line"``).

    Raises
    ------
    RecordingFormatError
        The file is empty, is not of this format, or python-can fails on it before reading
        any message.
    """
    return _run(dialect, stream, path, report, _check_batch_frames(batch_frames))


def _run(
    dialect: TextLogDialect, stream: BinaryIO, path: str, report: IngestReport, batch_frames: int
) -> Iterator[CanFrameBatch]:
    feed = _LineFeed(stream, dialect)
    acc = _Accounting(dialect, report)
    out = _Batcher(batch_frames)
    read_any = False
    errors_in_row = 0
    abandoned = False
    it = iter(dialect.make_reader(feed))
    while True:
        try:
            msg = next(it)
        except StopIteration:
            read_any = out.take(feed.fast) or read_any
            break
        except _PARSE_ERRORS as exc:
            if out.take(feed.fast):  # frames the dialect parsed, before the failing line
                read_any = True
                errors_in_row = 0
            bad = feed.pending.pop() if feed.pending else None
            acc.settle(feed.pending)
            feed.pending.clear()
            if bad is None:  # raised on replayed header lines at the end of the file
                acc.failed(None, "", exc)
                break
            kind = dialect.classify(bad[1])
            if kind in (OK, EVENT, "error_frame"):
                acc.settle([bad])  # e.g. a TRC 1.0 error frame python-can cannot parse
                read_any = read_any or kind == "error_frame"
            else:
                acc.failed(bad[0], bad[1], exc)
                errors_in_row += 1
                if not read_any and acc.n_errors >= _MAX_ERRORS_BEFORE_DATA:
                    break
                if errors_in_row >= _MAX_ERRORS_IN_ROW:
                    abandoned = True
                    break
            feed.replay(dialect.replay())
            it = iter(dialect.make_reader(feed))
            continue
        out.take(feed.fast)
        read_any = True
        errors_in_row = 0
        pending = feed.pending
        number = pending.pop()[0] if pending else feed.n_lines
        if pending:
            acc.settle(pending)
            pending.clear()
        where = f"line {number}"
        if msg.is_error_frame:
            report.reject("error_frame", 1, where)
        elif msg.is_remote_frame:
            report.reject("remote_frame", 1, where)
        elif dialect.payload_short(msg):
            report.reject("unparsable_line", 1, where)
            acc.short += 1
        elif not 0 <= msg.arbitration_id <= (
            _MAX_CAN_ID if msg.is_extended_id else _MAX_STD_ID
        ):
            report.reject("unparsable_line", 1, where)
            acc.bad_id += 1
        else:
            out.message(msg, number)
        yield from out.full()
    acc.settle(feed.pending)
    feed.pending.clear()
    if feed.first_line is None:
        found = f"an unreadable stream ({feed.read_error})" if feed.read_error else "an empty file"
        raise RecordingFormatError(path, "line 1", dialect.expected, found)
    if not read_any and not dialect.sniff(bytes(feed.head)):
        first_no, first_text = feed.first_line
        raise RecordingFormatError(path, f"line {first_no}", dialect.expected,
                                   f"{first_text.strip()[:80]!r}")
    if not read_any and acc.n_errors:
        err_no, err_text, err = acc.first_error
        raise RecordingFormatError(
            path, f"line {err_no}" if err_no else None, dialect.expected,
            f"{err_text.strip()[:80]!r}" if err_text else "no more lines",
            f"python-can {type(err).__name__}: {err}" + dialect.hint(),
        )
    if abandoned:
        stop_line = feed.n_lines
        n_rest, first_rest = 0, 0
        for rest_no, _ in feed.rest():
            n_rest += 1
            first_rest = first_rest or rest_no
        report.reject("unparsable_line", n_rest, f"line {first_rest}")
        report.warn(
            f"{path}: python-can failed on {_MAX_ERRORS_IN_ROW} lines in a row; the "
            f"{n_rest} non-blank lines after line {stop_line} were not parsed and are "
            "counted as unparsable_line"
        )
    if feed.read_error:
        report.reject("truncated_stream", 1, f"line {feed.n_lines + 1}")
        report.warn(f"{path}: the stream ended with an error after line {feed.n_lines} "
                    f"({feed.read_error}); frames up to there are kept")
    acc.summarise(path, feed)
    dialect.finish(report, path, feed.last_line)
    yield from out.rest()


class _Batcher:
    """Frames in file order, batched: python-can's messages and the dialect's own batches.

    Yielded in batches of ``size`` frames (the last one smaller).
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self.parts: list[CanFrameBatch] = []
        #: Runs of lines taken after the last part, not made into a batch yet.
        self.runs: list[FastRuns] = []
        self.n = 0
        self.messages: list[can.Message] = []
        self.positions: list[int] = []

    def message(self, msg: can.Message, line: int) -> None:
        """One data frame python-can read at ``line``."""
        self.messages.append(msg)
        self.positions.append(line)

    def take(self, fast: list[FastRuns]) -> bool:
        """Move the dialect's runs of lines in (``fast`` is emptied); True when any came.

        Runs of one block stay runs until a batch is made of them (one gather for the many
        runs between the error and remote frames of a block).
        """
        if not fast:
            return False
        self._close_messages()
        for lines, first_line, runs in fast:
            last = self.runs[-1] if self.runs else None
            if last is not None and last[0] is lines:
                last[2].extend(runs)
            else:
                self.runs.append((lines, first_line, list(runs)))
            self.n += sum(hi - lo for lo, hi, _ in runs)
        fast.clear()
        return True

    def _close_runs(self) -> None:
        for lines, first_line, runs in self.runs:
            self.parts.append(lines.rows(runs, first_line))
        self.runs = []

    def _close_messages(self) -> None:
        if self.messages:
            self._close_runs()  # the runs came first
            b = from_messages(self.messages, self.positions, "line")
            self.parts.append(b)
            self.n += len(b)
            self.messages, self.positions = [], []

    def full(self) -> Iterator[CanFrameBatch]:
        """The whole batches gathered so far."""
        if self.n + len(self.messages) < self.size:
            return
        if not self.parts and not self.runs:  # python-can's messages only
            yield from_messages(self.messages, self.positions, "line")
            self.messages, self.positions = [], []
            return
        yield from self._split(final=False)

    def rest(self) -> Iterator[CanFrameBatch]:
        """Everything left."""
        yield from self._split(final=True)

    def _split(self, final: bool) -> Iterator[CanFrameBatch]:
        self._close_runs()
        self._close_messages()
        if not self.parts:
            return
        whole = self.parts[0] if len(self.parts) == 1 else concat(self.parts)
        self.parts, self.n = [], 0
        size = self.size
        for lo in range(0, len(whole), size):
            hi = min(lo + size, len(whole))
            piece = whole if (lo, hi) == (0, len(whole)) else whole.take(np.arange(lo, hi))
            if hi - lo < size and not final:
                self.parts, self.n = [piece], len(piece)
                return
            yield piece


class _Accounting:
    """Tallies of the lines python-can produced no message from."""

    def __init__(self, dialect: TextLogDialect, report: IngestReport) -> None:
        self.dialect = dialect
        self.report = report
        self.n_events = 0
        self.first_event = 0
        self.n_errors = 0
        self.first_error: tuple[int | None, str, BaseException] = (None, "", ValueError())
        self.short = 0
        self.bad_id = 0

    def settle(self, lines: Iterable[tuple[int, str]]) -> None:
        for number, text in lines:
            kind = self.dialect.classify(text)
            if kind == OK:
                continue
            if kind == EVENT:
                self.n_events += 1
                self.first_event = self.first_event or number
                continue
            self.report.reject(kind, 1, f"line {number}")

    def failed(self, number: int | None, text: str, exc: BaseException) -> None:
        if not self.n_errors:
            self.first_error = (number, text, exc)
        self.n_errors += 1
        if number is not None:
            self.report.reject("unparsable_line", 1, f"line {number}")

    def summarise(self, path: str, feed: _LineFeed) -> None:
        if self.n_errors:
            number, _, exc = self.first_error
            self.report.warn(
                f"{path}: python-can raised on {self.n_errors} line(s) (first at line "
                f"{number}: {type(exc).__name__}: {exc}); counted as unparsable_line"
            )
        if self.short:
            self.report.warn(
                f"{path}: {self.short} frame line(s) carry fewer payload bytes than their "
                "DLC (truncated lines); counted as unparsable_line"
            )
        if self.bad_id:
            self.report.warn(
                f"{path}: {self.bad_id} frame line(s) carry an identifier above 0x1FFFFFFF "
                "(29 bits, the largest CAN identifier) or a standard-format identifier above "
                "0x7FF (11 bits); counted as unparsable_line"
            )
        if self.n_events:
            self.report.warn(
                f"{path}: {self.n_events} logged event line(s) that are not CAN frames "
                f"(status, statistics, transport protocol, ...) ignored; first at line "
                f"{self.first_event}"
            )
        if feed.non_utf8:
            self.report.warn(
                f"{path}: {feed.non_utf8} line(s) are not valid UTF-8 and were decoded as "
                f"cp1252/latin-1; first at line {feed.first_non_utf8}"
            )

