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
from typing import Any, BinaryIO, Final

import can

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can.frames import CanFrameBatch, from_messages
from rigtools.ingest.recording import IngestReport

__all__ = ["EVENT", "OK", "TextLogDialect", "head_lines", "read_text_log"]

_HEAD_BYTES: Final[int] = 8192
#: Bytes read from the stream at a time (at most).
_BLOCK_BYTES: Final[int] = 1 << 16
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
            for text in self._chunk_lines(chunk, number + 1):
                number += 1
                self.n_lines = number
                if text and not text.isspace():
                    item = (number, text)
                    self.last_line = item
                    if self.first_line is None:
                        self.first_line = item
                    yield item

    def _chunks(self) -> Iterator[bytes]:
        """Blocks of the stream that end with a line feed (the last one may not)."""
        tail = b""
        # read1 returns what one underlying read gives: a truncated gzip stream then loses
        # only the last piece, where read() would drop the whole block on the error
        read = getattr(self._stream, "read1", self._stream.read)
        try:
            while block := read(_BLOCK_BYTES):
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
    messages: list[can.Message] = []
    positions: list[int] = []
    read_any = False
    errors_in_row = 0
    abandoned = False
    it = iter(dialect.make_reader(feed))
    while True:
        try:
            msg = next(it)
        except StopIteration:
            break
        except _PARSE_ERRORS as exc:
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
            messages.append(msg)
            positions.append(number)
            if len(messages) >= batch_frames:
                yield from_messages(messages, positions, "line")
                messages, positions = [], []
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
    if messages:
        yield from_messages(messages, positions, "line")


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

