"""Choosing a reader: by content first, by suffix where content says nothing.

Every format is one reader object satisfying
:class:`~rigtools.ingest.contract.RecordingReader` (``name``, ``sniff(head) -> bool``,
``read(path, request) -> Recording``), listed in :data:`READERS`; the CAN log formats are
:class:`~rigtools.ingest.can.reader.CanLogReader` objects, also listed in :data:`CAN_READERS`.
A file whose suffix lies (a BLF named ``.log``) or is missing is still read by the reader its
first bytes name; ``.gz`` is unwrapped first.
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

from rigtools.errors import RecordingFormatError, UnsupportedFormatError
from rigtools.ingest import mcap, parquet
from rigtools.ingest.can import asc, blf, candump, csv_log, trc
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.contract import RecordingReader
from rigtools.ingest.files import open_source

__all__ = ["CAN_READERS", "READERS", "SUFFIXES", "detect_format"]

#: The CAN log formats by name: frames parsed from the log, decoded through a DBC.
CAN_READERS: Final[dict[str, CanLogReader]] = {
    "blf": blf.READER,
    "trc": trc.READER,
    "asc": asc.READER,
    "candump": candump.READER,
    "csv": csv_log.READER,
}

#: Every format by name, in the order :func:`detect_format` asks them about the content:
#: binary magics first, then the text dialects, the loosest last.
READERS: Final[dict[str, RecordingReader]] = {
    "mcap": mcap.READER,
    "parquet": parquet.READER,
    **CAN_READERS,
}

#: Lower-case suffix -> format name; used only when the content does not identify the file.
SUFFIXES: Final[dict[str, str]] = {
    ".mcap": "mcap",
    ".blf": "blf",
    ".asc": "asc",
    ".trc": "trc",
    ".log": "candump",
    ".csv": "csv",
    ".parquet": "parquet",
}

_HEAD_BYTES = 8192


def detect_format(path: str | Path, fmt: str | None = None) -> str:
    r"""Name the format of a file.

    ===============  ==========================================  =============
    format           content signature                            suffix
    ===============  ==========================================  =============
    ``mcap``         magic ``\x89MCAP0\r\n``                   ``.mcap``
    ``parquet``      magic ``PAR1`` (a normalized recording)      ``.parquet``
    ``blf``          magic ``LOGG``                               ``.blf``
    ``trc``          ``;$FILEVERSION`` or a PEAK header comment   ``.trc``
    ``asc``          ``date``/``base hex`` header lines            ``.asc``
    ``candump``      ``(1700000000.000000) can0 123#...`` lines    ``.log``
    ``csv``          python-can CSV header                        ``.csv``
    ===============  ==========================================  =============

    Any of these may be gzip-compressed (``.gz`` suffix or not).

    Raises
    ------
    RecordingFormatError
        The file is empty or missing, or the path is a directory.
    UnsupportedFormatError
        Neither the content nor the suffix names a known format; the message lists them.
    """
    p = Path(path)
    if p.is_dir():
        raise RecordingFormatError(p, None, "a recording file", "a directory")
    if not p.exists():
        raise RecordingFormatError(p, None, "a recording file", "no such file")
    if not p.is_file():
        raise RecordingFormatError(p, None, "a recording file",
                                   "neither a regular file nor a directory")
    if fmt is not None:
        if fmt not in READERS:
            raise UnsupportedFormatError(p, None, f"one of {sorted(READERS)}", repr(fmt))
        return fmt
    with open_source(p) as f:
        try:
            head = f.read(_HEAD_BYTES)
        except (OSError, EOFError) as exc:
            raise RecordingFormatError(p, 0, "a readable gzip stream", str(exc)) from exc
    if not head:
        raise RecordingFormatError(p, 0, "a non-empty recording", "an empty file")
    for name, reader in READERS.items():
        if reader.sniff(head):
            return name
    suffixes = [s.lower() for s in p.suffixes]
    if suffixes and suffixes[-1] == ".gz":
        suffixes = suffixes[:-1]
    if suffixes and suffixes[-1] in SUFFIXES:
        return SUFFIXES[suffixes[-1]]
    raise UnsupportedFormatError(
        p,
        0,
        "content or a suffix of a supported format: " + ", ".join(sorted(SUFFIXES)) + " (or .gz)",
        repr(head[:16]),
    )

