"""Vector ASC logs, read with python-can's ``ASCReader`` and every line accounted for.

python-can parses the ASC dialects (classic and CAN FD frames, error and remote frames,
``base hex|dec``, relative or absolute time stamps); rigtools feeds it the file line by line
and knows, for each message, which line produced it. A line python-can passes over is
classified here: header, comment and trigger-block lines are expected; time-stamped lines
that are not CAN frames (chip status, bus statistics, J1939 transport protocol, system
variables, ...) are *events*, tallied in one warning; every other line python-can could not
turn into a message is counted ``unparsable_line`` with its line number (python-can itself
skips them silently, STYLE.md anti-pattern 1).

The line accounting itself lives in :mod:`rigtools.ingest.textlog`.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from typing import BinaryIO, Final

import can

from rigtools.ingest.frames import CanFrameBatch
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.textlog import EVENT, OK, TextLogDialect, head_lines, read_text_log

__all__ = ["KIND", "NAME", "iter_batches", "sniff"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME: Final[str] = "asc"
#: Reader family: yields :class:`~rigtools.ingest.frames.CanFrameBatch` blocks.
KIND: Final[str] = "can"


# --- ASC line patterns (matched on stripped lines) -------------------------------------------
# The header patterns are those of python-can's ASCReader._extract_header.
_DATE = re.compile(r"date\s+\w+\s+.+", re.IGNORECASE)
_BASE = re.compile(r"base\s+(hex|dec)\b", re.IGNORECASE)
_COMMENT = re.compile(r"//")
_EVENTS = re.compile(r"(no)?\s*internal\s+events\s+logged", re.IGNORECASE)
_TRIGGER = re.compile(r"begin\s+triggerblock\b", re.IGNORECASE)
_END_TRIGGER = re.compile(r"end\s+triggerblock\b", re.IGNORECASE)
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

    def sniff(self, head: bytes) -> bool:
        return sniff(head)

    def make_reader(self, lines: Iterable[str]) -> Iterable[can.Message]:
        self.reader = can.ASCReader(lines)  # type: ignore[arg-type]
        return self.reader

    def prefilter(
        self, lines: Iterator[tuple[int | None, str]]
    ) -> Iterator[tuple[int | None, str]]:
        # python-can's header scan consumes the first line that is not a header line; when
        # the header has no "internal events logged" line that would be a frame, lost. A
        # synthetic events line ends the header scan instead.
        for number, text in lines:
            s = text.strip()
            if _DATE.match(s) or _BASE.match(s) or _COMMENT.match(s):
                if not _COMMENT.match(s):
                    self.header.append(s)
                yield number, text
                continue
            if _EVENTS.match(s):
                yield number, text
            else:
                yield None, _NO_EVENTS_LINE
                yield number, text
            break
        yield from lines

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

    def payload_short(self, msg: can.Message) -> bool:
        # python-can: FD frames carry `dlc` = data length; classic ones min(8, dlc) bytes.
        expected = int(msg.dlc) if msg.is_fd else min(8, int(msg.dlc))
        return len(msg.data) < expected

    def finish(self, report: IngestReport, path: str, last_line: tuple[int, str] | None) -> None:
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
        Data frames, timestamps (s) exactly as python-can's ``ASCReader`` gives them
        (relative to the measurement start), ``position`` the 1-based line number.

    Raises
    ------
    RecordingFormatError
        The file is empty, is not an ASC log, or python-can fails before any frame.
    ValueError
        ``batch_frames`` is not a positive integer.
    """
    return read_text_log(_AscDialect(), stream, path, report, batch_frames=batch_frames)
