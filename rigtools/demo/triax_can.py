"""A second CAN layout for the demo: one frame per sample time carrying a counter and three axes.

The reference layout (``data_schemas/rig_reference.dbc``) sends one accelerometer per message,
three consecutive little-endian samples per frame, and describes itself with the
``RigChannel``/``RigSampleRate``/``RigCounter`` attributes. Many loggers do it the other way
round; this layout is such a logger, so that the demo campaign exercises a user DBC with a
mapping file (``data_schemas/channel_mapping.schema.json``):

========  ========================  ==========================================================
frame     identifier                payload (8 bytes, Motorola / big-endian signals)
========  ========================  ==========================================================
TRIAX     0x0CFF1021 (29-bit)       ``SeqCnt`` uint16 (counts frames, wraps at 65536), ``AccX``,
                                    ``AccY``, ``AccZ`` int16 at 0.01 m/s^2 per bit: one sample
                                    of each axis, 25.6 kHz
RIG_STATE 0x300                     ``SpeedPinion`` uint16 0.1 rpm, ``TorqueShaft`` int16
                                    0.02 N m; 10 Hz
RIG_TEMPS 0x301                     ``TempBulk``, ``TempOil`` int16 0.01 degC; 10 Hz
========  ========================  ==========================================================

The DBC carries no rigtools attributes: the mapping (:data:`MAPPING_TEXT`) names the channels
``accel_x``, ``accel_y``, ``accel_z`` and the slow signals ``PinionSpeed_rpm``, ``Torque_Nm``,
``BulkTemp_C``, ``OilTemp_C``, as the demo's MCAP runs name them.

:func:`encode_triax_frames` packs samples into frames following the DBC (every signal is
byte-aligned big-endian, so packing is a byte-order view), optionally dropping frames (gaps in
the sample counter).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np

from rigtools.ingest.can.dbc import load_dbc
from rigtools.ingest.can.frames import CanFrameBatch

__all__ = [
    "ACCEL_CHANNELS",
    "ACCEL_LSB_M_S2",
    "DBC_TEXT",
    "MAPPING_TEXT",
    "SLOW_SIGNALS",
    "encode_triax_frames",
    "write_triax_layout",
]

#: Channel names of the three axes (mapping file and MCAP runs alike).
ACCEL_CHANNELS: Final[tuple[str, ...]] = ("accel_x", "accel_y", "accel_z")
#: Acceleration step of the layout's int16 samples (m/s^2 per bit).
ACCEL_LSB_M_S2: Final[float] = 0.01
#: Slow signal name (as the mapping names it) -> (message, DBC signal, unit).
SLOW_SIGNALS: Final[dict[str, tuple[str, str, str]]] = {
    "PinionSpeed_rpm": ("RIG_STATE", "SpeedPinion", "rpm"),
    "Torque_Nm": ("RIG_STATE", "TorqueShaft", "N.m"),
    "BulkTemp_C": ("RIG_TEMPS", "TempBulk", "degC"),
    "OilTemp_C": ("RIG_TEMPS", "TempOil", "degC"),
}
_TRIAX_ID: Final[int] = 0x0CFF1021
_SAMPLE_RATE_HZ: Final[float] = 25_600.0

#: The layout's DBC (extended identifiers carry bit 31 in a DBC file).
DBC_TEXT: Final[str] = f'''VERSION "rigtools demo triaxial logger 1.0"


NS_ :

BS_:

BU_: TriaxSensor RigPLC Logger

BO_ {_TRIAX_ID | 0x80000000} TRIAX: 8 TriaxSensor
 SG_ SeqCnt : 7|16@0+ (1,0) [0|65535] "" Logger
 SG_ AccX : 23|16@0- ({ACCEL_LSB_M_S2:g},0) [-327.68|327.67] "m/s^2" Logger
 SG_ AccY : 39|16@0- ({ACCEL_LSB_M_S2:g},0) [-327.68|327.67] "m/s^2" Logger
 SG_ AccZ : 55|16@0- ({ACCEL_LSB_M_S2:g},0) [-327.68|327.67] "m/s^2" Logger

BO_ 768 RIG_STATE: 8 RigPLC
 SG_ SpeedPinion : 7|16@0+ (0.1,0) [0|6553.5] "rpm" Logger
 SG_ TorqueShaft : 23|16@0- (0.02,0) [-655.36|655.34] "N.m" Logger

BO_ 769 RIG_TEMPS: 8 RigPLC
 SG_ TempBulk : 7|16@0- (0.01,0) [-327.68|327.67] "degC" Logger
 SG_ TempOil : 23|16@0- (0.01,0) [-327.68|327.67] "degC" Logger


CM_ "Demo logger of rigtools: triaxial accelerometer, one frame per sample time.";
CM_ BO_ {_TRIAX_ID | 0x80000000} "Pinion bearing cover, x y z per frame, 25.6 kHz.";
CM_ SG_ 768 TorqueShaft "Test-gear torque at the pinion shaft.";
CM_ SG_ 769 TempBulk "Gear body (bulk) temperature.";
CM_ SG_ 769 TempOil "Oil sump temperature (the housing follows it).";
'''


def _mapping_text() -> str:
    lines = ["# rigtools channel mapping (data_schemas/channel_mapping.schema.json) for triax.dbc:",
             "# one TRIAX frame per sample time carries the three axes and the frame counter.",
             ""]
    for name, sig in zip(ACCEL_CHANNELS, ("AccX", "AccY", "AccZ"), strict=True):
        lines += ["[[uniform]]", f'channel = "{name}"', 'message = "TRIAX"',
                  f'samples = ["{sig}"]', 'counter = "SeqCnt"',
                  f"sample_rate_Hz = {_SAMPLE_RATE_HZ:.1f}", 'unit = "m/s^2"', ""]
    for name, (msg, sig, unit) in SLOW_SIGNALS.items():
        lines += ["[[slow]]", f'name = "{name}"', f'message = "{msg}"', f'signal = "{sig}"',
                  f'unit = "{unit}"', ""]
    return "\n".join(lines)


#: The mapping file of the layout (TOML).
MAPPING_TEXT: Final[str] = _mapping_text()


def write_triax_layout(directory: str | Path, *, dbc_name: str = "triax.dbc",
                       mapping_name: str = "triax-map.toml") -> tuple[Path, Path]:
    """Write the layout's DBC and mapping file into ``directory``.

    Returns
    -------
    pathlib.Path
        The DBC.
    pathlib.Path
        The mapping (TOML).
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    dbc = d / dbc_name
    dbc.write_text(DBC_TEXT, encoding="utf-8")
    mapping = d / mapping_name
    mapping.write_text(MAPPING_TEXT, encoding="utf-8")
    return dbc, mapping


def _raw(values: np.ndarray, signal: Any, what: str) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError(f"`{what}` must be finite")
    raw = np.rint((v - float(signal.offset)) / float(signal.scale))
    n = int(signal.length)
    lo, hi = (-(1 << (n - 1)), (1 << (n - 1)) - 1) if signal.is_signed else (0, (1 << n) - 1)
    return np.clip(raw, lo, hi).astype(np.int64)


def _put(data: np.ndarray, raw: np.ndarray, signal: Any) -> None:
    """Write a byte-aligned big-endian 16-bit signal into the payload columns (in place)."""
    if (signal.byte_order != "big_endian" or int(signal.length) != 16
            or int(signal.start) % 8 != 7):
        raise ValueError(f"signal {signal.name!r}: only byte-aligned big-endian 16-bit "
                         "signals are packed")
    byte = int(signal.start) // 8
    data[:, byte : byte + 2] = (raw & 0xFFFF).astype(">u2").view(np.uint8).reshape(-1, 2)


def encode_triax_frames(
    accel_m_s2: np.ndarray,
    slow: Mapping[str, np.ndarray] | None = None,
    *,
    dbc: str | Path,
    start_time_s: float,
    slow_rate_Hz: float = 10.0,
    drop_frames: Sequence[int] | np.ndarray = (),
    latency_s: float = 150e-6,
    jitter_s: float = 10e-6,
    rng: np.random.Generator | int | None = 0,
) -> CanFrameBatch:
    """Frames of the triaxial layout carrying the samples and the slow signals.

    Parameters
    ----------
    accel_m_s2 : numpy.ndarray
        Samples of x, y, z (m/s^2), shape ``(n, 3)``; rounded to the DBC step and clipped to
        int16.
    slow : mapping of str to numpy.ndarray, optional
        Slow signals by mapping name (:data:`SLOW_SIGNALS`), one value per slow frame
        (``ceil(n / 25600 * slow_rate_Hz)`` values) or a scalar.
    dbc : str or pathlib.Path
        The layout's DBC (written by :func:`write_triax_layout`).
    start_time_s : float
        Logger time of sample 0 (s since the epoch).
    slow_rate_Hz : float
        Rate of the slow frames (Hz).
    drop_frames : sequence of int
        Sample indices whose TRIAX frames are lost (gaps in the counter).
    latency_s, jitter_s : float
        Logger stamp = sample time + latency + uniform jitter in ``[0, jitter_s)`` (s); keep
        the jitter below a frame period (39 us).
    rng : numpy.random.Generator, int or None
        Randomness of the jitter (SPEC 7).

    Returns
    -------
    CanFrameBatch
        Frames sorted by timestamp; ``position`` is the frame index.
    """
    acc = np.asarray(accel_m_s2, dtype=float)
    if acc.ndim != 2 or acc.shape[1] != 3:
        raise ValueError(f"`accel_m_s2` must have shape (n, 3), was {acc.shape}")
    if not (math.isfinite(slow_rate_Hz) and slow_rate_Hz > 0):
        raise ValueError(f"`slow_rate_Hz` must be > 0, was {slow_rate_Hz!r}")
    gen = np.random.default_rng(rng)
    db = load_dbc(dbc)
    triax = db.get_message_by_name("TRIAX")
    n = acc.shape[0]
    keep = np.ones(n, bool)
    drop = np.asarray(drop_frames, dtype=np.int64)
    if drop.size and (drop.min() < 0 or drop.max() >= n):
        raise ValueError(f"`drop_frames` must lie in [0, {n}), were {drop.min()}..{drop.max()}")
    keep[drop] = False
    idx = np.flatnonzero(keep)
    data = np.zeros((idx.size, 8), np.uint8)
    _put(data, idx % 65536, triax.get_signal_by_name("SeqCnt"))
    for k, sig in enumerate(("AccX", "AccY", "AccZ")):
        s = triax.get_signal_by_name(sig)
        _put(data, _raw(acc[idx, k], s, f"accel_m_s2[:, {k}]"), s)
    stamps = [start_time_s + idx / _SAMPLE_RATE_HZ + latency_s
              + gen.uniform(0.0, jitter_s, idx.size)]
    ids = [np.full(idx.size, _TRIAX_ID, np.uint32)]
    ext = [np.ones(idx.size, bool)]
    payloads = [data]
    n_slow = max(1, math.ceil(n / _SAMPLE_RATE_HZ * slow_rate_Hz - 1e-9))
    by_message: dict[str, list[tuple[Any, np.ndarray]]] = {}
    for name, value in (slow or {}).items():
        if name not in SLOW_SIGNALS:
            raise ValueError(f"`slow` names {name!r}, not one of {sorted(SLOW_SIGNALS)}")
        msg_name, sig_name, _unit = SLOW_SIGNALS[name]
        v = np.broadcast_to(np.asarray(value, dtype=float), (n_slow,)) if np.ndim(value) == 0 \
            else np.asarray(value, dtype=float)
        if v.shape != (n_slow,):
            raise ValueError(f"`slow[{name!r}]` must be a scalar or hold {n_slow} values, "
                             f"had {v.size}")
        sig = db.get_message_by_name(msg_name).get_signal_by_name(sig_name)
        by_message.setdefault(msg_name, []).append((sig, v))
    for msg_name, entries in by_message.items():
        msg = db.get_message_by_name(msg_name)
        d = np.zeros((n_slow, 8), np.uint8)
        for sig, v in entries:
            _put(d, _raw(v, sig, sig.name), sig)
        stamps.append(start_time_s + np.arange(n_slow) / slow_rate_Hz + latency_s
                      + gen.uniform(0.0, jitter_s, n_slow))
        ids.append(np.full(n_slow, int(msg.frame_id), np.uint32))
        ext.append(np.zeros(n_slow, bool))
        payloads.append(d)
    t = np.concatenate(stamps)
    order = np.argsort(t, kind="stable")
    m = t.size
    return CanFrameBatch(
        t[order], np.concatenate(ids)[order], np.concatenate(ext)[order], np.zeros(m, bool),
        np.full(m, 8, np.uint8), np.ascontiguousarray(np.concatenate(payloads)[order]),
        np.zeros(m, np.int16), np.arange(m, dtype=np.int64), "byte")
