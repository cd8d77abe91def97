"""Write MCAP recordings the way the rig's logger does (for demos, tests and benchmarks).

* :func:`write_accel_mcap` writes accelerometer channels as ``rigtools.AccelBatch`` messages
  (protobuf or JSON, ``data_schemas/accel_batch.*``), slow signals as ``rigtools.SlowValue``
  JSON messages (one point per message, schema ``data_schemas/slow_value.schema.json``,
  embedded byte for byte) and the run metadata as a Metadata record named ``rigtools.run``;
* :func:`write_imu_mcap` writes ROS 2 ``sensor_msgs/msg/Imu`` messages (and optional
  ``std_msgs/msg/Float64`` topics) with ``mcap-ros2-support``, as a ROS 2 robot would.

Topics: accelerometer channel ``name`` on ``/accel/<name>``, slow signal ``name`` on
``/slow/<name>``. Messages of all topics are interleaved in log-time order.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from rigtools.ingest.mcap.decoders import (
    ACCEL_BATCH_SCHEMA_NAME,
    IMU_SCHEMA_NAME,
    IMU_SCHEMA_TEXT,
    SLOW_VALUE_SCHEMA_FILE,
    SLOW_VALUE_SCHEMA_NAME,
    accel_batch_file_descriptor_set,
    encode_accel_batch_protobuf,
)
from rigtools.ingest.recording import RunMetadata
from rigtools.schemas import schema_path

if TYPE_CHECKING:
    from mcap.records import Schema

__all__ = ["flatten_run_metadata", "imu_cdr_payloads", "write_accel_mcap", "write_imu_cdr_mcap",
           "write_imu_mcap"]

Compression = Literal["zstd", "lz4", "none"]
_LIBRARY = "rigtools.demo.mcap_writer"


def _compression(name: str) -> Any:
    from mcap.writer import CompressionType

    table = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
             "none": CompressionType.NONE}
    if name not in table:
        raise ValueError(f"`compression` must be one of {sorted(table)}, was {name!r}")
    return table[name]


def flatten_run_metadata(metadata: RunMetadata | Mapping[str, str]) -> dict[str, str]:
    """Key/values of a ``rigtools.run`` Metadata record.

    A :class:`~rigtools.ingest.recording.RunMetadata` becomes ``run_id``, ``rig``,
    ``gear_set`` (when set), ``conditions.<name_with_unit>`` (``repr`` of the float, so it
    reads back exactly) and its ``extra`` keys; a mapping is taken as is.
    """
    if not isinstance(metadata, RunMetadata):
        return {str(k): str(v) for k, v in metadata.items()}
    out: dict[str, str] = {}
    for key in ("run_id", "rig", "gear_set"):
        v = getattr(metadata, key)
        if v is not None:
            out[key] = str(v)
    for name, value in metadata.conditions.items():
        out[f"conditions.{name}"] = repr(float(value))
    out.update(metadata.extra)
    return out


def _to_ns(t_s: float) -> int:
    return round(t_s * 1e9)


def write_accel_mcap(
    path: str | Path,
    channels: Mapping[str, tuple[np.ndarray, float, str, int, float]],
    slow: Mapping[str, tuple[np.ndarray, np.ndarray, str]] | None = None,
    metadata: RunMetadata | Mapping[str, str] | None = None,
    *,
    encoding: Literal["protobuf", "json"] = "protobuf",
    compression: Compression = "zstd",
    batch: int = 1024,
    chunk_size: int = 1 << 20,
    use_chunking: bool = True,
    indexed: bool = True,
) -> Path:
    """Write accelerometer channels, slow signals and run metadata to an MCAP file.

    Parameters
    ----------
    path : str or pathlib.Path
        Output file.
    channels : mapping
        Channel name -> ``(values, sample_rate_Hz, unit, first_sample_index, start_time_s)``:
        samples (written as float32), nominal rate (Hz), unit, the absolute sample counter
        of ``values[0]``, and the logger time of sample index 0 (s since the UNIX epoch).
        Batch ``k`` carries ``first_sample_index + k * batch`` and the stamp
        ``start_time_s + first / sample_rate_Hz`` (rounded to ns).
    slow : mapping, optional
        Slow signal name -> ``(time_s, values, unit)``: one ``rigtools.SlowValue`` JSON
        message per point.
    metadata : RunMetadata or mapping, optional
        Written as a Metadata record named ``rigtools.run`` (see
        :func:`flatten_run_metadata`).
    encoding : {"protobuf", "json"}
        Encoding of the batch messages.
    compression : {"zstd", "lz4", "none"}
        Chunk compression.
    batch : int
        Samples per batch message.
    chunk_size : int
        Target uncompressed chunk size (bytes).
    use_chunking : bool
        False writes messages straight into the data section (no chunks).
    indexed : bool
        False writes no message indexes, chunk indexes, statistics, repeated schemas and
        channels or summary offsets: a file readable only by streaming.

    Returns
    -------
    pathlib.Path
        The file written. Every message's ``log_time`` is the stamp of the batch's last
        sample (when the logger had it complete).
    """
    from mcap.writer import IndexType, Writer

    if batch < 1:
        raise ValueError(f"`batch` must be >= 1, was {batch}")
    if encoding not in ("protobuf", "json"):
        raise ValueError(f"`encoding` must be 'protobuf' or 'json', was {encoding!r}")
    out = Path(path)
    slow_points: Mapping[str, tuple[np.ndarray, np.ndarray, str]] = slow or {}
    events: list[tuple[int, int, str, int]] = []  # (log_time_ns, order, kind:name, k)
    order = 0
    for name, (values, fs, _unit, _first, t0) in channels.items():
        n = len(values)
        for k in range(math.ceil(n / batch)):
            last = min(n, (k + 1) * batch) - 1
            events.append((_to_ns(t0 + (_first + last) / fs), order, name, k))
            order += 1
    for name, (time_s, _v, _unit) in slow_points.items():
        for k, t in enumerate(np.asarray(time_s, np.float64)):
            events.append((_to_ns(float(t)), order, "\0" + name, k))
            order += 1
    events.sort()

    with open(out, "wb") as f:
        kwargs: dict[str, Any] = {}
        if not indexed:
            kwargs = dict(index_types=IndexType.NONE, repeat_channels=False,
                          repeat_schemas=False, use_statistics=False, use_summary_offsets=False)
        w = Writer(f, chunk_size=chunk_size, compression=_compression(compression),
                   use_chunking=use_chunking, **kwargs)
        w.start(profile="", library=_LIBRARY)
        if encoding == "protobuf":
            sid = w.register_schema(ACCEL_BATCH_SCHEMA_NAME, "protobuf",
                                    accel_batch_file_descriptor_set())
        else:
            sid = w.register_schema(ACCEL_BATCH_SCHEMA_NAME, "jsonschema",
                                    schema_path("accel_batch.schema.json").read_bytes())
        chan_ids = {name: w.register_channel(f"/accel/{name}", encoding, sid)
                    for name in channels}
        slow_ids: dict[str, int] = {}
        if slow_points:
            ssid = w.register_schema(SLOW_VALUE_SCHEMA_NAME, "jsonschema",
                                     schema_path(SLOW_VALUE_SCHEMA_FILE).read_bytes())
            slow_ids = {name: w.register_channel(f"/slow/{name}", "json", ssid)
                        for name in slow_points}
        seq: dict[str, int] = {}
        for log_ns, _o, key, k in events:
            if key.startswith("\0"):
                name = key[1:]
                time_s, vals, unit = slow_points[name]
                t = float(np.asarray(time_s, np.float64)[k])
                data = json.dumps({"name": name, "unit": unit, "stamp_ns": _to_ns(t),
                                   "value": float(np.asarray(vals, np.float64)[k])}).encode()
                cid = slow_ids[name]
            else:
                name = key
                values, fs, unit, first, t0 = channels[name]
                block = np.asarray(values[k * batch : (k + 1) * batch], dtype=np.float32)
                first_i = int(first) + k * batch
                stamp = _to_ns(t0 + first_i / fs)
                if encoding == "protobuf":
                    data = encode_accel_batch_protobuf(name, unit, float(fs), first_i, stamp,
                                                       block)
                else:
                    data = json.dumps({"channel": name, "unit": unit, "sample_rate_Hz": float(fs),
                                       "first_sample_index": first_i, "stamp_ns": stamp,
                                       "values": block.tolist()}).encode()
                cid = chan_ids[name]
            s = seq.get(key, 0)
            seq[key] = s + 1
            w.add_message(cid, log_time=log_ns, data=data, publish_time=log_ns, sequence=s)
        if metadata is not None:
            w.add_metadata("rigtools.run", flatten_run_metadata(metadata))
        w.finish()
    return out


def write_imu_mcap(
    path: str | Path,
    stamps_s: np.ndarray,
    accel_m_s2: np.ndarray,
    *,
    topic: str = "/imu",
    frame_id: str = "imu_link",
    scalars: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    log_delay_s: float = 0.0,
    compression: Compression = "zstd",
    chunk_size: int = 1 << 20,
) -> Path:
    """Write ROS 2 ``sensor_msgs/msg/Imu`` messages (and ``std_msgs/msg/Float64`` topics).

    Parameters
    ----------
    path : str or pathlib.Path
        Output file.
    stamps_s : numpy.ndarray
        Header stamps (s since the UNIX epoch), shape ``(n,)``.
    accel_m_s2 : numpy.ndarray
        Linear acceleration x, y, z (m/s^2), shape ``(n, 3)``.
    topic, frame_id : str
        Imu topic and header frame id.
    scalars : mapping, optional
        Topic -> ``(time_s, values)`` written as ``std_msgs/msg/Float64`` with
        ``log_time = time_s``.
    log_delay_s : float
        Imu ``log_time`` = header stamp + this delay (s), as a logger receiving late would.
    compression : {"zstd", "lz4", "none"}
        Chunk compression.
    chunk_size : int
        Target uncompressed chunk size (bytes).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    from mcap_ros2.writer import Writer

    stamps = np.asarray(stamps_s, np.float64)
    acc = np.asarray(accel_m_s2, np.float64)
    if acc.shape != (stamps.size, 3):
        raise ValueError(f"`accel_m_s2` must have shape ({stamps.size}, 3), was {acc.shape}")
    out = Path(path)
    zero3 = {"x": 0.0, "y": 0.0, "z": 0.0}
    with open(out, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=_compression(compression))
        imu = w.register_msgdef(IMU_SCHEMA_NAME, IMU_SCHEMA_TEXT)
        events: list[tuple[int, int, str, int]] = [
            (_to_ns(float(t) + log_delay_s), i, topic, i) for i, t in enumerate(stamps)
        ]
        float64_topics: dict[str, tuple[Schema, np.ndarray]] = {}
        if scalars:
            f64 = w.register_msgdef("std_msgs/msg/Float64", "float64 data\n")
            for name, (ts, values) in scalars.items():
                float64_topics[name] = (f64, values)
                events += [(_to_ns(float(t)), len(events) + j, "\0" + name, j)
                           for j, t in enumerate(np.asarray(ts, np.float64))]
        events.sort()
        for log_ns, _o, key, k in events:
            if key.startswith("\0"):
                name = key[1:]
                schema, values = float64_topics[name]
                w.write_message(name, schema, {"data": float(values[k])},
                                log_time=log_ns, sequence=k)
                continue
            t_ns = _to_ns(float(stamps[k]))
            msg = {
                "header": {"stamp": {"sec": t_ns // 1_000_000_000,
                                     "nanosec": t_ns % 1_000_000_000},
                           "frame_id": frame_id},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                "orientation_covariance": [0.0] * 9,
                "angular_velocity": zero3,
                "angular_velocity_covariance": [0.0] * 9,
                "linear_acceleration": {"x": float(acc[k, 0]), "y": float(acc[k, 1]),
                                        "z": float(acc[k, 2])},
                "linear_acceleration_covariance": [0.0] * 9,
            }
            w.write_message(topic, imu, msg, log_time=log_ns, sequence=k)
        w.finish()
    return out


def imu_cdr_payloads(
    stamps_ns: np.ndarray, accel_m_s2: np.ndarray, *, frame_id: str = "imu_link",
    big_endian: bool = False,
) -> np.ndarray:
    """CDR ``sensor_msgs/msg/Imu`` payloads of many samples at once, one row per message.

    The layout is the one ``mcap-ros2-support`` (and a ROS 2 driver) serialises: the 4-byte
    encapsulation header (``00 01`` little-endian, ``00 00`` big-endian, options ``00 00``),
    ``int32 sec``, ``uint32 nanosec``, ``uint32`` length and bytes of ``frame_id`` with its
    NUL, padding to 8 bytes counted from the end of the encapsulation header, then the
    orientation (0, 0, 0, 1), 9 zero covariances, a zero angular velocity, 9 zero covariances,
    the linear acceleration (m/s^2) and 9 zero covariances, all float64.

    Parameters
    ----------
    stamps_ns : numpy.ndarray
        Header stamps (ns since the UNIX epoch, int64), shape ``(n,)``.
    accel_m_s2 : numpy.ndarray
        Linear acceleration x, y, z (m/s^2), shape ``(n, 3)``.
    frame_id : str
        Header frame id (the same in every message).
    big_endian : bool
        Big-endian CDR (encapsulation kind 0) instead of little-endian (kind 1).

    Returns
    -------
    numpy.ndarray
        uint8, shape ``(n, length)``: row ``i`` is the payload of message ``i``.
    """
    stamps = np.asarray(stamps_ns, np.int64)
    acc = np.asarray(accel_m_s2, np.float64)
    if acc.shape != (stamps.size, 3):
        raise ValueError(f"`accel_m_s2` must have shape ({stamps.size}, 3), was {acc.shape}")
    name = frame_id.encode("utf-8") + b"\0"
    e = ">" if big_endian else "<"
    body = (12 + len(name) + 7) & ~7  # stamp, length word, frame id and padding
    n_bytes = 4 + body + 8 * 37
    dt = np.dtype({"names": ["enc", "sec", "nsec", "slen", "name", "f"],
                   "formats": ["4u1", e + "i4", e + "u4", e + "u4", f"{len(name)}u1",
                               (e + "f8", (37,))],
                   "offsets": [0, 4, 8, 12, 16, 4 + body], "itemsize": n_bytes})
    out = np.zeros(stamps.size, dt)
    out["enc"] = (0, 0 if big_endian else 1, 0, 0)
    sec, nsec = np.divmod(stamps, 1_000_000_000)
    out["sec"] = sec
    out["nsec"] = nsec
    out["slen"] = len(name)
    out["name"] = np.frombuffer(name, np.uint8)
    f = out["f"]
    f[:, 3] = 1.0  # orientation.w
    f[:, 25:28] = acc
    return out.view(np.uint8).reshape(stamps.size, n_bytes)


def write_imu_cdr_mcap(
    path: str | Path,
    stamps_ns: np.ndarray,
    accel_m_s2: np.ndarray,
    *,
    topic: str = "/imu",
    frame_id: str = "imu_link",
    big_endian: bool = False,
    scalars: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    log_delay_ns: int = 0,
    compression: Compression = "zstd",
    chunk_size: int = 1 << 20,
) -> Path:
    """Write many ``sensor_msgs/msg/Imu`` messages fast (a driver's per-sample stream).

    The same file :func:`write_imu_mcap` writes (schema ``ros2msg``
    :data:`~rigtools.ingest.mcap.decoders.IMU_SCHEMA_TEXT`, channel encoding ``cdr``), but
    the payloads are laid out with array operations (:func:`imu_cdr_payloads`), so millions
    of messages take seconds, and big-endian CDR can be written too. ``std_msgs/msg/Float64``
    topics in ``scalars`` (topic -> ``(time_s, values)``, ``log_time = time_s``) are
    interleaved in log-time order.

    Parameters
    ----------
    path : str or pathlib.Path
        Output file.
    stamps_ns : numpy.ndarray
        Header stamps (ns since the UNIX epoch, int64), shape ``(n,)``.
    accel_m_s2 : numpy.ndarray
        Linear acceleration x, y, z (m/s^2), shape ``(n, 3)``.
    topic, frame_id : str
        Imu topic and header frame id.
    big_endian : bool
        Big-endian CDR payloads.
    scalars : mapping, optional
        ``std_msgs/msg/Float64`` topics.
    log_delay_ns : int
        Imu ``log_time`` = header stamp + this delay (ns).
    compression : {"zstd", "lz4", "none"}
        Chunk compression.
    chunk_size : int
        Target uncompressed chunk size (bytes).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    from mcap.writer import Writer

    stamps = np.asarray(stamps_ns, np.int64)
    rows = imu_cdr_payloads(stamps, accel_m_s2, frame_id=frame_id, big_endian=big_endian)
    log = (stamps + int(log_delay_ns)).tolist()
    out = Path(path)
    with open(out, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=_compression(compression))
        w.start(profile="ros2", library=_LIBRARY)
        sid = w.register_schema(IMU_SCHEMA_NAME, "ros2msg", IMU_SCHEMA_TEXT.encode())
        cid = w.register_channel(topic, "cdr", sid)
        events: list[tuple[int, int, int, bytes]] = []
        if scalars:
            fsid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data\n")
            for name, (ts, values) in scalars.items():
                scid = w.register_channel(name, "cdr", fsid)
                vals = np.asarray(values, np.float64)
                for j, t in enumerate(np.asarray(ts, np.float64).tolist()):
                    events.append((_to_ns(t), scid, j,
                                   b"\0\1\0\0" + vals[j : j + 1].astype("<f8").tobytes()))
            events.sort()
        add = w.add_message
        k = 0
        data = rows.tobytes()
        size = rows.shape[1]
        for i, t in enumerate(log):
            while k < len(events) and events[k][0] < t:
                lt, scid, j, payload = events[k]
                add(scid, log_time=lt, data=payload, publish_time=lt, sequence=j)
                k += 1
            add(cid, log_time=t, data=data[i * size : (i + 1) * size], publish_time=t,
                sequence=i)
        for lt, scid, j, payload in events[k:]:
            add(scid, log_time=lt, data=payload, publish_time=lt, sequence=j)
        w.finish()
    return out
