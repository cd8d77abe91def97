"""Observations files: write, read and validate the table as Parquet.

Writes the table as Parquet with the schema and the metadata in the file's key-value metadata,
reads it back, and validates a frame against the schema. Reading a table loads pandas and
pyarrow, not the signal analysis.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rigtools.campaign.observation_table import (
    METADATA_KEY,
    SCHEMA,
    SCHEMA_METADATA_KEY,
    Observations,
    observation_columns,
    to_frame,
)
from rigtools.schemas import iter_errors, load_schema

__all__ = ["read_observations", "validate_observations", "write_observations"]

# --------------------------------------------------------------------------------------------
# files


def write_observations(obs: Observations | pd.DataFrame, path: str | Path,
                       metadata: Mapping[str, Any] | None = None) -> Path:
    """Write the table as Parquet, with the schema and the metadata in the file's metadata.

    Parameters
    ----------
    obs : Observations or pandas.DataFrame
    path : str or pathlib.Path
    metadata : mapping, optional
        Metadata for a bare DataFrame (an Observations carries its own).

    Returns
    -------
    pathlib.Path
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    if isinstance(obs, Observations):
        df, meta = obs.table, dict(obs.metadata)
    else:
        df, meta = to_frame(obs.to_dict("records")), dict(metadata or {})
    table = pa.Table.from_pandas(df, preserve_index=False)
    kv = dict(table.schema.metadata or {})
    kv[SCHEMA_METADATA_KEY.encode()] = json.dumps(load_schema(SCHEMA)).encode()
    kv[METADATA_KEY.encode()] = json.dumps(_json_safe(meta), allow_nan=False).encode()
    table = table.replace_schema_metadata(kv)
    out = Path(path)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    try:
        pq.write_table(table, tmp)
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    return out


def read_observations(path: str | Path) -> pd.DataFrame:
    """Read an observations table; its metadata is in ``df.attrs["rigtools"]``.

    ``df.attrs["schema"]`` holds the schema the file was written with.
    """
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    kv = table.schema.metadata or {}
    df = to_frame(table.to_pandas().to_dict("records"))
    if METADATA_KEY.encode() in kv:
        df.attrs["rigtools"] = json.loads(kv[METADATA_KEY.encode()])
    if SCHEMA_METADATA_KEY.encode() in kv:
        df.attrs["schema"] = json.loads(kv[SCHEMA_METADATA_KEY.encode()])
    return df


def _json_safe(obj: Any) -> Any:
    if isinstance(obj, float | np.floating):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, Mapping):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if obj is pd.NA or obj is pd.NaT:
        return None
    return obj


def _cell(v: Any) -> Any:
    if v is None or v is pd.NA:
        return None
    if isinstance(v, float | np.floating):
        return None if not math.isfinite(float(v)) else float(v)
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def validate_observations(df: pd.DataFrame) -> list[tuple[str, str]]:
    """Check a table against ``data_schemas/observations.schema.json``.

    Returns
    -------
    list of (str, str)
        ``(json_path, message)`` per violation (``$[3].f_n_Hz``: row 3), best first; empty when
        valid. NaN counts as null.
    """
    cols = list(observation_columns())
    extra = [c for c in df.columns if c not in cols]
    rows = [{c: _cell(v) for c, v in rec.items()}
            for rec in df.astype(object).to_dict("records")]
    errors = iter_errors(rows, SCHEMA)
    if extra:
        errors.insert(0, ("$", f"columns not in the schema: {extra}"))
    return errors
