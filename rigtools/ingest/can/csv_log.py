"""python-can CSV logs, read with python-can's ``CSVReader`` and every line accounted for.

The format is the one :class:`can.CSVWriter` writes: a header line
``timestamp,arbitration_id,extended,remote,error,dlc,data``, then one line per message
with the time stamp (s), the identifier in hex, three 0/1 flags, the DLC and the payload in
base64. It carries no channel and no CAN FD flag. python-can raises on any line it cannot
read; the engine of :mod:`rigtools.ingest.can.asc` counts such a line ``unparsable_line`` with
its line number and carries on with the next one.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import BinaryIO, Final

import can

from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.can.textlog import OK, TextLogDialect, head_lines, read_text_log
from rigtools.ingest.recording import IngestReport

__all__ = ["HEADER", "NAME", "READER", "iter_batches", "sniff"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME: Final[str] = "csv"
#: The header line python-can's CSVWriter writes.
HEADER: Final[str] = "timestamp,arbitration_id,extended,remote,error,dlc,data"


def sniff(head: bytes) -> bool:
    """True when the first non-blank line of ``head`` is python-can's CSV header.

    Parameters
    ----------
    head : bytes
        First bytes of the (gzip-unwrapped) file, typically 8 KiB.

    Returns
    -------
    bool
    """
    lines = head_lines(head)
    return bool(lines) and lines is not None and lines[0] == HEADER


class _CsvDialect(TextLogDialect):
    name = "csv"
    expected = f"a python-can CSV log (header {HEADER!r})"

    def sniff(self, head: bytes) -> bool:
        return sniff(head)

    def make_reader(self, lines: Iterable[str]) -> Iterable[can.Message]:
        self.reader = can.CSVReader(lines)  # type: ignore[arg-type]
        return self.reader

    def prefilter(
        self, lines: Iterator[tuple[int | None, str]]
    ) -> Iterator[tuple[int | None, str]]:
        """Put the header back in front of a file that lost it.

        python-can's ``CSVReader`` skips its first line unread: without the header that
        is the first frame, lost (a file whose first lines were cut away still reads whole).
        """
        first = True
        for number, text in lines:
            if first and text.strip():
                first = False
                if text.strip() != HEADER:
                    yield None, HEADER
            yield number, text

    def classify(self, text: str) -> str:
        return OK if text.strip() == HEADER else "unparsable_line"

    def replay(self) -> list[str]:
        return [HEADER]  # CSVReader skips its first line

    def payload_short(self, msg: can.Message) -> bool:
        n, dlc = len(msg.data), int(msg.dlc)
        return n < min(8, dlc) or (8 < n < dlc)


def iter_batches(
    stream: BinaryIO, path: str, report: IngestReport, *, batch_frames: int = 100_000
) -> Iterator[CanFrameBatch]:
    """CAN data frames of a python-can CSV log, in blocks.

    Parameters
    ----------
    stream : BinaryIO
        The file's bytes (gzip already unwrapped), read line by line.
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
        Data frames, timestamps (s) as written (``repr`` of the float, so exact), channel
        -1 (the format has none), ``position`` the 1-based line number.

    Raises
    ------
    RecordingFormatError
        The file is empty, is not a python-can CSV log, or no line of it reads.
    ValueError
        ``batch_frames`` is not a positive integer.
    """
    return read_text_log(_CsvDialect(), stream, path, report, batch_frames=batch_frames)


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = CanLogReader(NAME, sniff, iter_batches)
