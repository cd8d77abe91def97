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
from collections.abc import Callable
from typing import Any

from rigtools.errors import PayloadDecodeError, SchemaUnusableError
from rigtools.ingest.mcap.cdr import Ros2BlockDecoder, decode_imu_cdr_many
from rigtools.ingest.mcap.json import decode_accel_batch_json, decode_slow_value_json, parse_json
from rigtools.ingest.mcap.payloads import (
    ACCEL_BATCH_FIELDS,
    ACCEL_BATCH_SCHEMA_NAME,
    IMU_SCHEMA_NAME,
    MAX_SAMPLE_RATE_HZ,
    MIN_SAMPLE_RATE_HZ,
    SLOW_VALUE_SCHEMA,
    SLOW_VALUE_SCHEMA_FILE,
    SLOW_VALUE_SCHEMA_NAME,
    AccelBatch,
    AccelBatchColumns,
    Decoder,
    ImuSample,
    SlowValue,
)
from rigtools.ingest.mcap.protobuf import (
    accel_batch_file_descriptor_set,
    decode_accel_batch_protobuf,
    encode_accel_batch_protobuf,
)
from rigtools.ingest.mcap.protobuf_batch import decode_accel_batches_protobuf
from rigtools.ingest.mcap.records import SchemaRecord
from rigtools.ingest.mcap.ros2 import (
    IMU_SCHEMA_TEXT,
    decode_imu_cdr,
    generic_ros2_decoder,
    get_field,
    message_stamp_ns,
    ros2_scalar_field,
)

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

def _generic_json(data: Any) -> Any:
    return parse_json(data, "JSON")


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
            decode = generic_ros2_decoder(schema)
            block = _block_decoder(schema)
            return Decoder("generic", decode,
                           decode_many=block.columns if block is not None else None)
        if name in (IMU_SCHEMA_NAME, "sensor_msgs/Imu"):
            return Decoder("imu", decode_imu_cdr, decode_many=decode_imu_cdr_many)
        text = schema.data.decode("utf-8", errors="replace")
        fname = ros2_scalar_field(text)
        if fname is None:
            return None
        decode = generic_ros2_decoder(schema)
        block = _block_decoder(schema)

        def scalar(data: Any, _decode: Callable[[Any], Any] = decode,
                   _field: str = fname) -> float:
            return float(getattr(_decode(data), _field))

        many = functools.partial(block.scalar_many, field=fname) if block is not None else None
        return Decoder("scalar", scalar, fname, decode_many=many)
    return None


def _block_decoder(schema: SchemaRecord) -> Ros2BlockDecoder | None:
    """The constant-layout block reader of a ``ros2msg`` schema.

    None when it cannot be built: the channel is then read message by message only.
    """
    try:
        return Ros2BlockDecoder(schema.name, schema.data.decode("utf-8"))
    except Exception:  # the third-party schema parser: the general path reports it
        return None
