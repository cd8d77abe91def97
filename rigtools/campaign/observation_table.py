"""The observations table: columns, flags, metadata keys, frame builder and result classes.

Holds the schema-derived columns, the flags a row may carry, the Parquet metadata keys, the
frame builder and the per-run and per-campaign result classes (``RunObservations``,
``Observations``). The rows are made by :mod:`rigtools.campaign.observe`; the files are
written and read by :mod:`rigtools.campaign.observation_files`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
import pandas as pd

from rigtools.schemas import load_schema

__all__ = [
    "FLAGS",
    "METADATA_KEY",
    "SCHEMA",
    "SCHEMA_METADATA_KEY",
    "Observations",
    "RunObservations",
    "observation_columns",
    "to_frame",
]

SCHEMA: Final = "observations.schema.json"
#: Parquet key-value metadata key holding the schema's JSON.
SCHEMA_METADATA_KEY: Final = "rigtools.observations.schema"
#: Parquet key-value metadata key holding the campaign, settings and versions (JSON).
METADATA_KEY: Final = "rigtools.observations"

#: Every flag a row may carry, and what it means.
FLAGS: Final[dict[str, str]] = {
    "gaps": "gaps or invalid samples in the channel (or run, or step)",
    "clipping": "runs of samples at the channel's extreme values",
    "low_snr": "peak prominence or mesh harmonic level under [analysis] low_snr_dB",
    "windows_dropped": "valid segments shorter than a Welch window, or order blocks lost to gaps",
    "ingest_losses": "frames or messages rejected at ingest",
    "at_mesh_line": "a mesh harmonic (up to the analysis' max_mesh_order), sideband or shaft "
                    "line sits on the mode, within its half-power band: masked out of its fit, "
                    "it has its own line row",
    "no_structural_peak": "no structural peak found in the channel's PSD",
    "peaks_failed": "the peak analysis of the channel failed",
    "constant": "every valid sample equal",
    "too_short": "no valid segment as long as one Welch window",
    "unit_not_acceleration": "the channel's unit is not an acceleration rigtools converts",
    "channel_missing": "a channel named in [sensors] accel is not in the recording",
    "condition_unresolved": "a condition names a slow signal that is absent or has no value",
    "speed_missing": "the speed signal is absent or covers none of the data",
    "no_speed_step": "no speed plateau long enough for a step",
    "speed_varies": "the run's speed varies beyond the step tolerance: the mesh line sweeps the "
                    "PSD, smeared; a natural frequency may be that swept line, not a mode",
    "step_without_block": "a speed step without one whole order block",
    "above_passband": "a mesh harmonic above the angular resampler's passband",
    "arms_failed": "the order analysis of the channel failed",
    "run_failed": "the run could not be read or analysed",
    "time_base_irregular": "a sample rate was estimated from stamps that do not fit a uniform "
                           "grid (a stamp more than half a sample off it, the logger clock "
                           "drifting by more than 100 ppm, stamps backwards, or samples moved "
                           "to a free slot)",
    "response_guessed": "the channel's unit does not say what it measures: the single-DOF "
                        "response fitted was chosen as the one that fits best",
}


# --------------------------------------------------------------------------------------------
# columns from the schema


def observation_columns() -> dict[str, str]:
    """Column name -> pandas dtype, in table order, from ``data_schemas/observations.schema.json``.

    ``number`` -> ``float64``, ``integer`` -> ``Int64``, ``boolean`` -> ``boolean``, strings and
    enums -> ``object`` (str or None).
    """
    props = load_schema(SCHEMA)["$defs"]["row"]["properties"]
    out = {}
    for name, p in props.items():
        types = p.get("type", "string")
        types = [types] if isinstance(types, str) else list(types)
        if "number" in types:
            out[name] = "float64"
        elif "integer" in types:
            out[name] = "Int64"
        elif "boolean" in types:
            out[name] = "boolean"
        else:
            out[name] = "object"
    return out


def to_frame(rows: Iterable[Mapping[str, Any]]) -> pd.DataFrame:
    """Rows (dicts with any subset of the columns) as a table with every column, typed."""
    cols = observation_columns()
    records = [{c: r.get(c) for c in cols} for r in rows]
    df = pd.DataFrame.from_records(records, columns=list(cols))
    for c, dtype in cols.items():
        if dtype == "float64":
            df[c] = pd.to_numeric(df[c].astype(object).where(df[c].notna(), np.nan),
                                  errors="raise").astype("float64")
        elif dtype == "object":
            df[c] = df[c].astype(object).where(df[c].notna(), None)
        else:
            df[c] = df[c].astype(dtype)
    return df


# --------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class RunObservations:
    """The rows of one run and whether it could be analysed.

    Attributes
    ----------
    run_id : str
    file : str
        The recording as resolved from the campaign.
    rows : tuple of dict
        Rows of the table (see the module docstring).
    analysed : bool
        The run was read and at least one channel analysed.
    error : str or None
        Why the run failed (the file and the reason), when it did.
    warnings : tuple of str
        Problems that flagged rows but did not fail the run.
    spectra : dict of str to (numpy.ndarray, numpy.ndarray, str)
        Channel -> ``(frequency_Hz, psd, psd_unit)``: the one-sided Welch PSD the channel's
        peaks were found on (bin frequencies in Hz, PSD in ``psd_unit``, the channel's unit
        squared per Hz, e.g. ``"(m/s^2)^2/Hz"``), for every channel that was analysed. Not
        part of the table nor of equality.
    """

    run_id: str
    file: str
    rows: tuple[dict[str, Any], ...]
    analysed: bool
    error: str | None = None
    warnings: tuple[str, ...] = ()
    spectra: dict[str, tuple[np.ndarray, np.ndarray, str]] = field(default_factory=dict,
                                                                   compare=False, repr=False)


@dataclass(frozen=True)
class Observations:
    """The observations of a campaign.

    Attributes
    ----------
    table : pandas.DataFrame
        The tidy table (columns: :func:`observation_columns`).
    runs : tuple of RunObservations
        Per run, in campaign order.
    metadata : dict
        Resolved campaign, analysis settings, versions (JSON-ready; written with the table).
    """

    table: pd.DataFrame
    runs: tuple[RunObservations, ...]
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def n_analysed(self) -> int:
        """Runs analysed."""
        return sum(r.analysed for r in self.runs)

    @property
    def failures(self) -> tuple[RunObservations, ...]:
        """Runs that failed."""
        return tuple(r for r in self.runs if not r.analysed)
