"""DBC loading (cantools) and vectorised signal decoding over whole frame columns.

cantools parses the DBC and is the reference decoder; decoding itself runs here as NumPy
over all frames of one message at once, bit-exact with ``cantools``'s ``decode_message``
(the tests compare the two on every signal layout: both byte orders, any start bit and
length up to 64, signed, IEEE float, multiplexed).
"""

from __future__ import annotations

import functools
import hashlib
import re
from pathlib import Path
from typing import Any

import cantools
import numpy as np

from rigtools.errors import DbcError

__all__ = [
    "dbc_digest",
    "decode_signal",
    "load_dbc",
    "multiplex_mask",
    "raw_signal",
    "signal_raw",
]


def load_dbc(path: str | Path, *, strict: bool = True) -> Any:
    """Load a DBC file with cantools.

    Parameters
    ----------
    path : str or pathlib.Path
        DBC file.
    strict : bool
        Refuse overlapping signals and signals that do not fit their message (cantools'
        ``strict``); a DBC that only loads with ``strict=False`` is refused unless asked.

    Returns
    -------
    cantools.database.can.Database

    Raises
    ------
    DbcError
        The file is missing or does not parse; the message names the file and, where cantools
        reports it, the line and column.
    """
    p = Path(path)
    if not p.is_file():
        raise DbcError(p, None, "a DBC file", "a directory" if p.is_dir() else "no such file")
    st = p.stat()
    return _load_dbc(str(p.resolve()), st.st_mtime_ns, st.st_size, bool(strict))


@functools.lru_cache(maxsize=8)
def _load_dbc(path: str, mtime_ns: int, size: int, strict: bool) -> Any:
    """The DBC parsed once per file version (a campaign reads hundreds of logs with one DBC).

    ``mtime_ns`` and ``size`` are part of the key so that an edited file is parsed again.
    The database is only read, never changed, by rigtools.
    """
    p = Path(path)
    try:
        return cantools.database.load_file(str(p), database_format="dbc", strict=strict)
    except Exception as exc:  # cantools raises ParseError, ValueError, KeyError, ...
        text = str(exc).strip() or type(exc).__name__
        m = re.search(r"line (\d+), column (\d+)", text)
        pos = f"line {m.group(1)} column {m.group(2)}" if m else None
        raise DbcError(p, pos, "a valid DBC file", None, f"cantools: {text[:300]}") from exc


def dbc_digest(path: str | Path) -> str:
    """SHA-256 of a DBC file (recorded in provenance)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def raw_signal(data: np.ndarray, start: int, length: int, byte_order: str) -> np.ndarray:
    """Raw unsigned bits of a signal for every row of ``data``.

    Parameters
    ----------
    data : numpy.ndarray
        Payload bytes, uint8, shape ``(n, width)``.
    start : int
        DBC start bit (LSB for little endian; MSB in DBC sawtooth numbering for big endian).
    length : int
        Signal length (bits), 1..64.
    byte_order : {"little_endian", "big_endian"}

    Returns
    -------
    numpy.ndarray
        uint64, shape ``(n,)``.
    """
    n = data.shape[0]
    mask = np.uint64((1 << length) - 1)
    if byte_order == "little_endian":
        first, last = start // 8, (start + length - 1) // 8
        shift = start - 8 * first
        acc = np.zeros(n, np.uint64)
        for i, b in enumerate(range(first, min(last, first + 7) + 1)):
            acc |= data[:, b].astype(np.uint64) << np.uint64(8 * i)
        out = acc >> np.uint64(shift)
        if last - first == 8:  # ninth byte: only when an unaligned signal is 57..64 bits long
            out |= data[:, last].astype(np.uint64) << np.uint64(64 - shift)
        return out & mask
    msb = (start // 8) * 8 + (7 - start % 8)
    lsb = msb + length - 1
    first, last = msb // 8, lsb // 8
    acc = np.zeros(n, np.uint64)
    nb = min(last - first + 1, 8)
    for i in range(nb):
        acc |= data[:, first + i].astype(np.uint64) << np.uint64(8 * (nb - 1 - i))
    if last - first == 8:
        shift = 7 - lsb % 8
        out = (acc << np.uint64(8 - shift)) | (data[:, last].astype(np.uint64) >> np.uint64(shift))
        return out & mask
    shift = (first + nb) * 8 - 1 - lsb
    return (acc >> np.uint64(shift)) & mask


def _aligned_field(data: np.ndarray, start: int, length: int, byte_order: str,
                   signed: bool, is_float: bool) -> np.ndarray | None:
    """An integer signal filling whole bytes, read as its bytes are, or None.

    8, 16, 32 or 64 bits on a byte boundary (either byte order): one copy of the bytes
    viewed as the integer, in the dtype :func:`signal_raw` gives. None for any other
    signal (and for float signals, whose bits go the general way).
    """
    if length not in (8, 16, 32, 64) or data.ndim != 2 or is_float:
        return None
    if byte_order == "little_endian":
        if start % 8:
            return None
        first, order = start // 8, "<"
    else:
        if start % 8 != 7:
            return None
        first, order = start // 8, ">"
    nb = length // 8
    if first + nb > data.shape[1]:
        return None
    kind = "i" if signed else "u"
    if data.flags.c_contiguous and first % nb == 0 and data.shape[1] % nb == 0:
        # the rows viewed as integers in place: a typed strided copy, not a byte-wise one
        return data.view(f"{order}{kind}{nb}")[:, first // nb].astype(f"={kind}{nb}")
    field = np.ascontiguousarray(data[:, first : first + nb]).view(f"{order}{kind}{nb}")[:, 0]
    return field.astype(f"={kind}{nb}")


def signal_raw(data: np.ndarray, signal: Any) -> tuple[np.ndarray, tuple[float, float]]:
    """Raw values of a signal in the smallest exact dtype, and its ``(scale, offset)``.

    Integer signals come back as the smallest signed or unsigned NumPy integer type that holds
    ``length`` bits (an int16 accelerometer sample costs 2 bytes); float signals as float32 or
    float64. ``decode_signal`` is ``raw.astype(float64) * scale + offset``.
    """
    length = int(signal.length)
    conv = (float(signal.scale), float(signal.offset))
    aligned = _aligned_field(data, int(signal.start), length, signal.byte_order,
                             bool(signal.is_signed), bool(signal.is_float))
    if aligned is not None:
        return aligned, conv
    raw = raw_signal(data, int(signal.start), length, signal.byte_order)
    if signal.is_float:
        if length == 32:
            return raw.astype(np.uint32).view(np.float32), conv
        if length == 64:
            return raw.view(np.float64), conv
        raise DbcError(None, f"signal {signal.name!r}", "a 32- or 64-bit float signal",
                       f"{length} bits")
    if signal.is_signed:
        if length == 64:
            return raw.view(np.int64), conv
        sraw = raw.astype(np.int64)
        neg = (raw >> np.uint64(length - 1)) & np.uint64(1)
        sraw -= neg.astype(np.int64) << np.int64(length)
        sdtype = next(t for t in (np.int8, np.int16, np.int32, np.int64)
                      if np.iinfo(t).bits >= length)
        return sraw.astype(sdtype), conv
    udtype = next(t for t in (np.uint8, np.uint16, np.uint32, np.uint64)
                  if np.iinfo(t).bits >= length)
    return raw.astype(udtype), conv


def decode_signal(data: np.ndarray, signal: Any) -> np.ndarray:
    """Physical values (float64) of a cantools signal for every row of ``data``.

    ``raw * scale + offset``, with two's complement for signed signals and IEEE 754 for float
    signals, as cantools' ``decode_message(..., decode_choices=False)`` computes them.
    """
    raw, (scale, offset) = signal_raw(data, signal)
    with np.errstate(invalid="ignore"):  # a signalling NaN in a float32 signal stays NaN
        val = raw.astype(np.float64)
    if scale == 1 and offset == 0:
        return val
    return val * scale + offset


def multiplex_mask(data: np.ndarray, message: Any, signal: Any) -> np.ndarray | None:
    """Rows where a multiplexed signal is present, or None for a plain signal.

    Handles cascaded multiplexers by walking up the chain of multiplexer signals.
    """
    mask: np.ndarray | None = None
    sig = signal
    while sig.multiplexer_ids:
        mux = message.get_signal_by_name(sig.multiplexer_signal)
        raw = raw_signal(data, int(mux.start), int(mux.length), mux.byte_order)
        here = np.isin(raw, np.asarray(sig.multiplexer_ids, np.uint64))
        mask = here if mask is None else (mask & here)
        sig = mux
    return mask
