"""ROS 2 (CDR) payloads and dotted field paths into decoded messages.

``sensor_msgs/msg/Imu`` read straight from CDR, one-numeric-field (scalar) messages and
generic messages via ``mcap-ros2-support``.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Callable
from typing import Any, Final

import numpy as np

from rigtools.errors import PayloadDecodeError, SchemaUnusableError
from rigtools.ingest.mcap.payloads import ImuSample
from rigtools.ingest.mcap.records import SchemaRecord

__all__ = [
    "IMU_SCHEMA_TEXT",
    "decode_imu_cdr",
    "generic_ros2_decoder",
    "get_field",
    "message_stamp_ns",
    "ros2_scalar_field",
]

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


def generic_ros2_decoder(schema: SchemaRecord) -> Callable[[Any], Any]:
    """A decoder of any ``ros2msg`` schema: ``mcap-ros2-support``'s, its errors ours.

    Raises
    ------
    SchemaUnusableError
        The schema text does not parse, or does not define ``schema.name``.
    """
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
    for part in re.split(r"\.|\[([0-9]+)\]", path):  # ASCII digits: int() of "²" fails
        if not part:
            continue
        nxt = _MISSING
        if isinstance(cur, dict):
            nxt = cur.get(part, _MISSING)
        elif isinstance(cur, list | tuple | bytes | np.ndarray) and part.isascii() \
                and part.isdigit():
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
