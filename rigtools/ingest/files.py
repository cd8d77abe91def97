"""Opening a recording file: gzip unwrapped with its damage counted, and the file's SHA-256.

Both the format detection (:func:`rigtools.ingest.registry.detect_format`) and every reader
open files through :func:`open_source`, so a ``.gz`` of any format reads like the plain file
and a gzip stream that breaks off ends the data cleanly instead of raising inside a reader.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from rigtools.ingest.recording import IngestReport

__all__ = ["TrackedFile", "open_source", "sha256_of"]


class TrackedFile(io.BufferedReader):
    """A buffered recording file that says how far into the file on disk it has been read.

    For progress displays, polled from another thread while a reader works. A reader that
    reads at positions (``os.pread``, the MCAP container) instead of moving the stream sets
    :attr:`position_probe`; a gzip file is measured at its compressed offset.
    """

    #: The reader's own position in the file (bytes), when ``tell()`` is not it.
    position_probe: Callable[[], int] | None = None

    def consumed(self) -> int:
        """Bytes of the file on disk read so far (approximately, for display)."""
        probe = self.position_probe
        if probe is not None:
            return int(probe())
        raw = self.raw
        if isinstance(raw, _GuardedGzip):
            return raw.compressed_position()
        return self.tell()


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

    def compressed_position(self) -> int:
        """Bytes of the gzip file read so far."""
        fileobj = getattr(self._gz, "fileobj", None)
        try:
            return int(fileobj.tell()) if fileobj is not None else 0
        except (OSError, ValueError):
            return 0

    def close(self) -> None:
        self._gz.close()
        super().close()


def open_source(path: Path, report: IngestReport | None = None) -> BinaryIO:
    """Open a file for reading, transparently unwrapping gzip (damage counted in ``report``)."""
    if _is_gzip(path):
        return TrackedFile(_GuardedGzip(path, report), 1 << 20)  # type: ignore[return-value]
    return TrackedFile(io.FileIO(path, "rb"))  # type: ignore[return-value]
