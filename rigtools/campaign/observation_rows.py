"""The observation row's finishing touches: its status from its flags, and its numbers.

Every module that makes rows of the observations table (:mod:`rigtools.campaign.observe`:
run, rms, natural_frequency and line rows; :mod:`rigtools.campaign.observe_orders`: arms rows)
builds a row as a dict with a private ``_flags`` list and finishes it with :func:`row_status`;
:func:`finite_or_none` turns a number into the null a missing value is in the table, and
:data:`ACCEL_TO_M_S2` is the acceleration units rigtools converts to m/s^2.
"""

from __future__ import annotations

import math
from typing import Any, Final

__all__ = ["ACCEL_TO_M_S2", "finite_or_none", "row_status"]


#: Acceleration units and their factor to m/s^2.
ACCEL_TO_M_S2: Final[dict[str, float]] = {
    "m/s^2": 1.0, "m/s2": 1.0, "m/s²": 1.0, "m s-2": 1.0, "m*s^-2": 1.0, "m.s-2": 1.0,
    "mm/s^2": 1e-3, "mm/s2": 1e-3, "g": 9.80665, "g0": 9.80665, "gn": 9.80665,
}


def finite_or_none(v: Any) -> float | None:
    """``v`` as a float, or None when it is None, NaN or infinite."""
    if v is None:
        return None
    f = float(v)
    return f if math.isfinite(f) else None


def row_status(row: dict[str, Any]) -> dict[str, Any]:
    """Fill ``quality_flags``, the flag columns and ``status`` from the row's ``_flags``."""
    flags = list(dict.fromkeys(row.pop("_flags", [])))
    row["quality_flags"] = ";".join(flags)
    row["flag_gaps"] = "gaps" in flags
    row["flag_clipping"] = "clipping" in flags
    row["flag_windows_dropped"] = "windows_dropped" in flags
    if row.get("quantity") in ("natural_frequency", "arms"):
        row["flag_low_snr"] = "low_snr" in flags
    if row.get("status") != "failed":
        row["status"] = "flagged" if flags else "ok"
    row.setdefault("message", "")
    return row

