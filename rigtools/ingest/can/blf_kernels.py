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
On the way it decodes the *plain* classic CAN frames (the common case: a data frame with
nothing to report) straight into frame columns, each object's bytes read once; every other
object is left to the NumPy decoding of its type, which reports and warns as before.

:func:`classic_fields` reads the fields of the classic CAN messages found into contiguous
columns, each object's bytes once, instead of NumPy fields of a strided record view.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["classic_fields", "plain_frame_columns", "walk_sound_objects"]


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


#: Ticks from this on are converted through :class:`decimal.Decimal`, as python-can does.
_BIG_TICK = np.uint64(1 << 53)


@njit(cache=True, nogil=True)
def walk_sound_objects(buf: np.ndarray, pos: int, max_object: int, out: np.ndarray,
                       filled: int, decode: bool, seg_starts: np.ndarray,
                       seg_origins: np.ndarray, start_s: float, frames: tuple,
                       n_frames: int) -> tuple[int, int, int]:  # pragma: no cover - compiled
    """Walk the sound objects of ``buf`` from byte ``pos``; decode the plain frames on the way.

    Parameters
    ----------
    buf : numpy.ndarray
        The block, uint8.
    pos : int
        Where the walk stands (the end of the previous object, or 0).
    max_object : int
        Largest object size accepted (bytes).
    out : numpy.ndarray
        int64 ``(capacity, 5)``: per object not decoded here its offset, type, header
        version, object size and header size, written from row ``filled`` on.
    filled : int
        Rows of ``out`` already used.
    decode : bool
        Decode plain frames into ``frames`` (else every object goes to ``out``).
    seg_starts, seg_origins : numpy.ndarray
        int64, the block offset where each container's data starts and that container's
        file offset (the frames' positions).
    start_s : float
        The file's start time (s since the epoch).
    frames : tuple of numpy.ndarray
        The columns of the plain frames (:func:`plain_frame_columns`), written from row
        ``n_frames`` on.
    n_frames : int
        Rows of ``frames`` already used.

    Returns
    -------
    tuple of int
        The objects added to ``out``, the frames added to ``frames`` and the position after
        the last object walked. The walk stops when ``out`` or ``frames`` is full.

    Notes
    -----
    A *plain frame* is a ``CAN_MESSAGE`` or ``CAN_MESSAGE2`` object of header version 1 or 2,
    at least its record's size, no remote frame, DLC at most 15, a tick below 2**53 and a
    channel number of at most 32768: its columns are exactly those
    :meth:`~rigtools.ingest.can.blf_objects.ObjectParser` computes with NumPy (timestamp
    ``float(ticks) / 1e5`` for object flags 1, else ``/ 1e9``, plus the start time; the 29
    identifier bits and the extended flag; DLC capped at 8 and the data bytes beyond it zero;
    the channel number minus one). Every other object (remote and error frames, CAN FD, any
    rarity the NumPy path reports or warns about) goes to ``out`` for that path.
    """
    n = buf.size
    k = filled
    m = n_frames
    off_col, pos_col, ts_col, id_col, ext_col, len_col, data_col, ch_col = frames
    seg = max(0, int(np.searchsorted(seg_starts, pos, side="right")) - 1)
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
        otype = _u32(buf, j + 12)
        hv = _u16(buf, j + 6)
        plain = False
        if decode and (otype == 1 or otype == 86) and (hv == 1 or hv == 2):
            b = j + (32 if hv == 1 else 40)
            if osize >= b - j + 16:
                ticks = np.uint64(_u32(buf, j + 24)) | (np.uint64(_u32(buf, j + 28))
                                                         << np.uint64(32))
                ch = _u16(buf, b)
                plain = bool((buf[b + 2] & 0x80) == 0 and buf[b + 3] <= 15
                             and ticks < _BIG_TICK and ch <= 32768)
        if plain:
            if m == off_col.size:
                break
            while seg + 1 < seg_starts.size and seg_starts[seg + 1] <= j:
                seg += 1
            off_col[m] = j
            pos_col[m] = seg_origins[seg]
            t = np.float64(ticks)
            ts_col[m] = (t / 1e5 if _u32(buf, j + 16) == 1 else t / 1e9) + start_s
            raw = _u32(buf, b + 4)
            id_col[m] = raw & 0x1FFFFFFF
            ext_col[m] = (raw & 0x80000000) != 0
            length = min(int(buf[b + 3]), 8)
            len_col[m] = length
            for q in range(8):
                data_col[m, q] = buf[b + 8 + q] if q < length else 0
            ch_col[m] = ch - 1
            m += 1
        else:
            out[k, 0] = j
            out[k, 1] = otype
            out[k, 2] = hv
            out[k, 3] = osize
            out[k, 4] = _u16(buf, j + 4)
            k += 1
        pos = end
    return k - filled, m - n_frames, pos


def plain_frame_columns(capacity: int) -> tuple[np.ndarray, ...]:
    """Empty columns for ``capacity`` plain frames (see :func:`walk_sound_objects`)."""
    return (np.empty(capacity, np.int64), np.empty(capacity, np.int64),
            np.empty(capacity, np.float64), np.empty(capacity, np.uint32),
            np.empty(capacity, np.bool_), np.empty(capacity, np.uint8),
            np.empty((capacity, 8), np.uint8), np.empty(capacity, np.int16))


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
