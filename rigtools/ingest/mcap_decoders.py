"""Payload decoders for MCAP messages, chosen by a factory from the message encoding and schema.

:func:`decoder_for` answers, for one channel's ``(message_encoding, schema)``, a
:class:`Decoder` (a callable on the message bytes, tagged with what it yields) or ``None``;
the MCAP reader caches the answer per channel and counts every message of a channel with
no decoder as ``no_decoder``, naming topic, encoding and schema in a warning.

====================  ==================  =========================  =====================
kind                  message encoding    schema (encoding, name)    yields
====================  ==================  =========================  =====================
``"batch"``           ``protobuf``        ``protobuf``,              :class:`AccelBatch`
                                          ``rigtools.AccelBatch``
``"batch"``           ``json``            ``jsonschema``,            :class:`AccelBatch`
                                          ``rigtools.AccelBatch``
``"slow"``            ``json``            ``jsonschema``,            :class:`SlowValue`
                                          ``rigtools.SlowValue``
``"imu"``             ``cdr``             ``ros2msg``,               :class:`ImuSample`
                                          ``sensor_msgs/msg/Imu``
``"scalar"``          ``cdr``             ``ros2msg``, one numeric   float
                                          field (``std_msgs/msg/
                                          Float64``, ...)
``"generic"``         ``cdr`` / ``json``  ``ros2msg`` / any          decoded object for a
                                                                     mapping's dotted path
====================  ==================  =========================  =====================

The rigtools accelerometer batch (``data_schemas/accel_batch.proto`` and
``accel_batch.schema.json``) is decoded by a small hand-written protobuf wire-format walker
that views the packed ``values`` as ``float32`` in place (``np.frombuffer``), so the cost per
message does not grow with the number of samples in Python. ROS 2 ``Imu`` is read straight
from its CDR layout; every other ROS 2 message goes through ``mcap-ros2-support``'s generic
CDR decoder.

``rigtools.SlowValue`` is the small JSON message rigtools writes for slow signals (one point
per message; schema ``data_schemas/slow_value.schema.json``, loaded as
:data:`SLOW_VALUE_SCHEMA`)::

    {"name": "PinionSpeed_rpm", "unit": "rpm", "stamp_ns": 1700000000000000000, "value": 1500.0}
"""

from __future__ import annotations

import functools
import json
import math
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Literal, NamedTuple, TypeAlias

import numpy as np

from rigtools.errors import RecordingFormatError
from rigtools.ingest.mcap_records import SchemaRecord
from rigtools.schemas import load_schema

__all__ = [
    "ACCEL_BATCH_FIELDS",
    "ACCEL_BATCH_SCHEMA_NAME",
    "IMU_SCHEMA_NAME",
    "IMU_SCHEMA_TEXT",
    "MAX_SAMPLE_RATE_HZ",
    "MIN_SAMPLE_RATE_HZ",
    "SLOW_VALUE_SCHEMA",
    "SLOW_VALUE_SCHEMA_FILE",
    "SLOW_VALUE_SCHEMA_NAME",
    "AccelBatch",
    "AccelBatchColumns",
    "Decoder",
    "ImuSample",
    "PayloadDecodeError",
    "SchemaRecord",
    "SchemaUnusableError",
    "SlowValue",
    "accel_batch_file_descriptor_set",
    "decode_accel_batch_json",
    "decode_accel_batch_protobuf",
    "decode_accel_batches_protobuf",
    "decode_imu_cdr",
    "decode_slow_value_json",
    "decoder_for",
    "encode_accel_batch_protobuf",
    "get_field",
    "message_stamp_ns",
    "ros2_scalar_field",
]

ACCEL_BATCH_SCHEMA_NAME: Final = "rigtools.AccelBatch"
SLOW_VALUE_SCHEMA_NAME: Final = "rigtools.SlowValue"
IMU_SCHEMA_NAME: Final = "sensor_msgs/msg/Imu"

#: The fields of ``rigtools.AccelBatch``: (name, number, protobuf type, label), in the order
#: of ``data_schemas/accel_batch.proto``. Types and labels are ``FieldDescriptorProto`` names.
ACCEL_BATCH_FIELDS: Final[tuple[tuple[str, int, str, str], ...]] = (
    ("channel", 1, "TYPE_STRING", "LABEL_OPTIONAL"),
    ("unit", 2, "TYPE_STRING", "LABEL_OPTIONAL"),
    ("sample_rate_Hz", 3, "TYPE_DOUBLE", "LABEL_OPTIONAL"),
    ("first_sample_index", 4, "TYPE_UINT64", "LABEL_OPTIONAL"),
    ("stamp_ns", 5, "TYPE_UINT64", "LABEL_OPTIONAL"),
    ("values", 6, "TYPE_FLOAT", "LABEL_REPEATED"),
)

#: File name (under ``data_schemas/``, see :func:`rigtools.schemas.schema_path`) of the JSON
#: Schema of ``rigtools.SlowValue``; writers embed its content as the MCAP schema data.
SLOW_VALUE_SCHEMA_FILE: Final = "slow_value.schema.json"
#: JSON Schema of ``rigtools.SlowValue`` (message encoding ``json``): one point of a slow
#: signal. ``stamp_ns`` is the logger time (ns since the UNIX epoch); ``value`` is in ``unit``.
#: Loaded from :data:`SLOW_VALUE_SCHEMA_FILE`; shared, do not modify.
SLOW_VALUE_SCHEMA: Final[dict[str, Any]] = load_schema(SLOW_VALUE_SCHEMA_FILE)

#: ROS 2 message definition of ``sensor_msgs/msg/Imu`` with its dependencies, as rosbag2 and
#: ``mcap-ros2-support`` write it into ``ros2msg`` schemas.
IMU_SCHEMA_TEXT: Final = """\
std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""

_ROS2_NUMERIC: Final = frozenset({
    "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32",
    "int64", "uint64", "float32", "float64",
})
_UINT64_MAX: Final = (1 << 64) - 1
_INT64_MAX: Final = (1 << 63) - 1

#: Sample rates an AccelBatch may state (Hz); one outside is counted ``decode_error``.
MIN_SAMPLE_RATE_HZ: Final = 1e-3
MAX_SAMPLE_RATE_HZ: Final = 1e7


class PayloadDecodeError(RecordingFormatError):
    """A message payload does not decode under its channel's schema.

    The MCAP reader catches it and counts the message as ``decode_error``; it never leaves
    :func:`rigtools.ingest.read`.
    """


class SchemaUnusableError(RecordingFormatError):
    """A schema names a known type but cannot be used (it does not parse, or its fields differ)."""


class AccelBatch(NamedTuple):
    """One decoded ``rigtools.AccelBatch`` message.

    Attributes
    ----------
    channel : str
        Channel name (may be empty; the reader then uses the topic).
    unit : str
        Unit of ``values``.
    sample_rate_Hz : float
        Nominal sample rate (Hz).
    first_sample_index : int
        Absolute sample counter of ``values[0]``.
    stamp_ns : int
        Logger time of ``values[0]`` (ns since the UNIX epoch).
    values : numpy.ndarray
        float32 samples; for protobuf a read-only view into the message bytes.
    """

    channel: str
    unit: str
    sample_rate_Hz: float
    first_sample_index: int
    stamp_ns: int
    values: np.ndarray


class AccelBatchColumns(NamedTuple):
    """Many ``rigtools.AccelBatch`` messages of one channel with the same length, decoded at once.

    Attributes
    ----------
    channel, unit : str
    sample_rate_Hz : float
        Shared by all the messages.
    first_sample_index : numpy.ndarray
        int64, shape ``(m,)``.
    stamp_ns : numpy.ndarray
        uint64, shape ``(m,)`` (ns since the UNIX epoch).
    values : numpy.ndarray
        float32, shape ``(m, k)``: row ``i`` holds the samples of message ``i`` (a copy).
    """

    channel: str
    unit: str
    sample_rate_Hz: float
    first_sample_index: np.ndarray
    stamp_ns: np.ndarray
    values: np.ndarray


class SlowValue(NamedTuple):
    """One decoded ``rigtools.SlowValue`` point: name, unit, time (ns) and value."""

    name: str
    unit: str
    stamp_ns: int
    value: float


class ImuSample(NamedTuple):
    """What the reader takes from a ``sensor_msgs/msg/Imu``: header stamp and acceleration.

    Attributes
    ----------
    stamp_ns : int
        Header stamp (ns since the UNIX epoch): ``sec * 1e9 + nanosec``.
    ax, ay, az : float
        ``linear_acceleration.x|y|z`` (m/s^2).
    """

    stamp_ns: int
    ax: float
    ay: float
    az: float


@dataclass(frozen=True)
class Decoder:
    """A payload decoder: call it on a message's bytes.

    Attributes
    ----------
    kind : str
        What ``decode`` returns: ``"batch"`` (:class:`AccelBatch`), ``"slow"``
        (:class:`SlowValue`), ``"imu"`` (:class:`ImuSample`), ``"scalar"`` (float) or
        ``"generic"`` (a decoded object for :func:`get_field`).
    decode : callable
        ``decode(data) -> payload``; raises :class:`PayloadDecodeError` on a malformed payload.
    field : str or None
        For ``"scalar"``: the name of the one numeric field.
    decode_many : callable or None
        ``decode_many(buffer, starts, ends, out=None)``: decode all messages lying at
        ``buffer[starts[i]:ends[i]]`` at once, or answer None when they are not uniform
        enough (the caller then decodes them one by one). For ``"batch"``: an
        :class:`AccelBatchColumns`, whose values go to ``out(m, k)`` when given (see
        :func:`decode_accel_batches_protobuf`).
    """

    kind: Literal["batch", "slow", "imu", "scalar", "generic"]
    decode: Callable[[Any], Any]
    field: str | None = None
    decode_many: Callable[..., Any] | None = None

    def __call__(self, data: Any) -> Any:
        """Decode one payload (same as ``decode(data)``)."""
        return self.decode(data)


# --------------------------------------------------------------------------------------
# rigtools.AccelBatch: protobuf descriptor, encoder and wire-format walker
# --------------------------------------------------------------------------------------


@functools.cache
def accel_batch_file_descriptor_set() -> bytes:
    """Serialized ``FileDescriptorSet`` of ``rigtools.AccelBatch`` (the MCAP schema data).

    Built with ``google.protobuf.descriptor_pb2`` to match ``data_schemas/accel_batch.proto``
    (file ``accel_batch.proto``, package ``rigtools``, proto3), so no ``protoc`` is needed.
    """
    from google.protobuf import descriptor_pb2

    fds = descriptor_pb2.FileDescriptorSet()
    f = fds.file.add()
    f.name = "accel_batch.proto"
    f.package = "rigtools"
    f.syntax = "proto3"
    m = f.message_type.add()
    m.name = "AccelBatch"
    fdp = descriptor_pb2.FieldDescriptorProto
    for name, number, ftype, label in ACCEL_BATCH_FIELDS:
        fld = m.field.add()
        fld.name = name
        fld.number = number
        fld.type = fdp.Type.Value(ftype)
        fld.label = fdp.Label.Value(label)
        fld.json_name = name
        if label == "LABEL_REPEATED":
            fld.options.packed = True
    return fds.SerializeToString(deterministic=True)


def _varint_bytes(value: int) -> bytes:
    out = bytearray()
    while True:
        b = value & 0x7F
        value >>= 7
        if value:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def _len_field(number: int, payload: bytes) -> bytes:
    return _varint_bytes(number << 3 | 2) + _varint_bytes(len(payload)) + payload


def encode_accel_batch_protobuf(
    channel: str,
    unit: str,
    sample_rate_Hz: float,
    first_sample_index: int,
    stamp_ns: int,
    values: np.ndarray,
) -> bytes:
    """Serialize one ``rigtools.AccelBatch`` in protobuf wire format.

    Parameters
    ----------
    channel, unit : str
        Channel name and unit of ``values``.
    sample_rate_Hz : float
        Nominal sample rate (Hz).
    first_sample_index : int
        Absolute sample counter of ``values[0]`` (0 to 2**64 - 1).
    stamp_ns : int
        Logger time of ``values[0]`` (ns since the UNIX epoch).
    values : numpy.ndarray
        Samples; written as little-endian float32 (packed).

    Returns
    -------
    bytes
        The same bytes as the protobuf library's deterministic serialization (fields in
        number order, proto3 defaults omitted).
    """
    parts = []
    if channel:
        parts.append(_len_field(1, channel.encode("utf-8")))
    if unit:
        parts.append(_len_field(2, unit.encode("utf-8")))
    if sample_rate_Hz != 0.0 or math.copysign(1.0, sample_rate_Hz) < 0:
        parts.append(b"\x19" + struct.pack("<d", sample_rate_Hz))
    if first_sample_index:
        parts.append(b"\x20" + _varint_bytes(int(first_sample_index)))
    if stamp_ns:
        parts.append(b"\x28" + _varint_bytes(int(stamp_ns)))
    v = np.ascontiguousarray(values, dtype="<f4")
    if v.size:
        parts.append(_len_field(6, v.tobytes()))
    return b"".join(parts)


def _read_varint(buf: memoryview, pos: int, end: int) -> tuple[int, int]:
    result = 0
    shift = 0
    while True:
        if pos >= end:
            raise PayloadDecodeError(None, pos, "a complete varint", "the end of the message")
        b = buf[pos]
        pos += 1
        result |= (b & 0x7F) << shift
        if not b & 0x80:
            return result & _UINT64_MAX, pos  # protobuf keeps the low 64 bits
        shift += 7
        if shift > 63:
            raise PayloadDecodeError(None, pos, "a varint of at most 10 bytes", "a longer one")


def decode_accel_batch_protobuf(data: bytes | memoryview) -> AccelBatch:
    """Decode a protobuf ``rigtools.AccelBatch`` without the protobuf runtime.

    Parameters
    ----------
    data : bytes or memoryview
        The message payload.

    Returns
    -------
    AccelBatch
        ``values`` is a float32 view into ``data`` when the samples come in one packed run
        (the usual case), a copy otherwise (several runs, or unpacked fixed32 fields).

    Raises
    ------
    PayloadDecodeError
        Truncated fields, a wire type that does not match the field, a packed run whose length
        is not a multiple of 4, or a sample rate that is not finite and positive.

    Notes
    -----
    The loop below handles the six fields with their proper wire types and nothing else;
    anything unusual (unknown fields, unpacked floats) is handed to the full walker, which
    also produces the error messages. Cost per message is a few microseconds whatever the
    number of samples.
    """
    buf = data if type(data) is memoryview else memoryview(data)
    if buf.format != "B" or buf.ndim != 1:
        buf = buf.cast("B")
    end = len(buf)
    pos = 0
    channel = unit = ""
    rate = 0.0
    first = stamp = 0
    values = None
    while pos < end:
        key = buf[pos]
        pos += 1
        if key == 0x32 or key == 0x0A or key == 0x12:  # fields 6, 1, 2: length-delimited
            if pos >= end:
                return _decode_accel_batch_general(buf)
            length = buf[pos]
            if length < 0x80:
                pos += 1
            else:
                length, pos = _read_varint(buf, pos, end)
            stop = pos + length
            if stop > end or (key == 0x32 and (length & 3 or values is not None)):
                return _decode_accel_batch_general(buf)
            if key == 0x32:
                values = np.frombuffer(buf, "<f4", length >> 2, pos)
            else:
                try:
                    text = str(buf[pos:stop], "utf-8")
                except UnicodeDecodeError:
                    return _decode_accel_batch_general(buf)
                if key == 0x0A:
                    channel = text
                else:
                    unit = text
            pos = stop
        elif key == 0x20 or key == 0x28:  # fields 4, 5: varint
            v = shift = 0
            while True:
                if pos >= end or shift > 63:
                    return _decode_accel_batch_general(buf)
                b = buf[pos]
                pos += 1
                v |= (b & 0x7F) << shift
                if b < 0x80:
                    break
                shift += 7
            if key == 0x20:
                first = v & _UINT64_MAX
            else:
                stamp = v & _UINT64_MAX
        elif key == 0x19 and pos + 8 <= end:  # field 3: fixed64 double
            rate = _unpack_double(buf, pos)[0]
            pos += 8
        else:
            return _decode_accel_batch_general(buf)
    if values is None:
        values = np.zeros(0, np.float32)
    return _checked_batch(channel, unit, rate, first, stamp, values)


_unpack_double = struct.Struct("<d").unpack_from


def _decode_accel_batch_general(buf: memoryview) -> AccelBatch:
    """The full wire-format walker: any field order, unknown fields, unpacked floats."""
    end = len(buf)
    pos = 0
    channel = unit = ""
    rate = 0.0
    first = stamp = 0
    runs: list[np.ndarray] = []
    loose: list[float] = []
    while pos < end:
        key, pos = _read_varint(buf, pos, end)
        number, wire = key >> 3, key & 7
        if wire == 2:
            length, pos = _read_varint(buf, pos, end)
            stop = pos + length
            if stop > end:
                raise PayloadDecodeError(None, pos, f"{length} bytes of field {number}",
                                         f"{end - pos} left")
            if number == 6:
                if length % 4:
                    raise PayloadDecodeError(None, pos, "packed float32 values (a multiple of "
                                             "4 bytes)", f"{length} bytes")
                runs.append(np.frombuffer(buf, "<f4", length // 4, pos))
            elif number in (1, 2):
                try:
                    text = str(buf[pos:stop], "utf-8")
                except UnicodeDecodeError as exc:
                    raise PayloadDecodeError(None, pos, "UTF-8 text", str(exc)) from None
                if number == 1:
                    channel = text
                else:
                    unit = text
            elif number in (3, 4, 5):
                raise PayloadDecodeError(None, pos, f"field {number} as a scalar",
                                         "a length-delimited field")
            pos = stop
        elif wire == 0:
            value, pos = _read_varint(buf, pos, end)
            if number == 4:
                first = value
            elif number == 5:
                stamp = value
            elif number in (1, 2, 3, 6):
                raise PayloadDecodeError(None, pos, f"field {number} with its own wire type",
                                         "a varint")
        elif wire == 1:
            if pos + 8 > end:
                raise PayloadDecodeError(None, pos, "8 bytes", f"{end - pos} left")
            if number == 3:
                rate = struct.unpack_from("<d", buf, pos)[0]
            elif number in (1, 2, 4, 5, 6):
                raise PayloadDecodeError(None, pos, f"field {number} with its own wire type",
                                         "a fixed64")
            pos += 8
        elif wire == 5:
            if pos + 4 > end:
                raise PayloadDecodeError(None, pos, "4 bytes", f"{end - pos} left")
            if number == 6:
                if runs:  # keep order between packed runs and loose values
                    loose.extend(np.concatenate(runs).tolist())
                    runs.clear()
                loose.append(struct.unpack_from("<f", buf, pos)[0])
            elif number in (1, 2, 3, 4, 5):
                raise PayloadDecodeError(None, pos, f"field {number} with its own wire type",
                                         "a fixed32")
            pos += 4
        else:
            raise PayloadDecodeError(None, pos, "wire type 0, 1, 2 or 5", f"wire type {wire}")
    if loose:
        values = np.asarray(loose + (np.concatenate(runs).tolist() if runs else []), np.float32)
    elif len(runs) == 1:
        values = runs[0]
    elif runs:
        values = np.concatenate(runs)
    else:
        values = np.zeros(0, np.float32)
    return _checked_batch(channel, unit, rate, first, stamp, values)


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
            length, p = _read_varint(msg, pos + 1, end)
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
                length, p = _read_varint(msg, pos + 1, n)
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


def _checked_batch(
    channel: str, unit: str, rate: float, first: int, stamp: int, values: np.ndarray
) -> AccelBatch:
    if not (math.isfinite(rate) and MIN_SAMPLE_RATE_HZ <= rate <= MAX_SAMPLE_RATE_HZ):
        raise PayloadDecodeError(None, None, f"a finite sample_rate_Hz from "
                                 f"{MIN_SAMPLE_RATE_HZ:g} to {MAX_SAMPLE_RATE_HZ:g} Hz",
                                 repr(rate))
    if first > _INT64_MAX:
        raise PayloadDecodeError(None, None, "first_sample_index below 2**63", str(first))
    return AccelBatch(channel, unit, float(rate), int(first), int(stamp), values)


def _json(data: Any, expected: str) -> Any:
    """``data`` parsed as JSON; anything that does not parse is a :class:`PayloadDecodeError`.

    A document nested deeper than the parser's recursion limit is refused the same way.
    """
    try:
        return json.loads(bytes(data))
    except (UnicodeDecodeError, ValueError) as exc:
        raise PayloadDecodeError(None, None, expected, str(exc)) from None
    except RecursionError:
        raise PayloadDecodeError(None, None, expected,
                                 "a document nested too deeply to parse") from None


def _json_object(data: Any, fields: frozenset[str] | None = None,
                 what: str = "") -> dict[str, Any]:
    """A JSON object; with ``fields``, one with exactly those keys.

    (The rigtools schemas require all their fields and set ``additionalProperties`` false.)
    """
    doc = _json(data, "a JSON object")
    if not isinstance(doc, dict):
        raise PayloadDecodeError(None, None, "a JSON object", type(doc).__name__)
    if fields is not None and doc.keys() != fields:
        missing = sorted(fields - doc.keys())
        extra = sorted(doc.keys() - fields)
        found = "; ".join(part for part in (
            f"missing {', '.join(missing)}" if missing else "",
            f"extra {', '.join(map(repr, extra))}" if extra else "") if part)
        raise PayloadDecodeError(None, None, f"exactly the {what} fields "
                                 f"{', '.join(sorted(fields))}", found)
    return doc


def _uint64(name: str, v: Any) -> int:
    """``v`` when it is a JSON integer from 0 to 2**64 - 1 (not a bool)."""
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= _UINT64_MAX:
        raise PayloadDecodeError(None, None, f"{name} as a uint64", _short_repr(v))
    return v


def _float(name: str, v: Any) -> float:
    """``v`` as a float when it is a JSON number (not a bool) a float can hold."""
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise PayloadDecodeError(None, None, f"a number {name}", _short_repr(v))
    try:
        return float(v)
    except OverflowError:  # an integer literal beyond the float range
        raise PayloadDecodeError(None, None, f"a number {name} within the float range",
                                 _short_repr(v)) from None


def _short_repr(v: Any, limit: int = 40) -> str:
    """``repr(v)``, cut to ``limit`` characters (a hostile payload may hold huge literals)."""
    if isinstance(v, int) and not isinstance(v, bool) and v.bit_length() > 128:
        return f"an integer of {v.bit_length()} bits"
    try:
        text = repr(v)
    except RecursionError:
        return "a deeply nested value"
    return text if len(text) <= limit else text[: limit - 3] + "..."


_ACCEL_BATCH_KEYS: Final = frozenset(name for name, *_ in ACCEL_BATCH_FIELDS)
_SLOW_VALUE_KEYS: Final = frozenset(SLOW_VALUE_SCHEMA["required"])
_JSON_NUMBER_TYPES: Final = frozenset({int, float})


def _json_values(raw: Any) -> np.ndarray:
    """The ``values`` array of a JSON AccelBatch as float32: JSON numbers only (not bools).

    NaN and Infinity tokens are kept (the builder marks them invalid and counts them); a
    finite number beyond the float32 range becomes Inf the same way, without a warning.
    """
    if not isinstance(raw, list):
        raise PayloadDecodeError(None, None, "values as an array", type(raw).__name__)
    if not set(map(type, raw)) <= _JSON_NUMBER_TYPES:
        bad = next(v for v in raw if type(v) not in _JSON_NUMBER_TYPES)
        raise PayloadDecodeError(None, None, "values as an array of numbers",
                                 f"an element {_short_repr(bad)}")
    try:
        values = np.asarray(raw, dtype=np.float64)
    except OverflowError:  # an integer literal beyond the float range
        raise PayloadDecodeError(None, None, "values within the float range",
                                 "an integer literal beyond it") from None
    with np.errstate(over="ignore"):
        return values.astype(np.float32)


def decode_accel_batch_json(data: bytes | memoryview) -> AccelBatch:
    """Decode a JSON ``rigtools.AccelBatch`` (``data_schemas/accel_batch.schema.json``).

    The document is checked against the schema: exactly the six fields, a non-empty string
    ``channel``, a string ``unit``, a number ``sample_rate_Hz`` (finite, from
    :data:`MIN_SAMPLE_RATE_HZ` to :data:`MAX_SAMPLE_RATE_HZ`), integer ``first_sample_index``
    and ``stamp_ns`` (uint64; the counter below 2**63) and ``values`` an array of numbers
    (NaN and Infinity tokens allowed). ``values`` are cast to float32, the type the schema
    documents, so JSON and protobuf recordings of the same samples are identical.

    Raises
    ------
    PayloadDecodeError
        Not JSON (or nested too deeply), not an object, a field missing, extra or of the
        wrong type, or a number beyond what its field holds.
    """
    doc = _json_object(data, _ACCEL_BATCH_KEYS, "AccelBatch")
    channel, unit = doc["channel"], doc["unit"]
    if not (isinstance(channel, str) and channel and isinstance(unit, str)):
        raise PayloadDecodeError(None, None, "a non-empty string channel and a string unit",
                                 f"{_short_repr(channel)}, {_short_repr(unit)}")
    first = _uint64("first_sample_index", doc["first_sample_index"])
    stamp = _uint64("stamp_ns", doc["stamp_ns"])
    rate = _float("sample_rate_Hz", doc["sample_rate_Hz"])
    values = _json_values(doc["values"])
    return _checked_batch(channel, unit, rate, first, stamp, values)


def decode_slow_value_json(data: bytes | memoryview) -> SlowValue:
    """Decode a JSON ``rigtools.SlowValue`` (see :data:`SLOW_VALUE_SCHEMA`).

    Exactly the four fields: a non-empty string ``name``, a string ``unit``, an integer
    ``stamp_ns`` (uint64) and a number ``value`` (NaN and Infinity tokens allowed).

    Raises
    ------
    PayloadDecodeError
        Not JSON (or nested too deeply), not an object, a field missing, extra or of the
        wrong type, or a value beyond the float range.
    """
    doc = _json_object(data, _SLOW_VALUE_KEYS, "SlowValue")
    name, unit = doc["name"], doc["unit"]
    if not (isinstance(name, str) and name and isinstance(unit, str)):
        raise PayloadDecodeError(None, None, "string name and unit",
                                 f"{_short_repr(name)}, {_short_repr(unit)}")
    stamp = _uint64("stamp_ns", doc["stamp_ns"])
    value = _float("value", doc["value"])
    return SlowValue(name, unit, stamp, value)


# --------------------------------------------------------------------------------------
# ROS 2 (CDR)
# --------------------------------------------------------------------------------------


def _cdr_endian(buf: bytes | memoryview) -> str:
    if len(buf) < 4:
        raise PayloadDecodeError(None, 0, "a 4-byte CDR encapsulation header",
                                 f"{len(buf)} bytes")
    kind = buf[1]
    if buf[0] != 0 or kind not in (0, 1):
        raise PayloadDecodeError(None, 0, "plain CDR (encapsulation 0x0000 or 0x0001)",
                                 f"0x{buf[0]:02x}{kind:02x}")
    return "<" if kind == 1 else ">"


def decode_imu_cdr(data: bytes | memoryview) -> ImuSample:
    """Read header stamp and linear acceleration from a CDR ``sensor_msgs/msg/Imu``.

    Notes
    -----
    After the 4-byte encapsulation header the layout is fixed but for the frame id:
    ``int32 sec, uint32 nanosec, uint32 len, char[len] frame_id``, padding to 8 bytes
    (alignment counted from the end of the encapsulation header), then 25 float64
    (orientation, its covariance, angular velocity, its covariance) and the three
    float64 of ``linear_acceleration``.
    """
    e = _cdr_endian(data)
    n = len(data) - 4
    if n < 12:
        raise PayloadDecodeError(None, 4, "an Imu header", f"{n} bytes")
    sec, nsec, slen = struct.unpack_from(e + "iII", data, 4)
    off = ((12 + slen + 7) & ~7) + 200
    if off + 24 > n:
        raise PayloadDecodeError(None, 4, f"an Imu message of at least {off + 24} bytes",
                                 f"{n} bytes")
    ax, ay, az = struct.unpack_from(e + "3d", data, 4 + off)
    return ImuSample(sec * 1_000_000_000 + nsec, ax, ay, az)


def ros2_scalar_field(schema_text: str) -> str | None:
    """Name of the only field of a ROS 2 message definition, if it is one numeric scalar.

    ``std_msgs/msg/Float64`` (``float64 data``) gives ``"data"``; a message with a header,
    several fields, an array or a non-numeric field gives None. Constants are ignored.
    """
    first = re.split(r"^={3,}\s*$", schema_text, maxsplit=1, flags=re.MULTILINE)[0]
    fields = []
    for raw in first.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = line.split()
        if len(tokens) < 2:
            return None
        ftype, rest = tokens[0], " ".join(tokens[1:])
        if re.match(r"^[A-Z][A-Z0-9_]*\s*=", rest):
            continue  # a constant
        fields.append((ftype, tokens[1]))
    if len(fields) != 1:
        return None
    ftype, fname = fields[0]
    return fname if ftype in _ROS2_NUMERIC else None


def _generic_ros2(schema: SchemaRecord) -> Callable[[Any], Any]:
    from mcap_ros2._dynamic import generate_dynamic

    try:
        types = generate_dynamic(schema.name, schema.data.decode("utf-8"))
    except Exception as exc:  # a third-party parser: reported, never hidden
        raise SchemaUnusableError(None, f"schema {schema.id}", f"a ros2msg definition of "
                                  f"{schema.name!r}", f"{type(exc).__name__}: {exc}") from None
    if schema.name not in types:
        raise SchemaUnusableError(None, f"schema {schema.id}",
                                  f"a definition of {schema.name!r}", "none in the schema")
    fn = types[schema.name]

    def decode(data: Any) -> Any:
        try:
            return fn(bytes(data))
        except Exception as exc:  # third-party decoder: counted as decode_error
            raise PayloadDecodeError(None, None, f"a CDR {schema.name}",
                                     f"{type(exc).__name__}: {exc}") from None

    return decode


def _generic_json(data: Any) -> Any:
    return _json(data, "JSON")


def _accel_batch_descriptor_matches(data: bytes) -> bool:
    from google.protobuf import descriptor_pb2
    from google.protobuf.message import DecodeError

    fds = descriptor_pb2.FileDescriptorSet()
    try:
        fds.ParseFromString(data)
    except DecodeError:
        return False
    fdp = descriptor_pb2.FieldDescriptorProto
    for f in fds.file:
        for m in f.message_type:
            if f"{f.package}.{m.name}" != ACCEL_BATCH_SCHEMA_NAME:
                continue
            got = {(x.name, x.number, fdp.Type.Name(x.type), fdp.Label.Name(x.label))
                   for x in m.field}
            return set(ACCEL_BATCH_FIELDS) <= got
    return False


def decoder_for(
    message_encoding: str, schema: SchemaRecord | None, *, generic: bool = False
) -> Decoder | None:
    """Choose the decoder of a channel from its message encoding and schema.

    Parameters
    ----------
    message_encoding : str
        The channel's ``message_encoding`` (``"protobuf"``, ``"json"``, ``"cdr"``, ...).
    schema : SchemaRecord or None
        The channel's schema; None for schemaless channels.
    generic : bool
        Answer a ``"generic"`` decoder (whole decoded message, for a mapping's dotted
        field path) instead of the specialised one.

    Returns
    -------
    Decoder or None
        None when rigtools has no decoder for this combination (the caller counts the
        channel's messages as ``no_decoder``).

    Raises
    ------
    SchemaUnusableError
        The schema names a type rigtools knows but does not parse or has other fields.
    """
    if schema is None:
        return Decoder("generic", _generic_json) if generic and message_encoding == "json" \
            else None
    return _decoder_for(message_encoding, schema, generic)


@functools.lru_cache(maxsize=256)
def _decoder_for(message_encoding: str, schema: SchemaRecord, generic: bool) -> Decoder | None:
    name, enc = schema.name, schema.encoding
    if message_encoding == "protobuf" and enc == "protobuf" and name == ACCEL_BATCH_SCHEMA_NAME:
        if not _accel_batch_descriptor_matches(schema.data):
            raise SchemaUnusableError(None, f"schema {schema.id}", "the fields of "
                                      "data_schemas/accel_batch.proto", "a different descriptor")
        return Decoder("batch", decode_accel_batch_protobuf,
                       decode_many=decode_accel_batches_protobuf)
    if message_encoding == "json":
        if generic:
            return Decoder("generic", _generic_json)
        if name == ACCEL_BATCH_SCHEMA_NAME:
            return Decoder("batch", decode_accel_batch_json)
        if name == SLOW_VALUE_SCHEMA_NAME:
            return Decoder("slow", decode_slow_value_json)
        return None
    if message_encoding == "cdr" and enc == "ros2msg":
        if generic:
            return Decoder("generic", _generic_ros2(schema))
        if name in (IMU_SCHEMA_NAME, "sensor_msgs/Imu"):
            return Decoder("imu", decode_imu_cdr)
        text = schema.data.decode("utf-8", errors="replace")
        fname = ros2_scalar_field(text)
        if fname is None:
            return None
        decode = _generic_ros2(schema)

        def scalar(data: Any, _decode: Callable[[Any], Any] = decode,
                   _field: str = fname) -> float:
            return float(getattr(_decode(data), _field))

        return Decoder("scalar", scalar, fname)
    return None


# --------------------------------------------------------------------------------------
# Dotted field paths
# --------------------------------------------------------------------------------------

_MISSING: Final = object()


def get_field(obj: Any, path: str) -> Any:
    """Follow a dotted path (``linear_acceleration.x``, ``data.3`` or ``data[3]``) into a message.

    Works on decoded ROS 2 objects (attributes), JSON objects (keys) and sequences
    (integer components).

    Raises
    ------
    KeyError
        A component of the path does not exist; the message names it.
    """
    cur = obj
    for part in re.split(r"\.|\[(\d+)\]", path):
        if not part:
            continue
        nxt = _MISSING
        if isinstance(cur, dict):
            nxt = cur.get(part, _MISSING)
        elif isinstance(cur, list | tuple | bytes | np.ndarray) and part.isdigit():
            i = int(part)
            nxt = cur[i] if i < len(cur) else _MISSING
        elif not part.startswith("_"):
            nxt = getattr(cur, part, _MISSING)
        if nxt is _MISSING:
            raise KeyError(f"no field {part!r} in path {path!r}")
        cur = nxt
    return cur


def message_stamp_ns(obj: Any) -> int | None:
    """The header stamp of a decoded message (ns), or None when it has none.

    Looks for ``header.stamp.sec``/``nanosec`` (ROS 2) or a top-level ``stamp_ns`` (JSON).
    """
    try:
        stamp = get_field(obj, "header.stamp")
        return int(get_field(stamp, "sec")) * 1_000_000_000 + int(get_field(stamp, "nanosec"))
    except (KeyError, TypeError, ValueError, OverflowError):
        pass
    try:
        v = get_field(obj, "stamp_ns")
    except KeyError:
        return None
    return int(v) if isinstance(v, int) and not isinstance(v, bool) else None
