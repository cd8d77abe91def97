"""Compiled (numba) loops over BLF log objects: the walk over sound headers, classic fields.

:meth:`rigtools.ingest.can.blf_objects.ObjectParser.walk` locates the objects of a block of
decompressed container data. Where every header is sound, this kernel walks them one by one
in a single compiled loop, with exactly the object-by-object rule of the Python walk (that
of python-can): the next ``LOBJ`` signature is the first one within 8 bytes of the previous
object's end (padding), its size is at least 16 bytes and at most the largest accepted, the
object ends inside the block, and another signature follows within 8 bytes of its end (or
the block ends within 8 bytes). It stops at the first object that does not pass, where the
Python walk takes over (a damaged header, a size that lies, an object cut at the block end)
and decides what it is, as before; it never accepts an object the Python walk would refuse.

:func:`classic_fields` reads the fields of the classic CAN messages found into contiguous
columns, each object's bytes once, instead of NumPy fields of a strided record view.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["classic_fields", "walk_sound_objects"]


@njit(cache=True, nogil=True)
def _signature_at(buf: np.ndarray, j: int) -> bool:  # pragma: no cover - compiled
    return buf[j] == 76 and buf[j + 1] == 79 and buf[j + 2] == 66 and buf[j + 3] == 74  # LOBJ


@njit(cache=True, nogil=True)
def _find_signature(buf: np.ndarray, lo: int, hi: int) -> int:  # pragma: no cover - compiled
    """First ``j`` with ``LOBJ`` in ``buf[j:j + 4]`` and ``lo <= j``, ``j + 4 <= hi``; or -1."""
    for j in range(lo, hi - 3):
        if _signature_at(buf, j):
            return j
    return -1


@njit(cache=True, nogil=True)
def _u16(buf: np.ndarray, j: int) -> np.int64:  # pragma: no cover - compiled
    return np.int64(buf[j]) | (np.int64(buf[j + 1]) << 8)


@njit(cache=True, nogil=True)
def _u32(buf: np.ndarray, j: int) -> np.int64:  # pragma: no cover - compiled
    return _u16(buf, j) | (_u16(buf, j + 2) << 16)


@njit(cache=True, nogil=True)
def walk_sound_objects(buf: np.ndarray, pos: int, max_object: int, out: np.ndarray,
                       filled: int) -> tuple[int, int]:  # pragma: no cover - compiled
    """Walk the sound objects of ``buf`` from byte ``pos``.

    Parameters
    ----------
    buf : numpy.ndarray
        The block, uint8.
    pos : int
        Where the walk stands (the end of the previous object, or 0).
    max_object : int
        Largest object size accepted (bytes).
    out : numpy.ndarray
        int64 ``(capacity, 5)``: per object its offset, type, header version, object size
        and header size, written from row ``filled`` on; the walk stops when it is full.
    filled : int
        Rows of ``out`` already used.

    Returns
    -------
    tuple of int
        The number of objects walked and the position after the last of them.
    """
    n = buf.size
    k = filled
    while k < out.shape[0]:
        j = _find_signature(buf, pos, min(pos + 8, n))
        if j < 0 or j + 16 > n:
            break
        osize = int(_u32(buf, j + 8))
        if osize < 16 or osize > max_object:
            break
        end = j + osize
        if end > n:
            break
        if end + 8 <= n and _find_signature(buf, end, end + 8) < 0:
            break
        out[k, 0] = j
        out[k, 1] = _u32(buf, j + 12)
        out[k, 2] = _u16(buf, j + 6)
        out[k, 3] = osize
        out[k, 4] = _u16(buf, j + 4)
        k += 1
        pos = end
    return k - filled, pos


@njit(cache=True, nogil=True)
def classic_fields(buf: np.ndarray, offs: np.ndarray, b: int, flags: np.ndarray,
                   ts: np.ndarray, ch: np.ndarray, fl: np.ndarray, dlc: np.ndarray,
                   ident: np.ndarray, data: np.ndarray) -> None:  # pragma: no cover - compiled
    """The fields of the ``CAN_MESSAGE`` / ``CAN_MESSAGE2`` objects at ``offs``, in place.

    As python-can unpacks them (little-endian): the object flags (uint32 at byte 16) and
    timestamp (uint64 at 24) of the header, then, from ``b`` (16 plus the rest of the header
    of its version), channel (uint16), message flags, DLC, identifier (uint32) and the 8 data
    bytes. Each object's bytes are read once, into contiguous columns.
    """
    for i in range(offs.size):
        o = offs[i]
        flags[i] = _u32(buf, o + 16)
        ts[i] = np.uint64(_u32(buf, o + 24)) | (np.uint64(_u32(buf, o + 28)) << np.uint64(32))
        ch[i] = _u16(buf, o + b)
        fl[i] = buf[o + b + 2]
        dlc[i] = buf[o + b + 3]
        ident[i] = _u32(buf, o + b + 4)
        for k in range(8):
            data[i, k] = buf[o + b + 8 + k]
