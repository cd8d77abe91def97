"""Vector ASC logs, read with python-can's ``ASCReader`` and every line accounted for.

python-can parses the ASC dialects (classic and CAN FD frames, error and remote frames,
``base hex|dec``, relative or absolute time stamps); rigtools feeds it the file line by line
and knows, for each message, which line produced it. A line python-can passes over is
classified here: header, comment and trigger-block lines are expected; time-stamped lines
that are not CAN frames (chip status, bus statistics, J1939 transport protocol, system
variables, ...) are *events*, tallied in one warning; every other line python-can could not
turn into a message is counted ``unparsable_line`` with its line number (python-can itself
skips them silently, STYLE.md anti-pattern 1).

Timestamps are absolute (s since the UNIX epoch), like those of the BLF, MCAP and candump
readers: python-can's ``ASCReader(..., relative_timestamp=False)`` adds each line's offset to
the measurement start, which is the date of the last ``Begin Triggerblock <date>`` line read,
else the ``date <date>`` header line. Things to know about those dates:

* They are the recording machine's wall-clock time without a time zone; python-can (hence
  rigtools) reads them in the *reading* machine's local time zone (``datetime.strptime(...)
  .timestamp()``). Files written and read on the same machine round-trip; a file recorded in
  another zone comes out shifted by the difference of the zones. (python-can reads BLF start
  times and TRC ``$STARTTIME`` as UTC.)
* They carry milliseconds at best: python-can's ``ASCWriter`` writes the first frame's time
  truncated to the millisecond in the ``Begin Triggerblock`` line and the frames' offsets to
  the first frame with 6 decimals, so its files read back up to 1 ms early (one constant
  offset for the whole file), each offset within 0.5 µs. (``ASCWriter``'s own ``date`` header
  line is the time of writing, not of the measurement; the trigger-block date wins.)
* python-can's ``ASCWriter`` (4.6.1) writes those milliseconds without leading zeros
  (``13.62`` for 13.062 s), which python-can, hence rigtools, reads back as 13.620 s: up to
  0.9 s late. A start date with one or two digits after the seconds (other than ``.0``) is
  read as written and gets a warning in the :class:`IngestReport`.
* A date python-can cannot parse (month names other than its English and German ones, such
  as ``sep`` or ``9月``, a comma before the milliseconds, a numeric date) would make python-can
  raise and lose the file. rigtools falls back to python-can's relative mode instead: from
  that line on times are offsets from the measurement start (s), and the
  :class:`IngestReport` gets a warning naming the line. A file with no date python-can
  recognises (no ``date`` line, or one like ``date sam. sept. ...`` that is not ``date <word>
  <date>``, which is then counted ``unparsable_line``) is read relative too, with a warning.

The line accounting itself lives in :mod:`rigtools.ingest.can.textlog`.
"""

from __future__ import annotations

import io
import re
from collections.abc import Iterable, Iterator
from typing import BinaryIO, Final

import can

from rigtools.ingest.can.asc_lines import FrameLines, parse_frame_lines
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.can.textlog import EVENT, OK, TextLogDialect, head_lines, read_text_log
from rigtools.ingest.recording import IngestReport

__all__ = ["NAME", "READER", "iter_batches", "sniff"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME: Final[str] = "asc"


# --- ASC line patterns (matched on stripped lines) -------------------------------------------
# The header patterns are those of python-can's ASCReader._extract_header.
_DATE = re.compile(r"date\s+\w+\s+.+", re.IGNORECASE)
_BASE = re.compile(r"base\s+(hex|dec)\b", re.IGNORECASE)
_COMMENT = re.compile(r"//")
_EVENTS = re.compile(r"(no)?\s*internal\s+events\s+logged", re.IGNORECASE)
_TRIGGER = re.compile(r"begin\s+triggerblock\b", re.IGNORECASE)
_END_TRIGGER = re.compile(r"end\s+triggerblock\b", re.IGNORECASE)
# The fraction of the seconds in a date ("15:06:13.191" -> "191").
_FRACTION = re.compile(r"\d:\d\d\.(\d+)\b")
# python-can's ASC_TRIGGER_REGEX: a trigger-block line that carries a date.
_TRIGGER_DATE = re.compile(r"begin\s+triggerblock\s+\w+\s+.+", re.IGNORECASE)
_START = re.compile(r"\d+(\.\d*)?\s+start\s+of\s+measurement", re.IGNORECASE)
# What a CAN frame line looks like (looser than python-can, so that a frame python-can
# cannot read, or a frame line cut short, is recognised as one): "<t> CANFD ...",
# "<t> <ch>" alone, "<t> <ch> ErrorFrame", "<t> <ch> <hex id>[x] ...", "<t> <ch> <x> Rx|Tx".
_FRAME_LIKE = re.compile(
    r"\d+(\.\d*)?\s+(CANFD\b|\d+(\s*$|\s+(ErrorFrame\b|[0-9A-F]+x?(\s|$)|\S+\s+(Rx|Tx)\b)))",
    re.IGNORECASE,
)
# A logged event: a time stamp followed by something that is not a CAN frame
# ("CAN 1 Status:...", "1 Statistic:...", "1 J1939TP ...", "SV: ...").
_TIMESTAMPED = re.compile(r"\d+(\.\d*)?\s+\S")
_NO_EVENTS_LINE: Final[str] = "no internal events logged"
#: What python-can raises on a date it cannot turn into a UNIX time (strptime, mktime).
_DATE_ERRORS: Final = (ValueError, OverflowError, OSError)


def _date_error(lines: list[str]) -> BaseException | None:
    """What python-can raises reading ``lines`` with absolute timestamps, or None.

    ``lines`` is a ``date`` header line alone, or an end-of-header line and a ``Begin
    Triggerblock`` line: python-can itself decides whether it finds a date there and can
    parse it.
    """
    text = "".join(f"{line}\n" for line in lines)
    try:
        for _ in can.ASCReader(io.StringIO(text), relative_timestamp=False):
            pass
    except _DATE_ERRORS as exc:
        return exc
    return None



def sniff(head: bytes) -> bool:
    """True when ``head`` (the first bytes of a file) starts a Vector ASC log.

    The first line that is neither blank nor a ``//`` comment must be an ASC header line:
    ``date <weekday> ...``, ``base hex|dec ...`` or ``Begin Triggerblock``.

    Parameters
    ----------
    head : bytes
        First bytes of the (gzip-unwrapped) file, typically 8 KiB.

    Returns
    -------
    bool
    """
    lines = head_lines(head)
    if not lines:
        return False
    for s in lines:
        if s.startswith("//"):
            continue
        return bool(_DATE.match(s) or _BASE.match(s) or _TRIGGER.match(s))
    return False


class _AscDialect(TextLogDialect):
    name = "asc"
    expected = "a Vector ASC log (date/base header, then frame lines)"

    def __init__(self) -> None:
        super().__init__()
        self.header: list[str] = []
        self.trigger: str | None = None
        self.begun = False
        #: Absolute timestamps (python-can's ``relative_timestamp=False``) until a date
        #: python-can cannot parse turns them relative.
        self.absolute = True
        #: A date python-can parsed was seen (header or trigger block).
        self.dated = False
        #: ``(line number, line, python-can's error)`` of the date that turned times relative.
        self.bad_date: tuple[int | None, str, BaseException] | None = None
        #: ``(line number, fraction)`` of the date in force when its milliseconds are ambiguous.
        self.short_fraction: tuple[int | None, str] | None = None
        #: python-can is past the header: lines :meth:`frame_lines` parses skip it.
        self.body = False

    def sniff(self, head: bytes) -> bool:
        return sniff(head)

    def make_reader(self, lines: Iterable[str]) -> Iterable[can.Message]:
        self.reader = can.ASCReader(
            lines, relative_timestamp=not self.absolute  # type: ignore[arg-type]
        )
        return self.reader

    def _check_date(self, number: int | None, text: str, probe: list[str]) -> None:
        """Turn times relative before python-can reads a date it cannot parse (it raises)."""
        if not self.absolute:
            return
        exc = _date_error(probe)
        if exc is None:
            self.dated = True
            # the last date python-can reads sets the start; python-can's ASCWriter writes the
            # milliseconds without leading zeros ("13.62" for 13.062 s)
            fraction = _FRACTION.search(text)
            self.short_fraction = None
            if fraction and len(fraction[1]) < 3 and int(fraction[1]):
                self.short_fraction = (number, fraction[1])
            return
        self.absolute = False
        self.bad_date = (number, text, exc)
        if self.reader is not None:
            # python-can reads this attribute (its constructor argument) on every date line;
            # the line in hand has not reached it yet.
            self.reader.relative_timestamp = True

    def prefilter(
        self, lines: Iterator[tuple[int | None, str]]
    ) -> Iterator[tuple[int | None, str]]:
        # python-can's header scan consumes the first line that is not a header line; when
        # the header has no "internal events logged" line that would be a frame, lost. A
        # synthetic events line ends the header scan instead.
        # Every date line is tried on python-can first (see _check_date).
        for number, text in lines:
            s = text.strip()
            if _DATE.match(s) or _BASE.match(s) or _COMMENT.match(s):
                if _DATE.match(s):
                    self._check_date(number, s, [s])
                if not _COMMENT.match(s):
                    self.header.append(s)
                yield number, text
                continue
            if _EVENTS.match(s):
                yield number, text
            else:
                yield None, _NO_EVENTS_LINE
                self._check_trigger(number, text)
                yield number, text
            break
        # python-can has read the header (and the first line after it): from here on the
        # lines frame_lines parses are read without it
        self.body = True
        for number, text in lines:
            self._check_trigger(number, text)
            yield number, text

    def _check_trigger(self, number: int | None, text: str) -> None:
        s = text.lstrip()
        if s[:5].lower() == "begin" and _TRIGGER_DATE.match(s):
            s = s.rstrip()
            self._check_date(number, s, [_NO_EVENTS_LINE, s])

    def classify(self, text: str) -> str:
        s = text.strip()
        if _TRIGGER.match(s):
            self.trigger = s
            self.begun = True
            return OK
        if (not s or _COMMENT.match(s) or _DATE.match(s) or _BASE.match(s) or _EVENTS.match(s)
                or _END_TRIGGER.match(s) or _START.match(s)):
            return OK
        if _FRAME_LIKE.match(s):
            return "unparsable_line"
        if _TIMESTAMPED.match(s):
            return EVENT
        return "unparsable_line"

    def replay(self) -> list[str]:
        out = [*self.header, _NO_EVENTS_LINE]
        if self.trigger is not None:
            out.append(self.trigger)
        return out

    def frame_lines(self, block: bytes) -> FrameLines | None:
        return parse_frame_lines(block)

    def fast_start_s(self) -> float | None:
        reader = self.reader
        if not self.body or reader is None or getattr(reader, "base", None) != "hex":
            return None
        return float(reader.start_time)

    def payload_short(self, msg: can.Message) -> bool:
        # python-can: FD frames carry `dlc` = data length; classic ones min(8, dlc) bytes.
        expected = int(msg.dlc) if msg.is_fd else min(8, int(msg.dlc))
        return len(msg.data) < expected

    def finish(self, report: IngestReport, path: str, last_line: tuple[int, str] | None) -> None:
        if self.bad_date is not None:
            number, text, exc = self.bad_date
            report.warn(f"{path}: python-can cannot parse the date of line {number} "
                        f"({text[:80]!r}: {type(exc).__name__}: {exc}); timestamps from there "
                        "on are relative to the measurement start (s), not UNIX times")
        elif not self.dated:
            report.warn(f"{path}: no 'date' or 'Begin Triggerblock' line with a date; "
                        "timestamps are relative to the measurement start (s), not UNIX times")
        elif self.short_fraction is not None:
            number, fraction = self.short_fraction
            report.warn(f"{path}: the start date (line {number}) has {len(fraction)} digit(s) "
                        f"after the seconds ('.{fraction}'), read as 0.{fraction} s as python-can "
                        "reads it; python-can's ASCWriter writes milliseconds without leading "
                        "zeros ('.62' for 62 ms), so the absolute times may be up to 0.9 s late")
        if self.begun and last_line is not None and not _END_TRIGGER.match(last_line[1].strip()):
            report.warn(f"{path}: no 'End TriggerBlock' at the end (last line {last_line[0]}); "
                        "the file may be truncated")


def iter_batches(
    stream: BinaryIO, path: str, report: IngestReport, *, batch_frames: int = 100_000
) -> Iterator[CanFrameBatch]:
    """CAN data frames of a Vector ASC log, in blocks.

    Parameters
    ----------
    stream : BinaryIO
        The file's bytes (gzip already unwrapped), read line by line; lines that are not
        UTF-8 are decoded as cp1252 (latin-1 where cp1252 has no character) and counted in
        a warning.
    path : str
        File name, used in errors and warnings.
    report : IngestReport
        Receives ``error_frame``, ``remote_frame`` and ``unparsable_line`` rejections
        (with the first line number of each) and warnings.
    batch_frames : int
        Frames per yielded batch.

    Yields
    ------
    CanFrameBatch
        Data frames, timestamps (s) exactly as python-can's ``ASCReader(...,
        relative_timestamp=False)`` gives them: absolute (UNIX time, from the trigger-block
        or ``date`` line read in local time), or relative to the measurement start when the
        file has no date python-can can parse (then with a warning); ``position`` the 1-based
        line number.

    Raises
    ------
    RecordingFormatError
        The file is empty, is not an ASC log, or python-can fails before any frame.
    ValueError
        ``batch_frames`` is not a positive integer.
    """
    return read_text_log(_AscDialect(), stream, path, report, batch_frames=batch_frames)


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = CanLogReader(NAME, sniff, iter_batches)
