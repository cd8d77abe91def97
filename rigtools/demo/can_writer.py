"""Synthetic CAN recordings of the reference layout, and CAN log files written from them.

:func:`encode_reference_frames` packs accelerometer sample arrays and slow signals into the
frames a rig logger would record under ``data_schemas/rig_reference.dbc`` (or any DBC that
describes its uniform channels with the ``RigChannel``/``RigSampleRate``/``RigCounter``
attributes): int16 samples at the DBC scale, a 16-bit frame counter that wraps at 65536,
logger timestamps with a fixed latency and a small jitter, and slow frames at a low rate.

:func:`write_can_log` writes such a batch as BLF, ASC, TRC, candump ``.log`` or python-can
CSV through python-can's own writers; for large files (benchmarks) a vectorised BLF and
candump writer produces the same bytes as python-can's ``BLFWriter`` and
``CanutilsLogWriter`` (the tests compare them byte for byte).
"""

from __future__ import annotations

import datetime
import struct
import zlib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rigtools.ingest.can.dbc import load_dbc
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.layout import CanLayout, can_layout
from rigtools.schemas import schema_path

__all__ = [
    "FORMATS",
    "blf_bytes",
    "candump_text",
    "encode_reference_frames",
    "quantise_reference",
    "reference_layout",
    "write_can_log",
]

#: Formats :func:`write_can_log` writes, with the suffix it expects.
FORMATS: dict[str, str] = {"blf": ".blf", "asc": ".asc", "trc": ".trc", "log": ".log",
                           "csv": ".csv"}


def reference_layout(dbc: str | Path | None = None) -> CanLayout:
    """The channel layout of a DBC (default: the shipped reference DBC), as ``read`` uses it."""
    path = Path(dbc) if dbc is not None else schema_path("rig_reference.dbc")
    return can_layout(load_dbc(path), None, str(path))


def _raw_limits(signal: Any) -> tuple[int, int]:
    n = int(signal.length)
    if signal.is_signed:
        return -(1 << (n - 1)), (1 << (n - 1)) - 1
    return 0, (1 << n) - 1


def _to_raw(values: np.ndarray, signal: Any, what: str) -> np.ndarray:
    """Physical values to raw integers of a signal: round to the scale, clip to its range."""
    v = np.asarray(values, np.float64)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"`{what}` must be finite, has {int((~np.isfinite(v)).sum())} "
                         "non-finite value(s)")
    lo, hi = _raw_limits(signal)
    raw = np.rint((v - float(signal.offset)) / float(signal.scale))
    return np.clip(raw, lo, hi).astype(np.int64)


def _pack(words: np.ndarray, raw: np.ndarray, signal: Any) -> None:
    """OR the raw values of a little-endian signal into 64-bit payload words (in place)."""
    if signal.byte_order != "little_endian" or signal.is_float:
        raise ValueError(f"signal {signal.name!r}: only little-endian integer signals are "
                         "encoded")
    n = int(signal.length)
    mask = np.uint64((1 << n) - 1)
    words |= (raw.astype(np.uint64) & mask) << np.uint64(int(signal.start))


def quantise_reference(
    channels: Sequence[np.ndarray] | Mapping[str, np.ndarray] | np.ndarray,
    dbc: str | Path | None = None,
) -> dict[str, np.ndarray]:
    """What a reader must return for each channel: samples quantised to the DBC's int16.

    Parameters
    ----------
    channels : sequence or mapping of numpy.ndarray
        Samples (unit of the DBC signals, m/s^2 for the reference layout), as passed to
        :func:`encode_reference_frames`.
    dbc : str or pathlib.Path, optional
        DBC; default the reference layout.

    Returns
    -------
    dict of str to numpy.ndarray
        Channel name -> ``raw * scale + offset`` (float64), computed as
        :func:`rigtools.ingest.can.dbc.decode_signal` computes it.
    """
    layout = reference_layout(dbc)
    named = _name_channels(channels, layout)
    out = {}
    for u in layout.uniform:
        if u.spec.channel not in named:
            continue
        sig = u.samples[0]
        raw = _to_raw(named[u.spec.channel], sig, u.spec.channel)
        out[u.spec.channel] = raw.astype(np.float64) * float(sig.scale) + float(sig.offset)
    return out


def _name_channels(
    channels: Sequence[np.ndarray] | Mapping[str, np.ndarray] | np.ndarray, layout: CanLayout
) -> dict[str, np.ndarray]:
    names = [u.spec.channel for u in layout.uniform]
    if isinstance(channels, Mapping):
        unknown = sorted(set(channels) - set(names))
        if unknown:
            raise ValueError(f"`channels` names {unknown}, not channels of the layout {names}")
        return {k: np.asarray(v, np.float64).ravel() for k, v in channels.items()}
    arrs = list(channels) if not isinstance(channels, np.ndarray) or channels.ndim > 1 else [
        channels]
    if len(arrs) > len(names):
        raise ValueError(f"`channels` has {len(arrs)} arrays, the layout {len(names)} channels")
    return {names[i]: np.asarray(a, np.float64).ravel() for i, a in enumerate(arrs)}


def encode_reference_frames(
    channels: Sequence[np.ndarray] | Mapping[str, np.ndarray] | np.ndarray,
    slow: Mapping[str, float | np.ndarray] | None = None,
    *,
    start_time_s: float = 1_700_000_000.0,
    slow_rate_Hz: float = 10.0,
    latency_s: float = 250e-6,
    jitter_s: float = 20e-6,
    first_counter: int = 0,
    bus_channel: int = 0,
    dbc: str | Path | None = None,
    rng: np.random.Generator | int | None = 0,
) -> CanFrameBatch:
    """Frames of the reference layout carrying the given samples and slow signals.

    Parameters
    ----------
    channels : sequence of numpy.ndarray, 2-D array, or mapping of str to numpy.ndarray
        Accelerometer samples in the DBC signals' unit (m/s^2): the i-th array becomes the
        i-th uniform channel of the layout (``accel_1`` .. ``accel_4``), or give them by name.
        Each length must be a multiple of the samples per frame (3).
    slow : mapping of str to float or numpy.ndarray, optional
        Slow signals by DBC signal name (``PinionSpeed_rpm``, ``Torque_Nm``, ``OilTemp_C``...):
        a constant, or one value per slow frame (``ceil(duration_s * slow_rate_Hz)`` values).
        Signals of a slow message that are not given are sent as raw 0.
    start_time_s : float
        Logger time of sample index 0 (s since the epoch).
    slow_rate_Hz : float
        Rate of the slow frames (Hz).
    latency_s : float
        Fixed delay between a frame's last sample and its logger timestamp (s).
    jitter_s : float
        Logger timestamp jitter, uniform in ``[0, jitter_s)`` (s). Keep it below a frame period
        (3 / 25.6 kHz = 117 µs) so the frames of a channel keep their order.
    first_counter : int
        Frame counter of the first frame of every channel (wraps at ``2**bits``).
    bus_channel : int
        CAN channel number of every frame (python-can numbering, from 0).
    dbc : str or pathlib.Path, optional
        DBC; default the reference layout.
    rng : numpy.random.Generator or int or None
        Randomness of the jitter (SPEC 7).

    Returns
    -------
    CanFrameBatch
        Data frames sorted by timestamp (stable); ``position`` is the frame index.

    Raises
    ------
    ValueError
        Unknown channel or signal names, a length that is not a whole number of frames,
        non-finite values, or slow arrays of the wrong length.
    """
    if slow_rate_Hz <= 0:
        raise ValueError(f"`slow_rate_Hz` must be > 0, was {slow_rate_Hz}")
    if jitter_s < 0 or latency_s < 0:
        raise ValueError(f"`jitter_s` and `latency_s` must be >= 0, were {jitter_s}, {latency_s}")
    gen = np.random.default_rng(rng)
    layout = reference_layout(dbc)
    named = _name_channels(channels, layout)
    stamps: list[np.ndarray] = []
    ids: list[np.ndarray] = []
    exts: list[np.ndarray] = []
    words: list[np.ndarray] = []
    duration_s = 0.0
    for u in layout.uniform:
        x = named.get(u.spec.channel)
        if x is None:
            continue
        k = len(u.samples)
        if x.size % k:
            raise ValueError(f"`channels[{u.spec.channel!r}]` must hold a multiple of {k} "
                             f"samples (one frame each {k}), has {x.size}")
        n = x.size // k
        fs = float(u.spec.sample_rate_Hz)
        duration_s = max(duration_s, x.size / fs)
        w = np.zeros(n, np.uint64)
        raw = _to_raw(x, u.samples[0], u.spec.channel).reshape(n, k)
        for j, sig in enumerate(u.samples):
            _pack(w, raw[:, j], sig)
        if u.counter is not None:
            cnt = (int(first_counter) + np.arange(n, dtype=np.int64)) % (1 << int(u.counter.length))
            _pack(w, cnt, u.counter)
        last_sample = np.arange(n, dtype=np.float64) * k + (k - 1)
        t = start_time_s + last_sample / fs + latency_s + gen.uniform(0.0, jitter_s, n)
        stamps.append(t)
        ids.append(np.full(n, int(u.message.frame_id), np.uint32))
        exts.append(np.full(n, bool(u.message.is_extended_frame)))
        words.append(w)
    if slow:
        by_msg: dict[str, list[tuple[Any, Any]]] = {}
        known = {s.spec.name: s for s in layout.slow}
        for name, value in slow.items():
            if name not in known:
                raise ValueError(f"`slow` names {name!r}, not a slow signal of the layout "
                                 f"({sorted(known)})")
            by_msg.setdefault(known[name].message.name, []).append((known[name], value))
        n_slow = max(1, int(np.ceil(duration_s * slow_rate_Hz - 1e-9)))
        for entries in by_msg.values():
            msg = entries[0][0].message
            w = np.zeros(n_slow, np.uint64)
            for s, value in entries:
                v = np.broadcast_to(np.asarray(value, np.float64), (n_slow,)) if np.ndim(
                    value) == 0 else np.asarray(value, np.float64)
                if v.shape != (n_slow,):
                    raise ValueError(f"`slow[{s.spec.name!r}]` must be a scalar or hold "
                                     f"{n_slow} values (one per slow frame), has {v.size}")
                _pack(w, _to_raw(v, s.signal, s.spec.name), s.signal)
            t = (start_time_s + np.arange(n_slow) / slow_rate_Hz + latency_s
                 + gen.uniform(0.0, jitter_s, n_slow))
            stamps.append(t)
            ids.append(np.full(n_slow, int(msg.frame_id), np.uint32))
            exts.append(np.full(n_slow, bool(msg.is_extended_frame)))
            words.append(w)
    if not stamps:
        return CanFrameBatch.empty()
    t = np.concatenate(stamps)
    order = np.argsort(t, kind="stable")
    n = t.size
    data = np.concatenate(words)[order].astype("<u8").view(np.uint8).reshape(n, 8)
    return CanFrameBatch(
        t[order],
        np.concatenate(ids)[order],
        np.concatenate(exts)[order],
        np.zeros(n, bool),
        np.full(n, 8, np.uint8),
        np.ascontiguousarray(data),
        np.full(n, bus_channel, np.int16),
        np.arange(n, dtype=np.int64),
        "byte",
    )


# -- writing -----------------------------------------------------------------------------------


def _messages(batch: CanFrameBatch) -> list[Any]:
    import can

    out = []
    for i in range(len(batch)):
        n = int(batch.length[i])
        ch = int(batch.channel[i])
        out.append(can.Message(
            timestamp=float(batch.timestamp_s[i]),
            arbitration_id=int(batch.arbitration_id[i]),
            is_extended_id=bool(batch.is_extended[i]),
            is_fd=bool(batch.is_fd[i]),
            dlc=n,
            data=bytes(batch.data[i, :n]),
            channel=ch if ch >= 0 else None,
        ))
    return out


def write_can_log(
    path: str | Path,
    batch: CanFrameBatch,
    fmt: str | None = None,
    *,
    engine: Literal["python-can", "rigtools"] = "python-can",
    compression_level: int = -1,
) -> Path:
    """Write a batch of frames as a CAN log file.

    Parameters
    ----------
    path : str or pathlib.Path
        Output file.
    batch : CanFrameBatch
        Data frames.
    fmt : {"blf", "asc", "trc", "log", "csv"}, optional
        Format; default from the suffix of ``path``. ``"candump"`` is an alias of ``"log"``.
    engine : {"python-can", "rigtools"}
        ``"python-can"`` writes through ``can.BLFWriter``, ``ASCWriter``, ``TRCWriter``,
        ``CanutilsLogWriter`` or ``CSVWriter``; ``"rigtools"`` uses the vectorised BLF and
        candump writers of this module (same bytes, much faster; blf and log only).
    compression_level : int
        zlib level of BLF containers (-1 as python-can's default).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        Unknown format or engine.
    """
    p = Path(path)
    if fmt is None:
        fmt = p.suffix.lower().lstrip(".")
    fmt = "log" if fmt == "candump" else fmt
    if fmt not in FORMATS:
        raise ValueError(f"`fmt` must be one of {sorted(FORMATS)}, was {fmt!r}")
    if engine == "rigtools":
        if fmt == "blf":
            p.write_bytes(blf_bytes(batch, compression_level=compression_level))
            return p
        if fmt == "log":
            p.write_text(candump_text(batch), encoding="utf-8", newline="\n")
            return p
        raise ValueError(f"`engine='rigtools'` writes blf and log only, not {fmt!r}")
    if engine != "python-can":
        raise ValueError(f"`engine` must be 'python-can' or 'rigtools', was {engine!r}")
    import can

    writers = {"blf": can.BLFWriter, "asc": can.ASCWriter, "trc": can.TRCWriter,
               "log": can.CanutilsLogWriter, "csv": can.CSVWriter}
    kwargs: dict[str, Any] = {"compression_level": compression_level} if fmt == "blf" else {}
    with writers[fmt](str(p), **kwargs) as writer:
        for msg in _messages(batch):
            writer.on_message_received(msg)
    return p


_FILE_HEADER = struct.Struct("<4sLBBBBBBBBQQLL8H8H")
_OBJ_BASE = struct.Struct("<4sHHLL")
_CONTAINER = struct.Struct("<H6xL4x")
_HEADER_SIZE = 144
_CONTAINER_BYTES = 128 * 1024
_FD_DLC = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64])

_CLASSIC_DT = np.dtype({
    "names": ["sig", "hs", "hv", "size", "type", "flags", "ts", "ch", "fl", "dlc", "id", "data"],
    "formats": ["S4", "<u2", "<u2", "<u4", "<u4", "<u4", "<u8", "<u2", "u1", "u1", "<u4",
                ("u1", 8)],
    "offsets": [0, 4, 6, 8, 12, 16, 24, 32, 34, 35, 36, 40], "itemsize": 48})
_FD_DT = np.dtype({
    "names": ["sig", "hs", "hv", "size", "type", "flags", "ts", "ch", "fl", "dlc", "id",
              "fdfl", "valid", "data"],
    "formats": ["S4", "<u2", "<u2", "<u4", "<u4", "<u4", "<u8", "<u2", "u1", "u1", "<u4",
                "u1", "u1", ("u1", 64)],
    "offsets": [0, 4, 6, 8, 12, 16, 24, 32, 34, 35, 36, 45, 46, 52], "itemsize": 116})


def _systemtime(timestamp: float | None) -> tuple[int, ...]:
    # As python-can's can.io.blf.timestamp_to_systemtime.
    if timestamp is None or timestamp < 631152000:
        return (0,) * 8
    t = datetime.datetime.fromtimestamp(round(timestamp, 3), tz=datetime.UTC)
    return (t.year, t.month, t.isoweekday() % 7, t.day, t.hour, t.minute, t.second,
            t.microsecond // 1000)


def blf_bytes(batch: CanFrameBatch, *, compression_level: int = -1) -> bytes:
    """A whole BLF file for ``batch``, byte for byte as python-can's ``BLFWriter`` writes it.

    Classic frames become ``CAN_MESSAGE`` objects, FD frames ``CAN_FD_MESSAGE`` objects with
    1 ns timestamps relative to the first frame's time truncated to the millisecond; the object
    stream is cut into 128 KiB containers and deflated at ``compression_level``.
    """
    n = len(batch)
    ts = batch.timestamp_s
    start = int(float(ts[0]) * 1000) / 1000 if n else None
    stop = float(ts[-1]) if n else None
    rel = np.maximum(((ts - start) * 1e9).astype(np.int64), 0) if n else np.zeros(0, np.int64)
    ch = np.where(batch.channel >= 0, batch.channel.astype(np.int64) + 1, 1)
    arb = batch.arbitration_id.astype(np.uint32) | np.where(
        batch.is_extended, np.uint32(0x80000000), np.uint32(0))
    fd = batch.is_fd
    sizes = np.where(fd, _FD_DT.itemsize, _CLASSIC_DT.itemsize)
    ends = np.cumsum(sizes)
    stream = np.zeros(int(ends[-1]) if n else 0, np.uint8)
    width = batch.data.shape[1]
    for dt, sel, otype in ((_CLASSIC_DT, ~fd, 1), (_FD_DT, fd, 100)):
        m = int(sel.sum())
        if not m:
            continue
        rec = np.zeros(m, dt)
        rec["sig"] = b"LOBJ"
        rec["hs"] = 32
        rec["hv"] = 1
        rec["size"] = dt.itemsize
        rec["type"] = otype
        rec["flags"] = 2
        rec["ts"] = rel[sel]
        rec["ch"] = ch[sel]
        rec["id"] = arb[sel]
        length = batch.length[sel]
        w = 8 if otype == 1 else 64
        payload = np.zeros((m, w), np.uint8)
        payload[:, : min(w, width)] = batch.data[sel][:, :w]
        payload[np.arange(w) >= length[:, None]] = 0
        rec["data"] = payload
        if otype == 1:
            rec["dlc"] = length
        else:
            rec["dlc"] = np.searchsorted(_FD_DLC, length)
            rec["fdfl"] = 1
            rec["valid"] = length
        raw = rec.view(np.uint8).reshape(m, dt.itemsize)
        if m == n:
            stream = raw.reshape(-1)
        else:
            starts = (ends - sizes)[sel]
            stream[starts[:, None] + np.arange(dt.itemsize)] = raw
    body = stream.tobytes()
    parts = [b""]
    uncompressed = _HEADER_SIZE
    for i in range(0, len(body), _CONTAINER_BYTES):
        chunk = body[i : i + _CONTAINER_BYTES]
        if compression_level:
            data, method = zlib.compress(chunk, compression_level), 2
        else:
            data, method = chunk, 0
        size = 32 + len(data)
        parts += [_OBJ_BASE.pack(b"LOBJ", 16, 1, size, 10), _CONTAINER.pack(method, len(chunk)),
                  data, b"\x00" * (size % 4)]
        uncompressed += 32 + len(chunk)
    file_size = _HEADER_SIZE + sum(len(x) for x in parts)
    header = _FILE_HEADER.pack(b"LOGG", _HEADER_SIZE, 5, 0, 0, 0, 2, 6, 8, 1, file_size,
                               uncompressed, n, 0, *_systemtime(start), *_systemtime(stop))
    parts[0] = header + b"\x00" * (_HEADER_SIZE - len(header))
    return b"".join(parts)


_HEX = np.frombuffer(b"0123456789ABCDEF", np.uint8)


def _hex_columns(values: np.ndarray, digits: int) -> np.ndarray:
    """Upper-case hex digits of integers, shape ``(n, digits)`` of ASCII codes."""
    shifts = np.arange(digits - 1, -1, -1, dtype=np.uint64) * np.uint64(4)
    nib = (values.astype(np.uint64)[:, None] >> shifts) & np.uint64(15)
    return _HEX[nib.astype(np.intp)]


def candump_text(batch: CanFrameBatch) -> str:
    """Text of a ``candump -L`` log for ``batch``, as python-can's ``CanutilsLogWriter`` writes it.

    ``(%f) canN ID#DATA R`` per frame (``vcan0`` where the channel is -1), ``#F`` after the
    ``#`` of FD frames; timestamps below the first are written as the first, as python-can
    does.
    """
    n = len(batch)
    if n == 0:
        return ""
    ts = batch.timestamp_s
    first = float(ts[0]) or 0.0
    ts = np.where(ts < first, first, ts)
    stamps = [f"({t:f}) " for t in ts.tolist()]
    chan_names = {c: (f"can{c}" if c >= 0 else "vcan0") for c in np.unique(batch.channel).tolist()}
    lines = np.empty(n, object)
    # Fixed-width tail per (extended, fd, length) group, built with NumPy.
    key = (batch.is_extended.astype(np.int64) << 8) | (batch.is_fd.astype(np.int64) << 7) | (
        batch.length.astype(np.int64))
    for k in np.unique(key).tolist():
        rows = np.flatnonzero(key == k)
        ext, fd, length = bool(k >> 8), bool((k >> 7) & 1), k & 0x7F
        digits = 8 if ext else 3
        cols = [_hex_columns(batch.arbitration_id[rows], digits),
                np.full((rows.size, 1), ord("#"), np.uint8)]
        if fd:
            cols.append(np.frombuffer(b"#0", np.uint8)[None, :].repeat(rows.size, 0))
        if length:
            d = batch.data[rows, :length]
            hexd = np.empty((rows.size, 2 * length), np.uint8)
            hexd[:, 0::2] = _HEX[d >> 4]
            hexd[:, 1::2] = _HEX[d & 15]
            cols.append(hexd)
        cols.append(np.frombuffer(b" R\n", np.uint8)[None, :].repeat(rows.size, 0))
        mat = np.ascontiguousarray(np.concatenate(cols, axis=1))
        texts = mat.view(f"S{mat.shape[1]}").ravel()
        lines[rows] = [b.decode("ascii") for b in texts.tolist()]
    channels = [chan_names[c] for c in batch.channel.tolist()]
    return "".join(f"{s}{c} {t}" for s, c, t in zip(stamps, channels, lines.tolist(),
                                                     strict=True))
