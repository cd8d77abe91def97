"""Opening a recording file: gzip unwrapped with its damage counted, and the file's SHA-256.

Both the format detection (:func:`rigtools.ingest.registry.detect_format`) and every reader
open files through :func:`open_source`, so a ``.gz`` of any format reads like the plain file
and a gzip stream that breaks off ends the data cleanly instead of raising inside a reader.

The file's bytes are hashed as they are read (:class:`HashingFile`): a reader that reads its
file from the first byte to the last gets the SHA-256 of the provenance without a second pass
over the file and without a second thread (SHA-256 runs at about a gigabyte a second on a
core with the SHA extensions: a few percent of a text log's parsing); :func:`source_sha256`
hashes what the reader left unread. A reader that reads at positions (``os.pread``, the MCAP
container and its chunk worker) hands what it read to :meth:`HashingFile.took_at`, from any
thread, and the same holds: the bytes are hashed in the thread that read them, in file order.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import os
import threading
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO, Final

from rigtools.ingest.recording import IngestReport

__all__ = ["HASH_GAP_BYTES", "HashingFile", "TrackedFile", "open_source", "sha256_of",
           "source_sha256"]

#: Largest run of unread bytes :meth:`HashingFile.took_at` reads itself to keep hashing in
#: order (records a reader skips: message indexes, attachments); a read further ahead (the
#: footer before the walk) is left for the walk to reach or for :meth:`HashingFile.sha256`.
HASH_GAP_BYTES: Final = 16 << 20


class HashingFile(io.FileIO):
    """A file opened for reading whose bytes are hashed (SHA-256) as they are read.

    Reads that continue where the hashed part ends extend it; so do reads at a position
    (``os.pread``) that the reader hands to :meth:`took_at`. Anything else (a seek back, a
    read far ahead) is read but not hashed, and :meth:`sha256` hashes the rest of the file
    from the end of the hashed part. Thread-safe: :meth:`took_at` may be called from the
    threads that read.
    """

    def __init__(self, path: str | Path) -> None:
        super().__init__(path, "rb")
        self._sha = hashlib.sha256()
        self._hashed = 0
        self._lock = threading.Lock()

    def _took(self, at: int, data: Any, n: int) -> None:
        if n > 0 and at <= self._hashed < at + n:
            with self._lock:
                self._extend(at, data, n)

    def _extend(self, at: int, data: Any, n: int) -> None:
        """Hash the part of ``data[:n]`` (read at ``at``) past the hashed part (lock held)."""
        skip = self._hashed - at
        if 0 <= skip < n:
            self._sha.update(memoryview(data)[skip:n])
            self._hashed = at + n

    @property
    def hashed(self) -> int:
        """Bytes from the start of the file hashed so far."""
        return self._hashed

    def took_at(self, at: int, data: bytes) -> None:
        """Hash ``data``, read at byte ``at`` of the file, if it extends the hashed part.

        Where it starts after the hashed part by at most :data:`HASH_GAP_BYTES`, the bytes
        between are read (``os.pread``) and hashed first; a piece already hashed, or further
        ahead, is ignored.
        """
        n = len(data)
        if n == 0 or at + n <= self._hashed or at > self._hashed + HASH_GAP_BYTES:
            return
        with self._lock:
            while self._hashed < at:
                gap = os.pread(self.fileno(), min(at - self._hashed, 1 << 20), self._hashed)
                if not gap:
                    return
                self._sha.update(gap)
                self._hashed += len(gap)
            self._extend(at, data, n)

    def readinto(self, b: Any) -> int | None:  # type: ignore[override]
        """Read into ``b`` (see :class:`io.FileIO`), hashing what extends the hashed part."""
        at = self.tell()
        n = super().readinto(b)
        self._took(at, b, n or 0)
        return n

    def read(self, size: int | None = -1) -> bytes:
        """Read up to ``size`` bytes (all with -1), hashing what extends the hashed part."""
        at = self.tell()
        data = super().read(size)
        self._took(at, data, len(data))
        return data

    def readall(self) -> bytes:
        """Read to the end, hashing what extends the hashed part."""
        return self.read(-1)

    def sha256(self) -> tuple[str, int]:
        """SHA-256 (hex) and size of the whole file; the unread rest is read now."""
        with self._lock:
            h = self._sha.copy()
            size = self._hashed
        with open(self.name, "rb") as f:
            f.seek(size)
            while block := f.read(1 << 20):
                h.update(block)
                size += len(block)
        return h.hexdigest(), size


def source_sha256(stream: BinaryIO) -> tuple[str, int] | None:
    """SHA-256 (hex) and size of the file behind a stream of :func:`open_source`.

    None when the stream does not hash its file (not opened by :func:`open_source`).
    """
    raw = getattr(stream, "raw", None)
    if isinstance(raw, _GuardedGzip):
        raw = raw.source
    if isinstance(raw, HashingFile):
        return raw.sha256()
    return None


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
        #: The gzip file itself, hashed as gzip reads it.
        self.source = HashingFile(path)
        self._gz = gzip.GzipFile(fileobj=self.source, mode="rb")
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
        self.source.close()
        super().close()


def open_source(path: Path, report: IngestReport | None = None) -> BinaryIO:
    """Open a file for reading, transparently unwrapping gzip (damage counted in ``report``).

    The file's bytes are hashed as they are read (:func:`source_sha256`).
    """
    if _is_gzip(path):
        return TrackedFile(_GuardedGzip(path, report), 1 << 20)  # type: ignore[return-value]
    return TrackedFile(HashingFile(path))  # type: ignore[return-value]
