"""Schema names, payload types and errors shared by the MCAP payload decoders.

See :mod:`rigtools.ingest.mcap.decoders` for the decoder factory.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Literal, NamedTuple

import numpy as np

from rigtools.errors import PayloadDecodeError
from rigtools.schemas import load_schema

__all__ = [
    "ACCEL_BATCH_FIELDS",
    "ACCEL_BATCH_SCHEMA_NAME",
    "IMU_SCHEMA_NAME",
    "MAX_SAMPLE_RATE_HZ",
    "MIN_SAMPLE_RATE_HZ",
    "SLOW_VALUE_SCHEMA",
    "SLOW_VALUE_SCHEMA_FILE",
    "SLOW_VALUE_SCHEMA_NAME",
    "UINT64_MAX",
    "AccelBatch",
    "AccelBatchColumns",
    "Decoder",
    "ImuSample",
    "SlowValue",
    "checked_batch",
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

UINT64_MAX: Final = (1 << 64) - 1
_INT64_MAX: Final = (1 << 63) - 1

#: Sample rates an AccelBatch may state (Hz); one outside is counted ``decode_error``.
MIN_SAMPLE_RATE_HZ: Final = 1e-3
MAX_SAMPLE_RATE_HZ: Final = 1e7


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
        Decodes all messages lying at ``buffer[starts[i]:ends[i]]`` (one channel's messages
        of one chunk) at once, or answers None when they are not uniform enough (the caller
        then decodes them one by one, which gives the same values). For ``"batch"``:
        ``decode_many(buffer, starts, ends, out=None)`` gives an :class:`AccelBatchColumns`,
        whose values go to ``out(m, k)`` when given (see
        :func:`~rigtools.ingest.mcap.protobuf_batch.decode_accel_batches_protobuf`). For
        ``"imu"``: ``decode_many(buffer, starts, ends)`` gives an
        :class:`~rigtools.ingest.mcap.cdr.ImuColumns`; for ``"scalar"`` a float64 array of
        the field; for a ROS 2 ``"generic"`` decoder ``decode_many(buffer, starts, ends,
        paths, scalar)`` gives a :class:`~rigtools.ingest.mcap.cdr.Ros2Columns` (see
        :mod:`rigtools.ingest.mcap.cdr`).
    """

    kind: Literal["batch", "slow", "imu", "scalar", "generic"]
    decode: Callable[[Any], Any]
    field: str | None = None
    decode_many: Callable[..., Any] | None = None

    def __call__(self, data: Any) -> Any:
        """Decode one payload (same as ``decode(data)``)."""
        return self.decode(data)


def checked_batch(
    channel: str, unit: str, rate: float, first: int, stamp: int, values: np.ndarray
) -> AccelBatch:
    """An :class:`AccelBatch` of decoded fields, its rate and first index checked.

    Raises
    ------
    PayloadDecodeError
        The rate is not finite or outside :data:`MIN_SAMPLE_RATE_HZ` ..
        :data:`MAX_SAMPLE_RATE_HZ`, or the first sample index is not below 2**63.
    """
    if not (math.isfinite(rate) and MIN_SAMPLE_RATE_HZ <= rate <= MAX_SAMPLE_RATE_HZ):
        raise PayloadDecodeError(None, None, f"a finite sample_rate_Hz from "
                                 f"{MIN_SAMPLE_RATE_HZ:g} to {MAX_SAMPLE_RATE_HZ:g} Hz",
                                 repr(rate))
    if first > _INT64_MAX:
        raise PayloadDecodeError(None, None, "first_sample_index below 2**63", str(first))
    return AccelBatch(channel, unit, float(rate), int(first), int(stamp), values)
