"""``rigtools.AccelBatch`` as protobuf: descriptor, encoder and wire-format walker."""

from __future__ import annotations

import functools
import math
import struct

import numpy as np

from rigtools.errors import PayloadDecodeError
from rigtools.ingest.mcap.payloads import (
    ACCEL_BATCH_FIELDS,
    UINT64_MAX,
    AccelBatch,
    checked_batch,
)

__all__ = [
    "accel_batch_file_descriptor_set",
    "decode_accel_batch_protobuf",
    "encode_accel_batch_protobuf",
    "read_varint",
]

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


def read_varint(buf: memoryview, pos: int, end: int) -> tuple[int, int]:
    """The protobuf varint at ``pos`` (its low 64 bits) and the position after it.

    Raises
    ------
    PayloadDecodeError
        The varint runs past ``end``.
    """
    result = 0
    shift = 0
    while True:
        if pos >= end:
            raise PayloadDecodeError(None, pos, "a complete varint", "the end of the message")
        b = buf[pos]
        pos += 1
        result |= (b & 0x7F) << shift
        if not b & 0x80:
            return result & UINT64_MAX, pos  # protobuf keeps the low 64 bits
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
                length, pos = read_varint(buf, pos, end)
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
                first = v & UINT64_MAX
            else:
                stamp = v & UINT64_MAX
        elif key == 0x19 and pos + 8 <= end:  # field 3: fixed64 double
            rate = _unpack_double(buf, pos)[0]
            pos += 8
        else:
            return _decode_accel_batch_general(buf)
    if values is None:
        values = np.zeros(0, np.float32)
    return checked_batch(channel, unit, rate, first, stamp, values)


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
        key, pos = read_varint(buf, pos, end)
        number, wire = key >> 3, key & 7
        if wire == 2:
            length, pos = read_varint(buf, pos, end)
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
            value, pos = read_varint(buf, pos, end)
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
    return checked_batch(channel, unit, rate, first, stamp, values)
