"""The byte source of the MCAP container walk: sequential reads that never over-allocate.

A record header may claim any length up to 2**64 - 1. :class:`ByteSource` keeps its position
and, where the stream's size is cheap to know (a regular file, a ``BytesIO``), clips every
read to what is left. Where it is not (a ``gzip`` stream), it reads in pieces of
:data:`READ_PIECE_BYTES`, so memory grows with the data that exists, not with the claim.

Where the size is known the source can also be read at a position without moving
(:meth:`ByteSource.peek`, ``os.pread`` on a file), from any thread: the container reads the
next chunk ahead with it. Whatever is read at a position from a file opened by
:func:`~rigtools.ingest.files.open_source` is handed to its
:meth:`~rigtools.ingest.files.HashingFile.took_at`: the provenance's SHA-256 is computed as
the file is read.
"""

from __future__ import annotations

import io
import os
import stat
from collections.abc import Callable, Iterator
from typing import BinaryIO, Final

__all__ = ["READ_PIECE_BYTES", "WINDOW_BYTES", "ByteSource", "known_size"]

#: Read size for streams whose length is unknown (gzip): allocation follows the data read.
READ_PIECE_BYTES: Final = 1 << 20
#: Window of small reads from a regular file (64 KiB).
WINDOW_BYTES: Final = 64 << 10


def known_size(stream: BinaryIO) -> int | None:
    """Bytes from the current position to the end, when cheap to know; else None.

    Known for ``io.BytesIO`` and for files that are regular files on disk; unknown for
    compressed streams, pipes and sockets.
    """
    if isinstance(stream, io.BytesIO):
        with stream.getbuffer() as b:
            return len(b) - stream.tell()
    if isinstance(stream, io.BufferedReader | io.FileIO):
        try:  # a BufferedReader over a decompressing raw stream has no file number
            st = os.fstat(stream.fileno())
        except (OSError, ValueError):  # io.UnsupportedOperation is both
            return None
        if stat.S_ISREG(st.st_mode):
            return max(0, st.st_size - stream.tell())
    return None


class ByteSource:
    """Sequential reads with a position, never allocating more than the data that exists.

    Parameters
    ----------
    stream : binary file object
        Read from its current position, which counts as position 0.

    Attributes
    ----------
    pos : int
        Bytes consumed so far (read or skipped).
    can_peek : bool
        True when :meth:`peek` can read at a position (a regular file or a ``BytesIO``).

    Notes
    -----
    A regular file is read with ``os.pread`` at the source's own position, through a window of
    :data:`WINDOW_BYTES` for small reads, and never seeked: skipping is free, and the small
    records between chunks cost one system call per window instead of one per record (each
    system call lets another thread take the GIL, which the chunk worker is waiting for). The
    stream's own position is then left where it was.
    """

    def __init__(self, stream: BinaryIO) -> None:
        self._f = stream
        self.pos = 0
        # A known size means a seekable stream (a regular file or a BytesIO).
        self._size = known_size(stream)
        self._base = stream.tell() if self._size is not None else 0
        self._fd: int | None = None
        if self._size is not None and not isinstance(stream, io.BytesIO) and \
                hasattr(os, "pread"):
            self._fd = stream.fileno()
        self.can_peek = self._size is not None and (self._fd is not None
                                                    or isinstance(stream, io.BytesIO))
        if self._fd is not None and hasattr(stream, "position_probe"):
            # read at positions, the stream does not move: say where we are (progress display)
            stream.position_probe = lambda: self._base + self.pos
        self._win = b""
        self._win_pos = 0
        # what is read at positions is hashed for the provenance (files.HashingFile.took_at)
        raw = getattr(stream, "raw", None)
        self._took_at: Callable[[int, bytes], None] | None = (
            getattr(raw, "took_at", None) if self._fd is not None else None)

    @property
    def size(self) -> int | None:
        """Bytes from position 0 to the end (None when the size is not known)."""
        return self._size

    def seek(self, pos: int) -> None:
        """Move to position ``pos`` (back or forth; only where :attr:`can_peek`)."""
        if not self.can_peek or self._size is None:
            raise io.UnsupportedOperation("this stream cannot be read at a position")
        pos = max(0, min(pos, self._size))
        if self._fd is None:
            self._f.seek(self._base + pos)
        self.pos = pos

    def remaining(self) -> int | None:
        """Bytes left to the end (None when the size is not known)."""
        return None if self._size is None else self._size - self.pos

    def read(self, n: int) -> bytes:
        """Up to ``n`` bytes; fewer only at the end of the data."""
        rem = self.remaining()
        if rem is not None and self._fd is not None:
            data = self.look(self.pos, min(n, rem))
            self.pos += len(data)
            return data
        if rem is not None:
            n = min(n, rem)
            data = self._f.read(n)
            if len(data) == n:
                self.pos += n
                return data
            pieces = [data]  # the file is shorter than its size said
            pieces.extend(self._pieces(n - len(data)))
        else:
            pieces = list(self._pieces(n))
        data = pieces[0] if len(pieces) == 1 else b"".join(pieces)
        self.pos += len(data)
        return data

    def skip(self, n: int) -> int:
        """Skip up to ``n`` bytes (seeking where the size is known); answer how many."""
        rem = self.remaining()
        if rem is not None:
            n = min(n, rem)
            if self._fd is None:
                self._f.seek(n, io.SEEK_CUR)
            self.pos += n
            return n
        got = sum(len(piece) for piece in self._pieces(n))
        self.pos += got
        return got

    def look(self, pos: int, n: int) -> bytes:
        """Like :meth:`peek`, through the reading thread's window (that thread only)."""
        if self._fd is None or self._size is None:
            return self.peek(pos, n)
        n = max(0, min(n, self._size - pos))
        w = pos - self._win_pos
        if 0 <= w and w + n <= len(self._win):
            return self._win[w : w + n]
        if n >= WINDOW_BYTES // 2:
            return self.peek(pos, n)
        self._win = self.peek(pos, WINDOW_BYTES)
        self._win_pos = pos
        return self._win[:n]

    def peek(self, pos: int, n: int) -> bytes:
        """Up to ``n`` bytes at position ``pos``, without moving; fewer only at the end.

        Only where :attr:`can_peek`; safe from another thread than the one reading.
        """
        if not self.can_peek or self._size is None:
            raise io.UnsupportedOperation("this stream cannot be read at a position")
        n = max(0, min(n, self._size - pos))
        off = self._base + pos
        if self._fd is None:
            assert isinstance(self._f, io.BytesIO)
            with self._f.getbuffer() as b:
                return bytes(b[off : off + n])
        parts = []
        while n > 0:
            piece = os.pread(self._fd, n, off)
            if not piece:
                break
            parts.append(piece)
            n -= len(piece)
            off += len(piece)
        data = parts[0] if len(parts) == 1 else b"".join(parts)
        if self._took_at is not None:
            self._took_at(self._base + pos, data)
        return data

    def _pieces(self, n: int) -> Iterator[bytes]:
        """Read ``n`` bytes in pieces of at most :data:`READ_PIECE_BYTES`, or to the end."""
        while n > 0:
            piece = self._f.read(min(READ_PIECE_BYTES, n))
            if not piece:
                return
            n -= len(piece)
            yield piece
