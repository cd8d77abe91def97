"""JSON payloads: ``rigtools.AccelBatch`` and ``rigtools.SlowValue`` parsing and checks."""

from __future__ import annotations

import json
from typing import Any, Final

import numpy as np
import orjson

from rigtools.errors import PayloadDecodeError
from rigtools.ingest.mcap.payloads import (
    ACCEL_BATCH_FIELDS,
    SLOW_VALUE_SCHEMA,
    UINT64_MAX,
    AccelBatch,
    SlowValue,
    checked_batch,
)

__all__ = ["decode_accel_batch_json", "decode_slow_value_json", "parse_json"]


def parse_json(data: Any, expected: str) -> Any:
    """``data`` parsed as JSON; anything that does not parse is a :class:`PayloadDecodeError`.

    Parsed by orjson (RFC 8259), about ten times faster than the standard library on the
    number arrays of an AccelBatch (issue 21: 63 against 641 us for 1024 values); a document
    orjson refuses is parsed again by the standard library's :func:`json.loads`, whose
    superset the schemas accept (NaN and Infinity tokens, numbers beyond the float range as
    infinities, integers of any size, UTF-16/32 and a byte-order mark) and whose messages say
    what is wrong. Both give the same values wherever both parse, except integers beyond the
    64-bit range, which orjson gives as floats: a ``uint64`` field refuses them either way,
    a number array holds them as floats either way. A document nested deeper than the
    standard parser's recursion limit is refused the same way.
    """
    try:
        return orjson.loads(data)
    except orjson.JSONDecodeError:
        pass
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
    doc = parse_json(data, "a JSON object")
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
    if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= UINT64_MAX:
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

    NumPy's type discovery first: strings, nulls, arrays and objects never come out as a
    1-D integer or float array (integers beyond 64 bits come out as objects, or as the
    floats ``float()`` makes of them), and a bool comes out as 0 or 1. So such an array
    holding no 0 and no 1 is numbers only, and the check of every element's Python type is
    skipped (28 against 22 us for the values of a 1024-value batch, measured here); anything
    else takes that check. The values are the same either way (integers through float64
    first, as below).
    """
    if not isinstance(raw, list):
        raise PayloadDecodeError(None, None, "values as an array", type(raw).__name__)
    try:
        found = np.array(raw)
    except (ValueError, TypeError, OverflowError):  # ragged, or otherwise not numbers
        found = None
    if found is not None and found.ndim == 1 and found.dtype.kind in "fiu":
        as64 = found.astype(np.float64, copy=False)
        if not ((as64 == 0.0) | (as64 == 1.0)).any():  # a bool would read as 0 or 1
            with np.errstate(over="ignore"):
                return as64.astype(np.float32)
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
    return checked_batch(channel, unit, rate, first, stamp, values)


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
