"""Values read from the stage JSON files, made into report.json values.

The stage files are read as loose JSON (:mod:`rigtools.report.inputs`); a field may be absent,
of the wrong type or not finite. Each function here takes one such value and returns the report
value or ``None`` (``{}`` for a mapping), so every report section reads its inputs the same way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

__all__ = [
    "QUANTITY_FIELDS",
    "as_dict",
    "as_float",
    "as_int",
    "as_quantity",
    "as_str",
    "plain",
]

#: Fields of a summary quantity carried into the report: mean, sd and quantiles.
QUANTITY_FIELDS: Final = ("mean", "sd", "q05", "q50", "q95")


def as_float(v: Any) -> float | None:
    """A finite number as float, else None (booleans are not numbers).

    Parameters
    ----------
    v : Any
        A JSON value.

    Returns
    -------
    float or None
    """
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    f = float(v)
    return f if math.isfinite(f) else None


def as_int(v: Any) -> int | None:
    """An integer, else None (booleans and floats are not integers).

    Parameters
    ----------
    v : Any
        A JSON value.

    Returns
    -------
    int or None
    """
    if isinstance(v, bool) or not isinstance(v, int):
        return None
    return int(v)


def as_str(v: Any) -> str | None:
    """A string as it is, else None.

    Parameters
    ----------
    v : Any
        A JSON value.

    Returns
    -------
    str or None
    """
    return v if isinstance(v, str) else None


def as_dict(v: Any) -> dict[str, Any]:
    """A JSON object as it is, else an empty dict.

    Parameters
    ----------
    v : Any
        A JSON value.

    Returns
    -------
    dict
    """
    return v if isinstance(v, dict) else {}


def plain(obj: Any) -> Any:
    """A JSON-safe copy: non-finite floats to None, keys to str, tuples to lists.

    Parameters
    ----------
    obj : Any
        Nested mappings, lists, tuples and scalars; anything else becomes its ``str``.

    Returns
    -------
    Any
        The copy.
    """
    if isinstance(obj, bool) or obj is None or isinstance(obj, str | int):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [plain(v) for v in obj]
    return str(obj)


def as_quantity(q: Any) -> dict[str, Any] | None:
    """Mean, sd and quantiles of a summary quantity, or None when absent.

    Parameters
    ----------
    q : Any
        A quantity of calibration ``summary.json`` (``parameters.<name>`` or
        ``derived.<name>``).

    Returns
    -------
    dict or None
        :data:`QUANTITY_FIELDS` (None where not a finite number), ``unit`` and, when the
        summary gives it, ``finite_fraction``.
    """
    if not isinstance(q, dict):
        return None
    out: dict[str, Any] = {k: as_float(q.get(k)) for k in QUANTITY_FIELDS}
    unit = as_str(q.get("unit"))
    out["unit"] = unit
    ff = as_float(q.get("finite_fraction"))
    if ff is not None:
        out["finite_fraction"] = ff
    return out
