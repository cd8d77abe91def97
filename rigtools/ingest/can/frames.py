"""Columnar batches of CAN frames: what every CAN log reader yields.

A reader turns its container (BLF objects, ASC/TRC/candump/CSV lines) into
:class:`CanFrameBatch` blocks of a few thousand to a few hundred thousand frames, so that
everything downstream (DBC decoding, counter unwrapping) runs as NumPy over whole columns.
Error frames and remote frames carry no data: readers count them in the
:class:`~rigtools.ingest.recording.IngestReport` and leave them out of the batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["CanFrameBatch", "byte_rows", "concat", "from_messages", "take_rows"]


def take_rows(a: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``a[rows]`` for a 2-D array (index array or boolean mask), each row moved as one item.

    NumPy gathers the rows of a small 2-D ``uint8`` array byte column by byte column; viewed
    as one ``void`` item per row the same gather is 5-8x faster (8 to 64-byte payload rows,
    256 k rows: 2.2 against 0.29 ms at 8 bytes). The values are the same bytes.
    """
    if a.ndim != 2 or not a.flags.c_contiguous or a.shape[1] == 0:
        return a[rows]
    width = a.shape[1]
    items = a.view(f"V{a.itemsize * width}")[:, 0]
    return items[rows].view(a.dtype).reshape(-1, width)


def byte_rows(buf: Any, offsets: np.ndarray, width: int) -> np.ndarray:
    """The ``width`` bytes of ``buf`` at each of ``offsets``, as a ``(n, width)`` uint8 array.

    A view with an item of ``width`` bytes at every byte of ``buf`` (stride 1, overlapping
    items) indexed by ``offsets``: each row moved whole, 5-8x faster than gathering the rows
    of a sliding-window view byte column by byte column. ``buf`` is any buffer (bytes, a
    memoryview, a uint8 array); ``offsets`` must lie in ``[0, len(buf) - width]``.
    """
    size = memoryview(buf).nbytes
    if width == 0:
        return np.zeros((offsets.size, 0), np.uint8)
    if size < width:
        if offsets.size:
            raise IndexError(f"rows of {width} bytes asked of a buffer of {size}")
        return np.zeros((0, width), np.uint8)
    items = np.ndarray((size - width + 1,), f"V{width}", buffer=buf, offset=0, strides=(1,))
    return items[offsets].view(np.uint8).reshape(-1, width)


@dataclass(frozen=True, eq=False)
class CanFrameBatch:
    """A block of CAN data frames, one row per frame.

    Attributes
    ----------
    timestamp_s : numpy.ndarray
        Logger timestamp (s), float64.
    arbitration_id : numpy.ndarray
        Frame identifier, uint32 (11- or 29-bit).
    is_extended : numpy.ndarray
        bool, 29-bit identifier.
    is_fd : numpy.ndarray
        bool, CAN FD frame.
    length : numpy.ndarray
        Payload length in bytes (0..64), uint8 (for classic CAN with DLC > 8, 8).
    data : numpy.ndarray
        Payload bytes, uint8, shape ``(n, width)`` with ``width >= length.max()``; bytes past
        ``length`` are zero.
    channel : numpy.ndarray
        Bus channel number, int16 (-1 where the log has none).
    position : numpy.ndarray
        Where each frame sits in the source (byte offset or 1-based line number), int64.
    position_unit : str
        ``"byte"`` or ``"line"``.
    """

    timestamp_s: np.ndarray
    arbitration_id: np.ndarray
    is_extended: np.ndarray
    is_fd: np.ndarray
    length: np.ndarray
    data: np.ndarray
    channel: np.ndarray
    position: np.ndarray
    position_unit: str = "byte"

    def __len__(self) -> int:
        return int(self.timestamp_s.shape[0])

    def where(self, position: int) -> str:
        """Human-readable position of frame ``position`` in the source."""
        return f"{self.position_unit} {int(self.position[position])}"

    def take(self, mask_or_index: np.ndarray) -> CanFrameBatch:
        """Rows selected by a boolean mask or an index array."""
        return CanFrameBatch(
            self.timestamp_s[mask_or_index],
            self.arbitration_id[mask_or_index],
            self.is_extended[mask_or_index],
            self.is_fd[mask_or_index],
            self.length[mask_or_index],
            take_rows(self.data, mask_or_index),
            self.channel[mask_or_index],
            self.position[mask_or_index],
            self.position_unit,
        )

    @staticmethod
    def empty(width: int = 8, position_unit: str = "byte") -> CanFrameBatch:
        """A batch with no frames."""
        return CanFrameBatch(
            np.zeros(0, np.float64),
            np.zeros(0, np.uint32),
            np.zeros(0, bool),
            np.zeros(0, bool),
            np.zeros(0, np.uint8),
            np.zeros((0, width), np.uint8),
            np.zeros(0, np.int16),
            np.zeros(0, np.int64),
            position_unit,
        )

    def equals(self, other: CanFrameBatch, *, compare_position: bool = False) -> bool:
        """Same frames: timestamps, ids, flags, lengths and payload bytes up to each length."""
        if len(self) != len(other):
            return False
        w = max(self.data.shape[1], other.data.shape[1])
        a = np.zeros((len(self), w), np.uint8)
        a[:, : self.data.shape[1]] = self.data
        b = np.zeros((len(other), w), np.uint8)
        b[:, : other.data.shape[1]] = other.data
        same = (
            np.array_equal(self.timestamp_s, other.timestamp_s)
            and np.array_equal(self.arbitration_id, other.arbitration_id)
            and np.array_equal(self.is_extended, other.is_extended)
            and np.array_equal(self.is_fd, other.is_fd)
            and np.array_equal(self.length, other.length)
            and np.array_equal(a, b)
        )
        if compare_position:
            same = same and np.array_equal(self.position, other.position)
        return bool(same)


def concat(batches: Sequence[CanFrameBatch]) -> CanFrameBatch:
    """Concatenate batches (widths padded to the widest)."""
    if not batches:
        return CanFrameBatch.empty()
    w = max(b.data.shape[1] for b in batches)
    data = np.zeros((sum(len(b) for b in batches), w), np.uint8)
    row = 0
    for b in batches:
        data[row : row + len(b), : b.data.shape[1]] = b.data
        row += len(b)
    return CanFrameBatch(
        np.concatenate([b.timestamp_s for b in batches]),
        np.concatenate([b.arbitration_id for b in batches]),
        np.concatenate([b.is_extended for b in batches]),
        np.concatenate([b.is_fd for b in batches]),
        np.concatenate([b.length for b in batches]),
        data,
        np.concatenate([b.channel for b in batches]),
        np.concatenate([b.position for b in batches]),
        batches[0].position_unit,
    )


def from_messages(
    messages: Sequence[object], positions: Sequence[int], position_unit: str = "line"
) -> CanFrameBatch:
    """Build a batch from python-can ``Message`` objects (data frames only).

    Used by the readers that delegate parsing to python-can (ASC, TRC, CSV) and by tests.
    """
    n = len(messages)
    width = max([8] + [len(m.data) for m in messages])  # type: ignore[attr-defined]
    data = np.zeros((n, width), np.uint8)
    length = np.zeros(n, np.uint8)
    for i, m in enumerate(messages):
        payload = bytes(m.data)  # type: ignore[attr-defined]
        data[i, : len(payload)] = np.frombuffer(payload, np.uint8)
        length[i] = len(payload)
    return CanFrameBatch(
        np.fromiter((m.timestamp for m in messages), np.float64, n),  # type: ignore[attr-defined]
        np.fromiter((m.arbitration_id for m in messages), np.uint32, n),  # type: ignore[attr-defined]
        np.fromiter((m.is_extended_id for m in messages), bool, n),  # type: ignore[attr-defined]
        np.fromiter((m.is_fd for m in messages), bool, n),  # type: ignore[attr-defined]
        length,
        data,
        np.fromiter((_bus(m.channel) for m in messages), np.int16, n),  # type: ignore[attr-defined]
        np.asarray(positions, np.int64),
        position_unit,
    )


def _bus(channel: object) -> int:
    """python-can's ``Message.channel`` as a bus number: an int16, else -1 (unknown)."""
    return channel if isinstance(channel, int) and -1 <= channel <= 32767 else -1
