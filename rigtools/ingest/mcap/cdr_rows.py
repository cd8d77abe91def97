"""Shared pieces of the block readers of ROS 2 (CDR) payloads: byte spans and field reads.

Holds what both block readers of :mod:`rigtools.ingest.mcap.cdr` use on the payloads of one
channel in one chunk: the primitive type table, the :class:`Leaf` record of a primitive field,
:class:`Rows` (the same span of bytes in every payload, as a strided view or one gather), the
checks that every payload has the same bytes or decodable strings where the first one has them
(:func:`same_bytes`, :func:`strings_decode`), the length check of a block
(:func:`checked_block`), and the reads of a field as float64 or int64 arrays (:func:`float_field`,
:func:`int_field`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final, NamedTuple

import numpy as np

__all__ = [
    "PRIMITIVES",
    "Leaf",
    "Rows",
    "checked_block",
    "float_field",
    "int_field",
    "same_bytes",
    "strings_decode",
]

#: Payloads up to this long that do not lie at equal distances are gathered whole at once
#: (longer ones span by span, only the bytes needed).
_WHOLE_GATHER_BYTES: Final = 64
#: Primitive types: (NumPy kind + size, size in bytes).
PRIMITIVES: Final[dict[str, tuple[str, int]]] = {
    "bool": ("u1", 1),
    "byte": ("u1", 1),
    "char": ("i1", 1),
    "int8": ("i1", 1),
    "uint8": ("u1", 1),
    "int16": ("i2", 2),
    "uint16": ("u2", 2),
    "int32": ("i4", 4),
    "uint32": ("u4", 4),
    "int64": ("i8", 8),
    "uint64": ("u8", 8),
    "float32": ("f4", 4),
    "float64": ("f8", 8),
}


class Leaf(NamedTuple):
    """A primitive field (or primitive array) of a walked message.

    ``offset`` counts from the payload's first byte (the encapsulation header); ``elems`` is
    the number of elements (1 for a scalar); ``array`` tells an array from a scalar.
    """

    offset: int
    type: str
    elems: int
    array: bool


class Rows:
    """The ``m`` payloads of ``n`` bytes at ``s``: spans of bytes at one offset in each.

    A strided view of the buffer (no copy) when the payloads lie at equal distances;
    otherwise each span asked for is gathered with one fancy index (records of the span's
    length starting at every byte of the buffer, so the copy is one short run per payload).
    """

    def __init__(self, buf: Any, s: np.ndarray, n: int) -> None:
        m = s.shape[0]
        s0 = int(s[0])
        step = int(s[1] - s[0]) if m > 1 else n
        self.m = m
        self.view: np.ndarray | None = None
        if m == 1 or (step >= n and bool((s[1:] - s[:-1] == step).all())):
            self.view = np.ndarray((m, n), np.uint8, buf, s0, (step, 1))
        self.arr = np.frombuffer(buf, np.uint8)
        self.s = s
        self.first = self.arr[s0 : s0 + n]
        if self.view is None and n <= _WHOLE_GATHER_BYTES:
            self.view = self.span(0, n)  # small payloads: gathered whole, once

    def span(self, off: int, cnt: int) -> np.ndarray:
        """Bytes ``off .. off + cnt`` of every payload, shape ``(m, cnt)``."""
        if self.view is not None:
            return self.view[:, off : off + cnt]
        # a record of cnt bytes starting at every byte of the buffer: one copy per payload
        win = np.ndarray(
            (self.arr.shape[0] - cnt + 1,), np.dtype((np.void, cnt)), self.arr, 0, (1,)
        )
        return win[self.s + off].view(np.uint8).reshape(-1, cnt)


def same_bytes(rows: Rows, spans: Sequence[tuple[int, int]]) -> bool:
    """True when every payload has the first one's bytes in each ``(offset, count)`` span."""
    ref = rows.first
    for off, cnt in spans:
        if cnt and not bool((rows.span(off, cnt) == ref[off : off + cnt]).all()):
            return False
    return True


def strings_decode(rows: Rows, strings: Sequence[tuple[int, int]]) -> bool:
    """True when each string of each payload equals the first's or is all ASCII (so UTF-8)."""
    ref = rows.first
    for off, cnt in strings:
        if not cnt:
            continue
        part = rows.span(off, cnt)
        same = (part == ref[off : off + cnt]).all(axis=1)
        if not bool(same.all()) and not bool((same | (part < 0x80).all(axis=1)).all()):
            return False
    return True


def float_field(rows: Rows, leaf: Leaf, first: int, count: int, e: str) -> np.ndarray:
    """Elements ``first .. first + count`` of a leaf in every payload, float64 ``(m, count)``."""
    kind, size = PRIMITIVES[leaf.type]
    if count == 0:  # an empty array in every payload: no values (the general path's too)
        return np.empty((rows.m, 0), np.float64)
    raw = rows.span(leaf.offset + first * size, count * size)
    if not raw.flags.c_contiguous:
        raw = np.ascontiguousarray(raw)
    vals = raw.view(np.dtype(e + kind))
    if leaf.type == "bool":
        return (vals != 0).astype(np.float64)
    # A float32 signalling NaN becomes a quiet NaN of the same payload, as Python's float()
    # of the general path makes it, silently (NumPy would warn, or raise under seterr).
    with np.errstate(invalid="ignore"):
        return vals.astype(np.float64)


def int_field(rows: Rows, leaf: Leaf, e: str) -> np.ndarray:
    """An integer scalar leaf of every payload, as int64 ``(m,)``."""
    kind, size = PRIMITIVES[leaf.type]
    raw = np.ascontiguousarray(rows.span(leaf.offset, size))
    return raw.view(np.dtype(e + kind))[:, 0].astype(np.int64)


def checked_block(
    buf: Any, starts: np.ndarray, ends: np.ndarray
) -> tuple[Any, np.ndarray, int] | None:
    """The buffer as bytes, the starts, and the one payload length (None if lengths differ)."""
    s = np.asarray(starts, np.int64)
    e = np.asarray(ends, np.int64)
    if s.shape[0] == 0:
        return None
    n = int(e[0] - s[0])
    if n < 4 or not bool((e - s == n).all()):
        return None
    mv = memoryview(buf).cast("B") if not isinstance(buf, memoryview) else buf
    if mv.format != "B" or mv.ndim != 1:
        mv = mv.cast("B")
    return mv, s, n
