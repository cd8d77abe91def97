"""The byte source of the MCAP container walk: sequential reads that never over-allocate.

A record header may claim any length up to 2**64 - 1. :class:`ByteSource` keeps its position
and, where the stream's size is cheap to know (a regular file, a ``BytesIO``), clips every
read to what is left. Where it is not (a ``gzip`` stream), it reads in pieces of
:data:`READ_PIECE_BYTES`, so memory grows with the data that exists, not with the claim.
"""

from __future__ import annotations

import io
import os
import stat
from collections.abc import Iterator
from typing import BinaryIO, Final

__all__ = ["READ_PIECE_BYTES", "ByteSource", "known_size"]

#: Read size for streams whose length is unknown (gzip): allocation follows the data read.
READ_PIECE_BYTES: Final = 1 << 20


def known_size(stream: BinaryIO) -> int | None:
    """Bytes from the current position to the end, when cheap to know; else None.

    Known for ``io.BytesIO`` and for files that are regular files on disk; unknown for
    compressed streams, pipes and sockets.
    """
    if isinstance(stream, io.BytesIO):
        with stream.getbuffer() as b:
            return len(b) - stream.tell()
    if isinstance(stream, io.BufferedReader | io.FileIO):
        st = os.fstat(stream.fileno())
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
    """

    def __init__(self, stream: BinaryIO) -> None:
        self._f = stream
        self.pos = 0
        # A known size means a seekable stream (a regular file or a BytesIO).
        self._size = known_size(stream)

    def remaining(self) -> int | None:
        """Bytes left to the end (None when the size is not known)."""
        return None if self._size is None else self._size - self.pos

    def read(self, n: int) -> bytes:
        """Up to ``n`` bytes; fewer only at the end of the data."""
        rem = self.remaining()
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
            self._f.seek(n, io.SEEK_CUR)
            self.pos += n
            return n
        got = sum(len(piece) for piece in self._pieces(n))
        self.pos += got
        return got

    def _pieces(self, n: int) -> Iterator[bytes]:
        """Read ``n`` bytes in pieces of at most :data:`READ_PIECE_BYTES`, or to the end."""
        while n > 0:
            piece = self._f.read(min(READ_PIECE_BYTES, n))
            if not piece:
                return
            n -= len(piece)
            yield piece
