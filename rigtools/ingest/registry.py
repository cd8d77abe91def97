"""Choosing a reader: by content first, by suffix where content says nothing.

Each reader module exposes ``NAME``, ``KIND`` (``"can"``, ``"mcap"`` or ``"recording"``),
``sniff(head: bytes) -> bool`` and either ``iter_batches`` (CAN logs) or ``ingest`` (MCAP).
A file whose suffix lies (a BLF named ``.log``) or is missing is still read by the reader its
first bytes name; ``.gz`` is unwrapped first.
"""

from __future__ import annotations

import gzip
import hashlib
import importlib
import io
import zlib
from pathlib import Path
from types import ModuleType
from typing import Any, BinaryIO, Final

from rigtools.errors import RecordingFormatError, UnsupportedFormatError
from rigtools.ingest.recording import IngestReport

__all__ = ["READERS", "SUFFIXES", "detect_format", "open_source", "reader_module", "sha256_of"]

#: Reader modules by format name (modules under ``rigtools.ingest``).
READERS: Final[dict[str, str]] = {
    "mcap": "rigtools.ingest.mcap",
    "blf": "rigtools.ingest.blf",
    "asc": "rigtools.ingest.asc",
    "trc": "rigtools.ingest.trc",
    "candump": "rigtools.ingest.candump",
    "csv": "rigtools.ingest.csv_log",
    "parquet": "rigtools.ingest.parquet",
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

# Content checks in this order: binary magics first, then the text dialects, the loosest last.
_SNIFF_ORDER: Final[tuple[str, ...]] = ("mcap", "parquet", "blf", "trc", "asc", "candump", "csv")

_HEAD_BYTES = 8192


def reader_module(fmt: str) -> ModuleType:
    """Import the reader module of a format."""
    return importlib.import_module(READERS[fmt])


def sha256_of(path: Path) -> tuple[str, int]:
    """SHA-256 (hex) and size of a file, read in 1 MiB blocks."""
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as f:
        while block := f.read(1 << 20):
            h.update(block)
            size += len(block)
    return h.hexdigest(), size


def _is_gzip(path: Path) -> bool:
    with open(path, "rb") as f:
        return f.read(2) == b"\x1f\x8b"


class _GuardedGzip(io.RawIOBase):
    """A gzip stream whose damage ends the stream cleanly and is counted.

    A gzip file cut short or corrupted raises ``EOFError``/``BadGzipFile``/``zlib.error``
    from inside a reader; here it becomes the end of the data, counted ``truncated_stream``,
    so every reader returns what was intact before it.
    """

    def __init__(self, path: Path, report: IngestReport | None) -> None:
        self._gz = gzip.open(path, "rb")
        self._report = report
        self._path = path
        self._pos = 0
        self._broken = False

    def readable(self) -> bool:
        return True

    def readinto(self, b: Any) -> int:
        if self._broken:
            return 0
        try:
            # read1: one decompression step at a time, so a break loses nothing before it.
            data = self._gz.read1(len(b))
            n = len(data)
            b[:n] = data
        except (EOFError, OSError, zlib.error) as exc:
            if self._report is None:  # no report to count it in: let the reader see it
                raise
            self._broken = True
            if self._report is not None:
                self._report.reject("truncated_stream", 1, f"uncompressed byte {self._pos}")
                self._report.warn(f"{self._path}: the gzip stream breaks off after "
                                  f"{self._pos} bytes ({exc}); what came before was read")
            return 0
        self._pos += n
        return n

    def close(self) -> None:
        self._gz.close()
        super().close()


def open_source(path: Path, report: IngestReport | None = None) -> BinaryIO:
    """Open a file for reading, transparently unwrapping gzip (damage counted in ``report``)."""
    if _is_gzip(path):
        return io.BufferedReader(_GuardedGzip(path, report), 1 << 20)  # type: ignore[return-value]
    return open(path, "rb")


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
        The file is empty or missing.
    UnsupportedFormatError
        Neither the content nor the suffix names a known format; the message lists them.
    """
    p = Path(path)
    if fmt is not None:
        if fmt not in READERS:
            raise UnsupportedFormatError(p, None, f"one of {sorted(READERS)}", repr(fmt))
        return fmt
    if not p.is_file():
        raise RecordingFormatError(p, None, "a recording file", "no such file")
    with open_source(p) as f:
        try:
            head = f.read(_HEAD_BYTES)
        except (OSError, EOFError) as exc:
            raise RecordingFormatError(p, 0, "a readable gzip stream", str(exc)) from exc
    if not head:
        raise RecordingFormatError(p, 0, "a non-empty recording", "an empty file")
    for name in _SNIFF_ORDER:
        if reader_module(name).sniff(head):
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

