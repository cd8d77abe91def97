"""PEAK TRC logs, read with python-can's ``TRCReader`` and every line accounted for.

python-can reads TRC versions 1.0, 1.1, 1.3, 2.0 and 2.1 (a file without
``;$FILEVERSION``, or with a version it does not know, is parsed as 1.0). The file is fed
to python-can line by line through the engine of :mod:`rigtools.ingest.can.asc`, so each
message carries its line number and each line python-can skips is classified here:

* ``;`` lines (header, comments) are expected;
* status lines (version 1.0 ``FFFFFFFF`` bus-state lines, 1.x ``Warng``, 2.x ``ST``, ``EC``,
  ``EV``) are events, tallied in one warning;
* error frames (1.x ``ERROR`` in the data field, 2.x type ``ER``) are counted
  ``error_frame``; remote frames (``RTR``, ``RR``) ``remote_frame``;
* anything else is counted ``unparsable_line`` with its line number.

Timestamps are python-can's: ``;$STARTTIME`` (UNIX epoch, s) plus the offset column; a 1.0
file has no start time and gives the offset alone.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable, Iterator
from typing import BinaryIO, Final

import can
from can.io.trc import TRCFileVersion
from can.util import dlc2len

from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.can.textlog import EVENT, OK, TextLogDialect, head_lines, read_text_log
from rigtools.ingest.recording import IngestReport

__all__ = ["NAME", "READER", "iter_batches", "sniff"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME: Final[str] = "trc"

#: Versions python-can's TRCReader parses (1.0 is also its fallback).
_KNOWN_VERSIONS: Final[frozenset[str]] = frozenset({"1.0", "1.1", "1.3", "2.0", "2.1"})
#: Header comments PEAK tools (and python-can's TRCWriter) put in a version 1.0 file.
_PEAK_HEADER = re.compile(
    r"PCAN|PEAK|Start time:|Columns description|Message Number|TRCWriter", re.IGNORECASE
)
_STATUS_TYPES: Final[frozenset[str]] = frozenset({"ST", "EC", "EV", "WARNG"})
_ERROR_TYPES: Final[frozenset[str]] = frozenset({"ER", "ERROR"})


def sniff(head: bytes) -> bool:
    """True when ``head`` starts a PEAK TRC log.

    The first non-blank line must be a ``;`` comment, and the leading comment block must
    hold ``;$FILEVERSION`` or a PEAK header comment (``PCAN``, ``Start time:``, ``Columns
    description``, ``Message Number``, ...).

    Parameters
    ----------
    head : bytes
        First bytes of the (gzip-unwrapped) file, typically 8 KiB.

    Returns
    -------
    bool
    """
    lines = head_lines(head)
    if not lines or not lines[0].startswith(";"):
        return False
    for s in lines:
        if not s.startswith(";"):
            break
        if s.startswith(";$FILEVERSION") or _PEAK_HEADER.search(s):
            return True
    return False


class _TrcDialect(TextLogDialect):
    name = "trc"
    expected = "a PEAK TRC log (;$FILEVERSION or PEAK header comments, then frame lines)"

    def __init__(self) -> None:
        super().__init__()
        self.header: list[str] = []
        self.body = False
        self.declared_version: str | None = None

    def sniff(self, head: bytes) -> bool:
        return sniff(head)

    def make_reader(self, lines: Iterable[str]) -> Iterable[can.Message]:
        self.reader = can.TRCReader(lines)  # type: ignore[arg-type]
        return self.reader

    def classify(self, text: str) -> str:
        s = text.strip()
        if s.startswith(";"):
            if not self.body and s.startswith(";$") and s not in self.header:
                self.header.append(s)
                if s.startswith(";$FILEVERSION"):
                    self.declared_version = s.partition("=")[2].strip()
            return OK
        self.body = True
        cols = s.split()
        kind = self._type_column(cols)
        if kind in _ERROR_TYPES or any(c.upper() == "ERROR" for c in cols[2:]):
            return "error_frame"
        if kind in _STATUS_TYPES or (len(cols) > 2 and cols[2].upper() == "FFFFFFFF"):
            return EVENT
        return "unparsable_line"

    def _type_column(self, cols: list[str]) -> str | None:
        version = getattr(self.reader, "file_version", TRCFileVersion.UNKNOWN)
        columns: dict[str, int] = getattr(self.reader, "columns", {}) or {}
        try:
            if version in (TRCFileVersion.V2_0, TRCFileVersion.V2_1):
                return cols[columns["T"]].upper()
            if version == TRCFileVersion.V1_1:
                return cols[2].upper()
            if version == TRCFileVersion.V1_3:
                return cols[3].upper()
        except (IndexError, KeyError):
            return None
        return None

    def replay(self) -> list[str]:
        return list(self.header)

    def payload_short(self, msg: can.Message) -> bool:
        # python-can's TRC `dlc` is the DLC code for version 2.x FD frames.
        dlc = int(msg.dlc)
        expected = dlc2len(min(dlc, 15)) if msg.is_fd else min(8, dlc)
        return len(msg.data) < expected

    def hint(self) -> str:
        if self.declared_version is not None and self.declared_version not in _KNOWN_VERSIONS:
            return (f"; the file declares TRC version {self.declared_version}, which python-can "
                    f"does not read (it knows {', '.join(sorted(_KNOWN_VERSIONS))})")
        return ""

    def finish(self, report: IngestReport, path: str, last_line: tuple[int, str] | None) -> None:
        if self.declared_version is not None and self.declared_version not in _KNOWN_VERSIONS:
            report.warn(f"{path}: TRC version {self.declared_version} is not one python-can "
                        "knows; its lines were parsed as version 1.0")


def iter_batches(
    stream: BinaryIO, path: str, report: IngestReport, *, batch_frames: int = 100_000
) -> Iterator[CanFrameBatch]:
    """CAN data frames of a PEAK TRC log, in blocks.

    Parameters
    ----------
    stream : BinaryIO
        The file's bytes (gzip already unwrapped), read line by line; lines that are not
        UTF-8 are decoded as cp1252 and counted in a warning.
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
        Data frames, timestamps (s) exactly as python-can's ``TRCReader`` gives them,
        ``position`` the 1-based line number.

    Raises
    ------
    RecordingFormatError
        The file is empty, is not a TRC log, or python-can fails before any frame (for
        example a version it does not know, or a 2.x file without ``;$COLUMNS``).
    ValueError
        ``batch_frames`` is not a positive integer.
    """
    return _quiet(read_text_log(_TrcDialect(), stream, path, report, batch_frames=batch_frames))


class _DropParseFailures(logging.Filter):
    """Drops python-can's per-line "TRCReader: Failed to parse message" records."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith("TRCReader: Failed to parse message")


def _quiet(batches: Iterator[CanFrameBatch]) -> Iterator[CanFrameBatch]:
    """``batches`` with python-can's TRC logger kept from printing a line per bad line.

    Each such line is already counted ``unparsable_line`` with its line number; python-can
    would also log it (33 lines on stderr for a UTF-16 file). The filter is on the
    ``can.io.trc`` logger only while the read runs, and only drops those records.
    """
    logger = logging.getLogger("can.io.trc")
    quiet = _DropParseFailures()
    logger.addFilter(quiet)
    try:
        yield from batches
    finally:
        logger.removeFilter(quiet)


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = CanLogReader(NAME, sniff, iter_batches)
