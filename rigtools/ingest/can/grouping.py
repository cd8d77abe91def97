"""The frames of a batch grouped by message: (identifier, extended flag) -> rows, compiled.

:func:`rigtools.ingest.can.assembly.assemble_can` splits each batch by message. With NumPy
and pandas that took a factorisation (``pd.factorize``, a hash table), a stable ``argsort``
of the codes and a ``bincount``: 4.8 ms for 250 000 frames of a few identifiers, a tenth of
a mapped BLF read. One compiled loop with an open-addressing table of the keys seen and a
counting sort does the same in two passes over the frames (1.2-2.2 ms, measured here).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["group_by_message"]

_EMPTY = np.int64(-1)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@njit(cache=True, nogil=True)
def _slot(keys: np.ndarray, key: np.int64, bits: int) -> np.int64:  # pragma: no cover
    """Where ``key`` is in the table ``keys``, or the empty slot where it goes."""
    mask = np.int64((1 << bits) - 1)  # int64 throughout: uint64 with int64 would be float64
    h = np.int64((np.uint64(key) * _GOLDEN) >> np.uint64(64 - bits))
    while keys[h] != key and keys[h] != _EMPTY:
        h = (h + np.int64(1)) & mask
    return h


@njit(cache=True, nogil=True)
def _codes(ids: np.ndarray, ext: np.ndarray, start: int, keys: np.ndarray,
           codes_of: np.ndarray, bits: int, uniques: np.ndarray, n_unique: int,
           codes: np.ndarray) -> tuple[int, int]:  # pragma: no cover - compiled
    """Code each frame from ``start`` by its key; stop before the table is half full.

    Returns where it stopped (``ids.size`` when done) and the number of keys seen. The
    arrays are never reassigned here: growing them inside the loop would cost reference
    counting on every frame (4x slower, measured).
    """
    limit = min(keys.size // 2, uniques.size)
    last = _EMPTY
    last_code = 0
    for i in range(start, ids.size):
        key = np.int64(ids[i]) | (np.int64(ext[i]) << 32)
        if key == last:  # frames of one message often follow each other
            codes[i] = last_code
            continue
        h = _slot(keys, key, bits)
        if keys[h] == _EMPTY:
            if n_unique == limit:
                return i, n_unique
            keys[h] = key
            codes_of[h] = n_unique
            uniques[n_unique] = key
            n_unique += 1
        last = key
        last_code = codes_of[h]
        codes[i] = last_code
    return ids.size, n_unique


@njit(cache=True, nogil=True)
def _counting_sort(codes: np.ndarray,
                   n_unique: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Stable order of the rows by code, and where each code's rows begin."""
    bounds = np.zeros(n_unique + 1, np.int64)
    for c in codes:
        bounds[c + 1] += 1
    for c in range(n_unique):
        bounds[c + 1] += bounds[c]
    fill = bounds[:-1].copy()
    order = np.empty(codes.size, np.int64)
    for i in range(codes.size):
        c = codes[i]
        order[fill[c]] = i
        fill[c] += 1
    return order, bounds


@njit(cache=True, nogil=True)
def _rehash(uniques: np.ndarray, n_unique: int,
            bits: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """A table of ``2**bits`` slots holding the first ``n_unique`` keys, and their codes."""
    keys = np.full(1 << bits, _EMPTY)
    codes_of = np.empty(1 << bits, np.int64)
    for c in range(n_unique):
        s = _slot(keys, uniques[c], bits)
        keys[s] = uniques[c]
        codes_of[s] = c
    return keys, codes_of


def group_by_message(arbitration_id: np.ndarray,
                     is_extended: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows of each message, messages in order of first appearance.

    Parameters
    ----------
    arbitration_id : numpy.ndarray
        Identifiers (uint32, at most 29 bits).
    is_extended : numpy.ndarray
        Extended-frame flags (bool).

    Returns
    -------
    order : numpy.ndarray
        int64 row numbers grouped by message, each group in row order (stable).
    bounds : numpy.ndarray
        int64, ``order[bounds[c]:bounds[c + 1]]`` are the rows of message ``c``.
    keys : numpy.ndarray
        int64 ``identifier | extended << 32`` of message ``c``, in order of first appearance
        (what ``pd.factorize`` gives).
    """
    ids = np.ascontiguousarray(arbitration_id, np.uint32)
    ext = np.ascontiguousarray(is_extended, np.bool_)
    codes = np.empty(ids.size, np.int64)
    bits = 6
    uniques = np.empty(1 << (bits - 1), np.int64)
    keys, codes_of = _rehash(uniques, 0, bits)
    done, n_unique = _codes(ids, ext, 0, keys, codes_of, bits, uniques, 0, codes)
    while done < ids.size:  # half full: a table twice the size, the same codes
        bits += 1
        uniques = np.concatenate([uniques, np.empty_like(uniques)])
        keys, codes_of = _rehash(uniques, n_unique, bits)
        done, n_unique = _codes(ids, ext, done, keys, codes_of, bits, uniques, n_unique, codes)
    order, bounds = _counting_sort(codes, n_unique)
    return order, bounds, uniques[:n_unique].copy()
