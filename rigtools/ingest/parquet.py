"""Normalized recordings: one Parquet file, metadata inside, exact round trip.

Layout (contract: ``data_schemas/recording.schema.json``):

* the i-th uniform channel: columns ``ch/<i>/values`` (float64) and ``ch/<i>/valid`` (bool);
* the i-th slow signal: columns ``slow/<i>/time_s`` and ``slow/<i>/value`` (float64);
  (columns are named by position, so no channel name can collide with another's column);
* columns padded with nulls to the longest; the lengths come from the metadata;
* the Parquet key-value metadata ``rigtools.recording`` holds a JSON document with channel
  rates, start times and first indices, run metadata and provenance (with the ingest report).

Values are stored as float64 bit patterns, so NaN and Inf survive and
``read_parquet(write_parquet(rec))`` equals ``rec`` bit for bit. Every data page carries a
CRC32 that is verified on reading, and the metadata document its SHA-256, so a flipped bit is
an error, not a silently wrong value.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any, Final

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from rigtools.errors import RecordingFormatError
from rigtools.ingest.contract import ReadRequest
from rigtools.ingest.recording import Channel, Provenance, Recording, RunMetadata, SlowSignal
from rigtools.schemas import iter_errors

__all__ = ["NAME", "READER", "ParquetReader", "read_parquet", "sniff", "write_parquet"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME = "parquet"
META_KEY = b"rigtools.recording"
DIGEST_KEY = b"rigtools.recording.sha256"


def sniff(head: bytes) -> bool:
    """Parquet magic."""
    return head[:4] == b"PAR1"


def _padded(arr: np.ndarray, n_rows: int, typ: pa.DataType) -> pa.ChunkedArray:
    chunks = [pa.array(arr, type=typ)]
    if n_rows > arr.shape[0]:
        chunks.append(pa.nulls(n_rows - arr.shape[0], typ))
    return pa.chunked_array(chunks, type=typ)


def _clean(obj: Any) -> Any:
    """Drop non-finite floats (not JSON) from dicts so the document stays valid JSON."""
    if isinstance(obj, dict):
        return {
            k: _clean(v)
            for k, v in obj.items()
            if not (isinstance(v, float) and not math.isfinite(v))
        }
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    return obj


def recording_document(rec: Recording) -> dict[str, Any]:
    """The JSON metadata document of a recording."""
    return {
        "format": "rigtools.recording",
        "format_version": 1,
        "channels": [
            {
                "name": c.name,
                "unit": c.unit,
                "sample_rate_Hz": c.sample_rate_Hz,
                "start_time_s": c.start_time_s,
                "first_index": c.first_index,
                "n_samples": len(c),
            }
            for c in rec.channels.values()
        ],
        "slow": [{"name": s.name, "unit": s.unit, "n_samples": len(s)} for s in rec.slow.values()],
        "metadata": rec.metadata.to_dict(),
        "provenance": _clean(rec.provenance.to_dict()),
    }


def write_parquet(rec: Recording, path: str | Path) -> Path:
    """Write a normalized recording.

    Parameters
    ----------
    rec : Recording
    path : str or pathlib.Path
        Output file (conventionally ``.parquet``).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    p = Path(path)
    doc = recording_document(rec)
    errors = iter_errors(doc, "recording.schema.json")
    if errors:  # a bug, not user input: the writer must only write what the schema allows
        raise RecordingFormatError(p, None, "a document valid against recording.schema.json",
                                   f"{errors[0][0]}: {errors[0][1]}")
    n_rows = max([len(c) for c in rec.channels.values()] + [len(s) for s in rec.slow.values()]
                 + [0])
    names: list[str] = []
    cols: list[pa.ChunkedArray] = []
    for i, c in enumerate(rec.channels.values()):
        names += [f"ch/{i}/values", f"ch/{i}/valid"]
        cols += [_padded(c.values, n_rows, pa.float64()), _padded(c.valid, n_rows, pa.bool_())]
    for i, s in enumerate(rec.slow.values()):
        names += [f"slow/{i}/time_s", f"slow/{i}/value"]
        cols += [_padded(s.time_s, n_rows, pa.float64()), _padded(s.values, n_rows, pa.float64())]
    text = json.dumps(doc).encode()
    schema = pa.schema([pa.field(n, c.type) for n, c in zip(names, cols, strict=True)],
                       metadata={META_KEY: text,
                                 DIGEST_KEY: hashlib.sha256(text).hexdigest().encode()})
    table = pa.Table.from_arrays(cols, schema=schema)
    pq.write_table(table, p, compression="zstd", row_group_size=1 << 20,
                   write_page_checksum=True)
    return p


def _column(table: pa.Table, name: str, n: int, path: Path) -> np.ndarray:
    if name not in table.column_names:
        raise RecordingFormatError(path, f"column {name!r}", "the column the metadata lists",
                                   "no such column")
    col = table.column(name)
    if len(col) < n:
        raise RecordingFormatError(path, f"column {name!r}", f"at least {n} rows",
                                   f"{len(col)} rows")
    piece = col.slice(0, n)
    if piece.null_count:
        raise RecordingFormatError(path, f"column {name!r}", f"{n} non-null values",
                                   f"{piece.null_count} nulls")
    return piece.to_numpy()


def read_parquet(path: str | Path) -> Recording:
    """Read a normalized recording written by :func:`write_parquet`.

    Raises
    ------
    RecordingFormatError
        Not Parquet, no ``rigtools.recording`` metadata, metadata not valid against the
        schema, or columns missing or shorter than the metadata says.
    """
    p = Path(path)
    try:
        pf = pq.ParquetFile(p, page_checksum_verification=True)
        meta = pf.schema_arrow.metadata or {}
    except (pa.ArrowException, OSError) as exc:
        raise RecordingFormatError(p, 0, "a Parquet file", str(exc)[:200]) from exc
    if META_KEY not in meta:
        raise RecordingFormatError(p, None, "a rigtools normalized recording",
                                   "Parquet without 'rigtools.recording' metadata")
    if meta.get(DIGEST_KEY) != hashlib.sha256(meta[META_KEY]).hexdigest().encode():
        raise RecordingFormatError(p, "metadata 'rigtools.recording'",
                                   "the SHA-256 stored beside it", "a mismatch (damaged file)")
    try:
        doc = json.loads(meta[META_KEY])
    except ValueError as exc:
        raise RecordingFormatError(p, "metadata 'rigtools.recording'", "JSON", str(exc)) from exc
    errors = iter_errors(doc, "recording.schema.json")
    if errors:
        raise RecordingFormatError(p, f"metadata {errors[0][0]}",
                                   "a document valid against recording.schema.json", errors[0][1])
    try:
        table = pf.read()
    except (pa.ArrowException, OSError) as exc:
        raise RecordingFormatError(p, None, "readable Parquet row groups", str(exc)[:200]) from exc
    channels = {}
    for i, c in enumerate(doc["channels"]):
        n = c["n_samples"]
        channels[c["name"]] = Channel(
            c["name"], c["unit"], float(c["sample_rate_Hz"]), float(c["start_time_s"]),
            int(c["first_index"]),
            _column(table, f"ch/{i}/values", n, p).astype(np.float64, copy=False),
            _column(table, f"ch/{i}/valid", n, p).astype(bool, copy=False),
        )
    slow = {}
    for i, s in enumerate(doc["slow"]):
        n = s["n_samples"]
        slow[s["name"]] = SlowSignal(
            s["name"], s["unit"],
            _column(table, f"slow/{i}/time_s", n, p).astype(np.float64, copy=False),
            _column(table, f"slow/{i}/value", n, p).astype(np.float64, copy=False),
        )
    if len(channels) != len(doc["channels"]) or len(slow) != len(doc["slow"]):
        raise RecordingFormatError(p, "metadata 'rigtools.recording'",
                                   "unique channel and slow-signal names", "repeated names")
    return Recording(channels, slow, RunMetadata.from_dict(doc["metadata"]),
                     Provenance.from_dict(doc["provenance"]))


class ParquetReader:
    """Normalized recordings in the registry: read whole, as they were written.

    The request does not apply: the recording was made by an earlier read, whose DBC,
    mapping, run metadata and provenance it keeps.
    """

    name: Final = NAME

    def __repr__(self) -> str:
        return "ParquetReader()"

    def sniff(self, head: bytes) -> bool:
        """Parquet magic."""
        return sniff(head)

    def read(self, path: Path, request: ReadRequest) -> Recording:
        """:func:`read_parquet` of the file (of ``request`` only ``progress``, once at the end)."""
        rec = read_parquet(path)
        if request.progress is not None:
            size = path.stat().st_size
            request.progress(size, size)
        return rec


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = ParquetReader()
