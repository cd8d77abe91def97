"""``rigtools.ingest.read``: any supported recording file to a :class:`Recording`."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import re
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from rigtools.errors import NoDataError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.can_assembly import assemble_can
from rigtools.ingest.dbc import dbc_digest, load_dbc
from rigtools.ingest.layout import ChannelMapping, can_layout, load_mapping
from rigtools.ingest.recording import IngestReport, Provenance, Recording, RunMetadata
from rigtools.ingest.registry import detect_format, open_source, reader_module, sha256_of
from rigtools.schemas import schema_path

__all__ = ["read", "versions"]

# Condition keys carry their unit (data_schemas/run_metadata.schema.json).
_CONDITION_KEY = re.compile(r"^[a-z][a-z0-9_]*_(Nm|C|K|rpm|Hz|s|m|um|kW|bar|Pa)$")


@functools.cache
def _versions() -> tuple[tuple[str, str], ...]:
    from importlib.metadata import PackageNotFoundError, version

    out = [("python", sys.version.split()[0])]
    for dist in ("rigtools", "numpy", "pyarrow", "mcap", "mcap-ros2-support", "python-can",
                 "cantools", "protobuf"):
        try:
            out.append((dist, version(dist)))
        except PackageNotFoundError:
            out.append((dist, "not installed"))
    return tuple(out)


def versions() -> dict[str, str]:
    """Versions of rigtools, Python and the libraries readers use."""
    return dict(_versions())


def read(
    path: str | Path,
    *,
    dbc: str | Path | None = None,
    mapping: str | Path | ChannelMapping | None = None,
    metadata: RunMetadata | None = None,
    fmt: str | None = None,
    strict_dbc: bool = True,
    mcap_clock: str = "header",
) -> Recording:
    """Read a recording file into a :class:`~rigtools.ingest.recording.Recording`.

    Parameters
    ----------
    path : str or pathlib.Path
        MCAP, BLF, ASC, TRC, candump ``.log``, python-can CSV (any of them gzipped), or a
        normalized recording written by :func:`rigtools.ingest.write_parquet`. The reader is
        chosen by content; the suffix is used only when the content says nothing (see
        :func:`rigtools.ingest.registry.detect_format` for the table).
    dbc : str or pathlib.Path, optional
        DBC for CAN logs. Default: the reference layout ``data_schemas/rig_reference.dbc``.
    mapping : str, pathlib.Path or ChannelMapping, optional
        User mapping of signals or MCAP fields to channels (TOML); replaces the DBC's own
        layout attributes, or the default MCAP decoding.
    metadata : RunMetadata, optional
        Run metadata; overrides what the file or the mapping carries.
    fmt : str, optional
        Force a format by name instead of detecting it.
    strict_dbc : bool
        Refuse DBCs with overlapping or oversized signals (cantools ``strict``).
    mcap_clock : {"header", "log_time"}
        MCAP only: the clock that places a channel whose messages carry a header stamp
        (Imu channels, mapped fields). ``"header"`` (default): the header stamp (the log time
        where a message has none, or where every Imu header stamp is zero); ``"log_time"``:
        the MCAP log time. The other clock is kept in the report as a second clock of the
        channel: ``recording.report.timebase[f"{channel}@log_time"]`` (or ``@header``) holds
        its statistics, its ``start_time_s`` and ``offset_s``, its median offset from the
        clock that placed the channel (s). Slow signals (topic scalars, log time only) are
        unaffected except mapped slow fields, timed by the chosen clock.

    Returns
    -------
    Recording
        Channels, slow signals, metadata and provenance; ``recording.report`` tallies what
        was decoded, rejected (by reason) and the gaps found.

    Raises
    ------
    RecordingFormatError
        The file is empty, unreadable, or damaged so that nothing intact can be returned.
    UnsupportedFormatError
        Neither content nor suffix names a supported format.
    DbcError, MappingError
        The DBC or the mapping does not load or does not match the file.
    ValueError
        ``mcap_clock`` is neither ``"header"`` nor ``"log_time"``.
    NoDataError
        The file reads but holds no decodable channel or slow signal.
    """
    if mcap_clock not in ("header", "log_time"):
        raise ValueError(f"mcap_clock must be 'header' or 'log_time', not {mcap_clock!r}")
    p = Path(path)
    kind = detect_format(p, fmt)
    module = reader_module(kind)
    if kind == "parquet":
        return module.read_parquet(p)
    # The hash runs in a second thread (hashlib releases the GIL): beside the reader for CAN
    # logs; for MCAP, whose reader keeps a decompression worker busy on the second core,
    # beside the building of the channels instead.
    hasher = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rigtools-sha256")
    try:
        return _read_with(p, kind, module, dbc, mapping, metadata, strict_dbc, hasher,
                          mcap_clock)
    finally:
        hasher.shutdown(wait=False)  # after a refusal, let the hash finish on its own


def _read_with(
    p: Path,
    kind: str,
    module: Any,
    dbc: str | Path | None,
    mapping: str | Path | ChannelMapping | None,
    metadata: RunMetadata | None,
    strict_dbc: bool,
    hasher: ThreadPoolExecutor,
    mcap_clock: str = "header",
) -> Recording:
    hashing = None if kind == "mcap" else hasher.submit(sha256_of, p)
    if isinstance(mapping, str | Path):
        mapping = load_mapping(mapping)
    report = IngestReport(units="messages" if kind == "mcap" else "frames")
    builder = RecordingBuilder(str(p), report)
    layout_desc: dict[str, Any]
    extra: dict[str, str] = {}
    with open_source(p, report) as stream:
        if module.KIND == "can":
            dbc_file = Path(dbc) if dbc is not None else schema_path("rig_reference.dbc")
            db = load_dbc(dbc_file, strict=strict_dbc)
            layout = can_layout(db, mapping, str(dbc_file))
            layout_desc = dict(layout.description)
            layout_desc["dbc_sha256"] = dbc_digest(dbc_file)
            assemble_can(module.iter_batches(stream, str(p), report), layout, builder, report)
        else:
            extra = module.ingest(stream, str(p), builder, report, mapping, clock=mcap_clock)
            layout_desc = {"source": "mapping" if mapping else "mcap-schemas"}
            if mapping is not None:
                layout_desc["mapping"] = mapping.to_dict()
    meta = _merge_metadata(extra, mapping, metadata, report)
    # Through JSON once, so the layout compares equal after a Parquet round trip.
    layout_desc = json.loads(json.dumps(layout_desc))
    if hashing is None:
        hashing = hasher.submit(sha256_of, p)
    placeholder = Provenance(str(p), "", 0, kind, versions(), report, layout_desc)
    rec = builder.build(meta, placeholder)
    digest, size = hashing.result()
    rec = dataclasses.replace(rec, provenance=dataclasses.replace(
        placeholder, source_sha256=digest, source_size_bytes=size))
    if not rec.channels and not rec.slow:
        reasons = ", ".join(f"{k}: {v}" for k, v in sorted(report.rejected.items())) or "none"
        raise NoDataError(
            p, None, "at least one decodable channel or slow signal",
            f"none ({report.decoded} {report.units} decoded; rejected {reasons})",
        )
    return rec


def _merge_metadata(
    extra: dict[str, str],
    mapping: ChannelMapping | None,
    given: RunMetadata | None,
    report: IngestReport,
) -> RunMetadata:
    if given is not None:
        return given
    if mapping is not None and mapping.run is not None:
        return mapping.run
    conditions: dict[str, float] = {}
    rest: dict[str, str] = {}
    for k, v in extra.items():
        if k.startswith("conditions."):
            name = k.removeprefix("conditions.")
            try:
                value = float(v)
            except ValueError:
                value = math.nan
            if _CONDITION_KEY.match(name) and math.isfinite(value):
                conditions[name] = value
            else:  # kept, but not as a condition: no unit in the key, or not a number
                rest[k] = str(v)
                report.warn(f"run metadata {k!r} = {v!r} is not a condition (a finite number "
                            "under a key ending in its unit, e.g. torque_Nm); kept as text")
        elif k not in ("run_id", "rig", "gear_set"):
            rest[k] = v
    return RunMetadata(extra.get("run_id"), extra.get("rig"), extra.get("gear_set"), conditions,
                       rest)
