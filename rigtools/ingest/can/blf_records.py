"""The layouts of BLF log objects and the reading of their fields.

The ``LOBJ`` object header, the object types :mod:`rigtools.ingest.can.blf` and
:mod:`rigtools.ingest.can.blf_objects` tell apart, the NumPy structured dtypes of
``CAN_MESSAGE`` (1), ``CAN_MESSAGE2`` (86), ``CAN_FD_MESSAGE`` (100) and ``CAN_FD_MESSAGE_64``
(101) as python-can unpacks them, the fields of the objects of one type read at once, and
their timestamps in seconds as python-can computes them.
"""

from __future__ import annotations

import struct
from decimal import Decimal
from typing import Any

import numpy as np

from rigtools.ingest.can.blf_kernels import classic_fields
from rigtools.ingest.can.frames import byte_rows

__all__ = [
    "CAN_FD_MESSAGE",
    "CAN_FD_MESSAGE_64",
    "CAN_MESSAGE",
    "CAN_MESSAGE2",
    "CLASSIC_TYPES",
    "ERROR_TYPES",
    "FRAME_TYPES",
    "HEADER_REST",
    "LOBJ",
    "LOG_CONTAINER",
    "OBJ_BASE",
    "RECORD_DTYPES",
    "read_records",
    "record_dtype",
    "tick_seconds",
]

#: The base header of every log object: signature, header size, header version, object size,
#: object type.
OBJ_BASE = struct.Struct("<4sHHLL")
#: Signature at the start of every log object.
LOBJ = b"LOBJ"

#: Frame object types: classic CAN messages (1, 86) and CAN FD messages (100, 101).
CAN_MESSAGE = 1
_CAN_ERROR = 2
#: Object type of a ``LOG_CONTAINER``.
LOG_CONTAINER = 10
_CAN_ERROR_EXT = 73
CAN_MESSAGE2 = 86
CAN_FD_MESSAGE = 100
CAN_FD_MESSAGE_64 = 101
_CAN_FD_ERROR_64 = 104
#: Error-frame object types.
ERROR_TYPES = frozenset({_CAN_ERROR, _CAN_ERROR_EXT, _CAN_FD_ERROR_64})
#: The object types that carry a data or remote frame.
FRAME_TYPES = frozenset({CAN_MESSAGE, CAN_MESSAGE2, CAN_FD_MESSAGE, CAN_FD_MESSAGE_64})

#: Bytes after the 16-byte base header that python-can unpacks as the object header proper,
#: by header version.
HEADER_REST = {1: 16, 2: 24}


def record_dtype(obj_type: int, header_version: int) -> np.dtype:
    """Fields of one object (offsets from the ``LOBJ`` signature), as python-can unpacks them."""
    b = 16 + HEADER_REST[header_version]
    names = ["flags", "ts"]
    formats: list[object] = ["<u4", "<u8"]
    offsets = [16, 24]
    if obj_type in (CAN_MESSAGE, CAN_MESSAGE2):  # channel, flags, dlc, id, data[8]
        names += ["ch", "fl", "dlc", "id", "data"]
        formats += ["<u2", "u1", "u1", "<u4", ("u1", 8)]
        offsets += [b, b + 2, b + 3, b + 4, b + 8]
        size = b + 16
    elif obj_type == CAN_FD_MESSAGE:  # ..., fd flags, valid bytes, 5 pad, data[64]
        names += ["ch", "fl", "dlc", "id", "fdfl", "valid", "data"]
        formats += ["<u2", "u1", "u1", "<u4", "u1", "u1", ("u1", 64)]
        offsets += [b, b + 2, b + 3, b + 4, b + 13, b + 14, b + 20]
        size = b + 84
    elif obj_type == CAN_FD_MESSAGE_64:  # channel u8, dlc, valid, txcount, id, ..., flags
        names += ["ch", "dlc", "valid", "id", "fdfl", "dir", "ext"]
        formats += ["u1", "u1", "u1", "<u4", "<u4", "u1", "u1"]
        offsets += [b, b + 1, b + 2, b + 4, b + 12, b + 34, b + 35]
        size = b + 40
    else:  # pragma: no cover - only frame types are decoded
        raise ValueError(obj_type)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": size})


#: The record dtype of each frame type and header version.
RECORD_DTYPES = {(t, v): record_dtype(t, v) for t in FRAME_TYPES for v in (1, 2)}


def tick_seconds(flags: np.ndarray, ts: np.ndarray, start_s: float) -> np.ndarray:
    """Seconds since the epoch of object ticks ``ts``, bit for bit as python-can has them.

    python-can computes ``float(Decimal(ts) * factor) + start`` with ``factor`` 1e-5 when
    the object flags equal 1 (10 µs ticks) and 1e-9 otherwise. For ``ts < 2**53`` the
    float division ``ts / 1e5`` or ``ts / 1e9`` is that same correctly rounded quotient;
    larger ticks go through :class:`decimal.Decimal` as python-can does.
    """
    ten_us = flags == 1
    if ten_us.all():
        out = ts.astype(np.float64) / 1e5
    elif not ten_us.any():
        out = ts.astype(np.float64) / 1e9
    else:
        out = ts.astype(np.float64) / np.where(ten_us, 1e5, 1e9)
    big = ts >= (1 << 53)
    if big.any():
        for i in np.flatnonzero(big).tolist():
            factor = Decimal("1e-5") if ten_us[i] else Decimal("1e-9")
            out[i] = float(Decimal(int(ts[i])) * factor)
    out += start_s
    return out


#: The classic CAN message types, whose fields the compiled loop reads.
CLASSIC_TYPES = frozenset({CAN_MESSAGE, CAN_MESSAGE2})


def _classic(a: np.ndarray, offs: np.ndarray, v: int) -> dict[str, np.ndarray]:
    """The fields of classic CAN objects as contiguous columns (named as in the dtypes)."""
    n = offs.size
    rec: dict[str, np.ndarray] = {"flags": np.empty(n, np.uint32), "ts": np.empty(n, np.uint64),
           "ch": np.empty(n, np.uint16), "fl": np.empty(n, np.uint8),
           "dlc": np.empty(n, np.uint8), "id": np.empty(n, np.uint32),
           "data": np.empty((n, 8), np.uint8)}
    classic_fields(a, offs, 16 + HEADER_REST[v], rec["flags"], rec["ts"], rec["ch"],
                   rec["fl"], rec["dlc"], rec["id"], rec["data"])
    return rec


def _gather(buf: bytes | bytearray, offs: np.ndarray, dt: np.dtype) -> np.ndarray:
    """Records of dtype ``dt`` at byte offsets ``offs`` of ``buf`` (strided view when regular)."""
    w = dt.itemsize
    if offs.size > 1:
        stride = int(offs[1] - offs[0])
        if stride >= w and int(offs[-1] - offs[0]) == stride * (offs.size - 1) and (
            np.all(np.diff(offs) == stride)
        ):
            return np.ndarray((offs.size,), dt, buffer=buf, offset=int(offs[0]),
                              strides=(stride,))
    return byte_rows(buf, offs, w).view(dt).reshape(offs.size)


def read_records(buf: bytes | bytearray, offs: np.ndarray, obj_type: int,
                 header_version: int) -> Any:
    """The fields of the frame objects of one type at byte offsets ``offs`` of ``buf``.

    Classic CAN messages: contiguous columns read by a compiled loop
    (:func:`~rigtools.ingest.can.blf_kernels.classic_fields`); the CAN FD types: records of
    :data:`RECORD_DTYPES` (a strided view when the objects are evenly spaced). Either is
    indexed by field name. The objects must be at least the record's size.
    """
    if obj_type in CLASSIC_TYPES:
        return _classic(np.frombuffer(buf, np.uint8), offs, header_version)
    return _gather(buf, offs, RECORD_DTYPES[(obj_type, header_version)])
