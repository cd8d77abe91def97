"""Decoding many protobuf ``rigtools.AccelBatch`` messages of the same layout at once."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final, NamedTuple, TypeAlias

import numpy as np

from rigtools.errors import PayloadDecodeError
from rigtools.ingest.mcap.payloads import AccelBatchColumns
from rigtools.ingest.mcap.protobuf import (
    decode_accel_batch_protobuf,
    read_varint,
)

__all__ = ["decode_accel_batches_protobuf"]

_VARINT_SHIFTS: Final = (7 * np.arange(10)).astype(np.uint64)
_TEN: Final = np.arange(10)


def _varints(arr: np.ndarray, pos: np.ndarray, ends: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decode one varint at each ``pos`` (vectorized): values, positions after, and ok."""
    idx = pos[:, None] + _TEN
    np.minimum(idx, arr.shape[0] - 1, out=idx)
    b = arr[idx]
    last = b < 0x80
    length = last.argmax(axis=1) + 1
    parts = (b & 0x7F).astype(np.uint64)
    parts <<= _VARINT_SHIFTS
    parts[_TEN >= length[:, None]] = 0
    after = pos + length
    ok = last.any(axis=1)
    ok &= after <= ends
    return np.bitwise_or.reduce(parts, axis=1), after, ok


def _prefix_length(msg: memoryview) -> int:
    """Bytes of the leading channel, unit and rate fields (shared by a channel's batches)."""
    pos, end = 0, len(msg)
    while pos < end:
        key = msg[pos]
        if key in (0x0A, 0x12):
            length, p = read_varint(msg, pos + 1, end)
            pos = p + length
        elif key == 0x19:
            pos += 9
        else:
            break
    return pos


class _Layout(NamedTuple):
    """The byte layout of one protobuf AccelBatch, for messages laid out the same way.

    The masks tell, byte by byte, what another message must share with this one: 0xFF the
    whole byte (tags, strings, the rate, the packed length), 0x80 the continuation bit (the
    bytes of the counter and stamp varints), 0 nothing (the values).
    """

    length: int
    head_mask: np.ndarray  # mask of the bytes ahead of the values
    tail_mask: np.ndarray  # mask of the bytes after them
    varints: tuple[tuple[int, int] | None, tuple[int, int] | None]  # (offset, width) of 4, 5
    values: tuple[int, int]  # offset and byte length of the packed values
    fields: tuple[str, str, float]  # channel, unit and rate, which the fixed bytes state


def _layout(msg: memoryview, fields: tuple[str, str, float]) -> _Layout | None:
    """The layout of ``msg`` when it is the plain kind: the six fields at most once each.

    ``fields``: channel, unit and rate of ``msg`` (decoded).
    """
    n = len(msg)
    mask = np.zeros(n, np.uint8)
    varints: dict[int, tuple[int, int]] = {}
    values: tuple[int, int] | None = None
    seen: set[int] = set()
    pos = 0
    while pos < n:
        key = msg[pos]
        if key in seen:
            return None
        seen.add(key)
        if key in (0x0A, 0x12, 0x32):
            try:
                length, p = read_varint(msg, pos + 1, n)
            except PayloadDecodeError:
                return None
            if length > n - p:
                return None
            if key == 0x32:
                if length % 4:
                    return None
                mask[pos:p] = 0xFF
                values = (p, length)
            else:
                mask[pos : p + length] = 0xFF
            pos = p + length
        elif key == 0x19:
            if pos + 9 > n:
                return None
            mask[pos : pos + 9] = 0xFF
            pos += 9
        elif key in (0x20, 0x28):
            p = pos + 1
            while p < n and msg[p] & 0x80 and p - pos < 10:
                p += 1
            if p >= n or msg[p] & 0x80:
                return None
            mask[pos] = 0xFF
            mask[pos + 1 : p + 1] = 0x80
            varints[key] = (pos + 1, p - pos)
            pos = p + 1
        else:
            return None
    if values is None:
        return None
    voff, vend = values[0], values[0] + values[1]
    # the values' bytes are free: keep only the masks around them (small, whatever the length)
    return _Layout(n, mask[:voff].copy(), mask[vend:].copy(),
                   (varints.get(0x20), varints.get(0x28)), values, fields)


def _decode_same_layout(mv: memoryview, s: np.ndarray, lay: _Layout, out: _ValuesOut
                        ) -> AccelBatchColumns | None:
    """Decode messages at ``s`` that all share the layout ``lay``, or None.

    The first message must be known to have the layout; every other is checked here.
    """
    m = s.shape[0]
    n = lay.length
    voff, nbytes = lay.values
    vend = voff + nbytes
    s0 = int(s[0])
    step = int(s[1] - s[0]) if m > 1 else n
    if m == 1 or (step >= n and (s[1:] - s[:-1] == step).all()):
        # evenly spaced (interleaved channels of one logger): a 2-D view, no copy
        rows = np.ndarray((m, n), np.uint8, mv, s0, (step, 1))
        head_b, tail_b = rows[:, :voff], rows[:, vend:]
    else:
        rows = None
        arr = np.frombuffer(mv, np.uint8)
        head_b = arr[s[:, None] + np.arange(voff)]
        tail_b = arr[s[:, None] + np.arange(vend, n)]
    ref = np.frombuffer(mv, np.uint8, n, s0)
    if ((head_b ^ ref[:voff]) & lay.head_mask).any() or \
            (vend < n and ((tail_b ^ ref[vend:]) & lay.tail_mask).any()):
        return None
    fields = []
    for field in lay.varints:
        if field is None:
            fields.append(np.zeros(m, np.uint64))
            continue
        off, width = field
        src = head_b if off < voff else tail_b
        off = off if off < voff else off - vend
        parts = src[:, off : off + width] & np.uint8(0x7F)
        parts = parts.astype(np.uint64)
        parts <<= _VARINT_SHIFTS[:width]
        fields.append(np.bitwise_or.reduce(parts, axis=1))
    first, stamp = fields
    if (first >> np.uint64(63)).any():
        return None
    if rows is not None:
        values = _copy_values(None, rows[:, voff:vend], None, 0, nbytes, out)
    else:
        values = _copy_values(np.frombuffer(mv, np.uint8), None, s + voff, 0, nbytes, out)
    return AccelBatchColumns(*lay.fields, first.astype(np.int64), stamp, values)


#: Layouts met lately, by payload length (at most :data:`_MAX_LAYOUTS` lengths, as many
#: layouts each, whose values end the message): the layout, its leading fixed bytes (up to the
#: first varint; a quick filter) and the bytes ahead of the values masked with the layout's
#: mask (equal for exactly the messages of that layout).
_LAYOUTS: dict[int, list[tuple[_Layout, bytes, bytes]]] = {}
_MAX_LAYOUTS: Final = 32


def _masked_head(mv: memoryview, s0: int, lay: _Layout) -> bytes:
    voff = lay.values[0]
    return (np.frombuffer(mv, np.uint8, voff, s0) & lay.head_mask).tobytes()


def _known_layout(mv: memoryview, s0: int, n: int) -> _Layout | None:
    """A remembered layout the message of ``n`` bytes at ``s0`` has (all its fixed bytes)."""
    for lay, prefix, masked in _LAYOUTS.get(n, ()):
        if mv[s0 : s0 + len(prefix)] == prefix and _masked_head(mv, s0, lay) == masked:
            return lay
    return None


def _remember_layout(mv: memoryview, s0: int, lay: _Layout) -> None:
    """Remember the layout of the message at ``s0`` (whose values end it)."""
    offs = [f[0] - 1 for f in lay.varints if f is not None]
    prefix = bytes(mv[s0 : s0 + min([lay.values[0], *offs])])
    known = _LAYOUTS.setdefault(lay.length, [])
    if len(known) >= _MAX_LAYOUTS:
        del known[0]
    known.append((lay, prefix, _masked_head(mv, s0, lay)))
    if len(_LAYOUTS) > _MAX_LAYOUTS:
        _LAYOUTS.clear()


#: ``out(m, k)``: a C-contiguous float32 array of shape ``(m, k)`` for decoded values to go to.
_ValuesOut: TypeAlias = Callable[[int, int], np.ndarray]


def _new_values(m: int, k: int) -> np.ndarray:
    return np.empty((m, k), np.float32)


def _copy_values(arr: np.ndarray | None, rows: np.ndarray | None, q: np.ndarray | None,
                 voff: int, nbytes: int, out: _ValuesOut) -> np.ndarray:
    """The packed values of each message (``nbytes`` at ``q[i]``) as rows of ``out``.

    ``rows`` is the evenly strided 2-D view of the messages (values at column ``voff``) when
    they are evenly spaced: then one strided copy does it. Otherwise ``arr[q[i]:]``.
    """
    m = rows.shape[0] if rows is not None else len(q)  # type: ignore[arg-type]
    dst = out(m, nbytes // 4)
    raw = dst.view(np.uint8).reshape(m, nbytes)
    if rows is not None:
        np.copyto(raw, rows[:, voff : voff + nbytes])
    else:
        assert arr is not None and q is not None
        for i, o in enumerate(q.tolist()):
            raw[i] = arr[o : o + nbytes]
    return dst.view("<f4")


def decode_accel_batches_protobuf(
    buf: Any, starts: np.ndarray, ends: np.ndarray, out: _ValuesOut | None = None
) -> AccelBatchColumns | None:
    """Decode many protobuf ``rigtools.AccelBatch`` messages lying in one buffer at once.

    Parameters
    ----------
    buf : bytes-like
        A chunk's uncompressed data.
    starts, ends : numpy.ndarray
        Byte range of each message payload in ``buf`` (int64, shape ``(m,)``).
    out : callable, optional
        ``out(m, k)`` gives the C-contiguous float32 array of shape ``(m, k)`` the values are
        copied to (asked for only once the messages are known to decode); default: a new
        array.

    Returns
    -------
    AccelBatchColumns or None
        None unless every message is laid out as rigtools writes them: the same channel, unit
        and rate bytes, then the counter and stamp varints (either may be absent when zero),
        then one packed run of the same number of float32 values ending the message. The
        caller then decodes the messages one by one with
        :func:`decode_accel_batch_protobuf`, which gives exactly the same result.

    Notes
    -----
    When all payloads have one length and share the first one's byte layout but for the
    values (same fields in the same order, same strings and rate, same varint widths, same
    packed length; checked on every message with one masked comparison), the fields are read
    at fixed columns of a 2-D view of the messages. Otherwise the varints are decoded with
    array operations over all messages. Either way the values are copied with one strided
    copy when the messages are evenly spaced in the buffer (as interleaved channels of one
    logger are), so the Python work is per chunk, not per message.
    """
    m = len(starts)
    if m == 0:
        return None
    mv = memoryview(buf).cast("B") if not isinstance(buf, memoryview) else buf
    s = np.asarray(starts, np.int64)
    e = np.asarray(ends, np.int64)
    s0 = int(s[0])
    n0 = int(e[0]) - s0
    if (e - s == n0).all():
        lay = _known_layout(mv, s0, n0)
        if lay is None:
            try:
                head = decode_accel_batch_protobuf(mv[s0 : s0 + n0])
            except PayloadDecodeError:
                return None
            lay = _layout(mv[s0 : s0 + n0], (head.channel, head.unit, head.sample_rate_Hz))
            if lay is not None and sum(lay.values) == n0:
                _remember_layout(mv, s0, lay)
        if lay is not None:
            cols = _decode_same_layout(mv, s, lay, out or _new_values)
            if cols is not None:
                return cols
    try:
        head = decode_accel_batch_protobuf(mv[s[0] : e[0]])
    except PayloadDecodeError:
        return None
    plen = _prefix_length(mv[s[0] : e[0]])
    if np.any(e - s < plen + 2):
        return None
    arr = np.frombuffer(mv, np.uint8)
    if plen and not (arr[s[:, None] + np.arange(plen)] == arr[s[0] : s[0] + plen]).all():
        return None
    q = s + plen
    top = arr.shape[0] - 1
    fields = []
    for key in (0x20, 0x28):
        present = (arr[np.minimum(q, top)] == key) & (q < e)
        if present.any():
            v, after, ok = _varints(arr, q + 1, e)
            if not ok[present].all():
                return None
            fields.append(np.where(present, v, np.uint64(0)))
            q = np.where(present, after, q)
        else:
            fields.append(np.zeros(m, np.uint64))
    if not np.all((arr[np.minimum(q, top)] == 0x32) & (q < e)):
        return None
    length, q, ok = _varints(arr, q + 1, e)
    nbytes = int(length[0])
    if nbytes % 4 or not ok.all() or (q + length.astype(np.int64) != e).any() \
            or (length != nbytes).any():
        return None
    first, stamp = fields
    if (first >> np.uint64(63)).any():
        return None
    step = int(q[1] - q[0]) if m > 1 else 0
    rows = None
    if m > 1 and step >= nbytes and (q[1:] - q[:-1] == step).all():
        rows = np.lib.stride_tricks.as_strided(arr[int(q[0]):], shape=(m, nbytes),
                                               strides=(step, 1), writeable=False)
    values = _copy_values(arr, rows, q, 0, nbytes, out or _new_values)
    return AccelBatchColumns(head.channel, head.unit, head.sample_rate_Hz,
                             first.astype(np.int64), stamp, values)
