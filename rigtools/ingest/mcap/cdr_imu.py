"""Reading many CDR ``sensor_msgs/msg/Imu`` messages of one layout at once.

Holds :class:`ImuColumns` and :func:`decode_imu_cdr_many`, the block reader that mirrors
:func:`~rigtools.ingest.mcap.ros2.decode_imu_cdr`: it reads the header stamp and the linear
acceleration of every payload at the offsets the ``frame_id`` length fixes, once it has checked
that every payload has the first one's length, encapsulation header and ``frame_id`` length word
(see :mod:`rigtools.ingest.mcap.cdr` for how a block is read).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from rigtools.errors import PayloadDecodeError
from rigtools.ingest.mcap.cdr_rows import Leaf, Rows, checked_block, float_field
from rigtools.ingest.mcap.ros2 import decode_imu_cdr

__all__ = ["ImuColumns", "decode_imu_cdr_many"]


class ImuColumns(NamedTuple):
    """Many ``sensor_msgs/msg/Imu`` messages read at once.

    Attributes
    ----------
    stamp_ns : numpy.ndarray
        int64 header stamps (ns): ``sec * 1e9 + nanosec`` with ``sec`` an int32.
    accel : numpy.ndarray
        float64, shape ``(m, 3)``: ``linear_acceleration.x|y|z`` (m/s^2).
    """

    stamp_ns: np.ndarray
    accel: np.ndarray


def decode_imu_cdr_many(buf: Any, starts: np.ndarray, ends: np.ndarray) -> ImuColumns | None:
    """Read header stamp and linear acceleration of many CDR ``sensor_msgs/msg/Imu`` at once.

    Parameters
    ----------
    buf : bytes-like
        A chunk's uncompressed data.
    starts, ends : numpy.ndarray
        Byte range of each payload in ``buf`` (int64, shape ``(m,)``).

    Returns
    -------
    ImuColumns or None
        None unless :func:`~rigtools.ingest.mcap.ros2.decode_imu_cdr` reads the first message
        and every message has its length, its 4 encapsulation header bytes and its
        ``frame_id`` length word; then the values are exactly those ``decode_imu_cdr`` gives
        message by message.

    Notes
    -----
    ``decode_imu_cdr`` reads ``int32 sec`` and ``uint32 nanosec`` at payload offsets 4 and 8,
    the ``frame_id`` length ``L`` at 12, and the three float64 of ``linear_acceleration`` at
    ``4 + ((12 + L + 7) & ~7) + 200``: only ``L`` moves them, and the header's kind byte
    says the byte order.
    """
    blk = checked_block(buf, starts, ends)
    if blk is None:
        return None
    mv, s, n = blk
    s0 = int(s[0])
    try:
        decode_imu_cdr(mv[s0 : s0 + n])
    except PayloadDecodeError:
        return None
    rows = Rows(mv, s, n)
    head = rows.span(0, 16)  # encapsulation header, sec, nanosec, frame_id length
    ref = rows.first
    if not bool((head[:, 0:4] == ref[0:4]).all()) or not bool((head[:, 12:16] == ref[12:16]).all()):
        return None
    e = "<" if ref[1] == 1 else ">"
    slen = int(ref[12:16].view(np.dtype(e + "u4"))[0])
    off = 4 + ((12 + slen + 7) & ~7) + 200
    stamp = np.ascontiguousarray(head[:, 4:12])
    sec = stamp[:, 0:4].copy().view(np.dtype(e + "i4"))[:, 0].astype(np.int64)
    nsec = stamp[:, 4:8].copy().view(np.dtype(e + "u4"))[:, 0].astype(np.int64)
    sec *= 1_000_000_000
    sec += nsec
    acc = float_field(rows, Leaf(off, "float64", 3, True), 0, 3, e)
    return ImuColumns(sec, acc)
