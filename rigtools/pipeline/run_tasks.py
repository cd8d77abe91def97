"""The work on one run: ingest it, observe it; cached, atomic, and safe to send to a worker.

Runs are independent until calibration, so their ingest and observe go to whatever executor
the pipeline uses (:mod:`rigtools.pipeline.executor`: in process, a process pool, a dask
cluster). The functions here are top-level and take and return frozen dataclasses, so they
pickle; they import the reading and the signal analysis only (no calibration, no figures), so
a fresh worker starts quickly. Each writes its files itself (a dask cluster needs OUTDIR on a
file system every worker sees) through :mod:`rigtools.pipeline.atomic`, and its key last
(:mod:`rigtools.pipeline.cache`).

Files of a run (``<stem>`` is :func:`~rigtools.pipeline.stems.run_file_stem`):

``ingest/<stem>.parquet``
    The normalized recording (:func:`rigtools.ingest.write_parquet`).
``ingest/<stem>.json``
    What ingest found (:func:`ingest_document`; a failed run has one too, saying why).
``ingest/<stem>.key``
    The ingest key (source SHA-256, the run's sensors and layout files, rigtools version).
``observe/<stem>.parquet``, ``observe/<stem>.json``
    The run's rows of the observations table, and whether it was analysed, its error and
    warnings.
``spectra/<stem>.parquet``
    The Welch spectra the peaks were found on, long format (:func:`write_spectra`).
``observe/<stem>.key``
    The observe key (the ingest key, the run's entry and the campaign's analysis settings).

A recording that cannot be read or analysed (missing, damaged, no channel) is a failed run
(``status = "failed"`` and the reason); an error *writing* (a full disk) is raised.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from rigtools import __version__
from rigtools.campaign import (
    Campaign,
    CampaignRun,
    RunObservations,
    observe_recording,
    read_observations,
    read_run,
    to_frame,
    write_observations,
)
from rigtools.errors import RigtoolsError
from rigtools.ingest import Recording, read_parquet, write_parquet
from rigtools.pipeline.atomic import atomic_output, atomic_write_json
from rigtools.pipeline.cache import (
    file_sha256,
    invalidate,
    is_current,
    stage_key,
    write_key,
)

__all__ = [
    "INGEST_DIR",
    "MAX_GAPS_LISTED",
    "OBSERVE_DIR",
    "SPECTRA_DIR",
    "IngestOutcome",
    "ObserveOutcome",
    "RunTask",
    "cached_ingest",
    "cached_observe",
    "failed_run_rows",
    "ingest_document",
    "ingest_run",
    "observe_key",
    "observe_run_task",
    "read_run_rows",
    "write_spectra",
]

INGEST_DIR: Final = "ingest"
OBSERVE_DIR: Final = "observe"
SPECTRA_DIR: Final = "spectra"
#: Gaps listed in ``ingest/<stem>.json`` (all are counted).
MAX_GAPS_LISTED: Final = 50
#: Parquet key-value metadata key of a spectra file.
SPECTRA_METADATA_KEY: Final = "rigtools"
#: Errors that make a run fail (bad input), as opposed to errors of the pipeline.
_INPUT_ERRORS: Final = (RigtoolsError, OSError, ValueError)


@dataclass(frozen=True)
class RunTask:
    """One run to ingest and observe.

    Attributes
    ----------
    campaign : Campaign
    run : CampaignRun
    outdir : str
        OUTDIR (the per-run files go to its ``ingest/``, ``observe/`` and ``spectra/``).
    stem : str
        The run's file stem.
    ingest_parts : dict
        What the ingest key hashes besides the source file's SHA-256 (JSON-ready).
    observe_parts : dict
        What the observe key hashes besides the ingest key.
    """

    campaign: Campaign
    run: CampaignRun
    outdir: str
    stem: str
    ingest_parts: dict[str, Any]
    observe_parts: dict[str, Any]


@dataclass(frozen=True)
class IngestOutcome:
    """What ingest did with a run.

    Attributes
    ----------
    run_id, stem : str
    status : {'ok', 'failed'}
    error : str or None
        Why the run could not be read.
    source_sha256 : str or None
        None when the file could not be read.
    key : str
        The ingest key.
    reused : bool
        The cached output was current and kept.
    size_bytes : int
        Size of the recording (0 when absent), for the progress in bytes.
    elapsed_s : float
    """

    run_id: str
    stem: str
    status: Literal["ok", "failed"]
    error: str | None
    source_sha256: str | None
    key: str
    reused: bool
    size_bytes: int
    elapsed_s: float


@dataclass(frozen=True)
class ObserveOutcome:
    """What observe did with a run.

    Attributes
    ----------
    run_id, stem : str
    status : {'ok', 'failed'}
        ``"failed"`` when no channel could be analysed.
    error : str or None
    key : str
        The observe key.
    reused : bool
    elapsed_s : float
    """

    run_id: str
    stem: str
    status: Literal["ok", "failed"]
    error: str | None
    key: str
    reused: bool
    elapsed_s: float


# --------------------------------------------------------------------------------------------
# ingest


def _paths(task: RunTask, folder: str) -> tuple[Path, Path, Path]:
    base = Path(task.outdir) / folder
    return (base / f"{task.stem}.parquet", base / f"{task.stem}.json",
            base / f"{task.stem}.key")


def _reason(exc: BaseException) -> str:
    if isinstance(exc, RigtoolsError):
        return str(exc)
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return f"{where}{exc.strerror or exc}"
    if isinstance(exc, ValueError):
        return str(exc)
    return (f"internal error {type(exc).__name__}: {exc} (rerun with --debug for a "
            "traceback, and please report it)")


def ingest_document(run: CampaignRun, rec: Recording | None, *, source_sha256: str | None,
                    error: str | None, elapsed_s: float) -> dict[str, Any]:
    """``ingest/<stem>.json``: what ingest found in a run's recording (issue 19 contract).

    Parameters
    ----------
    run : CampaignRun
    rec : Recording or None
        None when the run could not be read.
    source_sha256 : str or None
    error : str or None
        Why the run failed.
    elapsed_s : float
        Time to read and write it (s); volatile.

    Returns
    -------
    dict
        JSON-ready.
    """
    doc: dict[str, Any] = {
        "run_id": run.id, "file": run.file_as_written, "path": str(Path(run.file).resolve()),
        "source_sha256": source_sha256, "reader": None, "format": None,
        "status": "failed" if rec is None else "ok", "error": error, "units": "frames",
        "n_decoded": 0, "n_rejected": 0, "rejected": {}, "n_gaps": 0,
        "n_missing_samples": 0, "gaps": [], "gaps_truncated": False, "warnings": [],
        "channels": {}, "slow_signals": [], "duration_s": None, "elapsed_s": elapsed_s,
    }
    if rec is None:
        return doc
    rep = rec.report
    prov = rec.provenance
    doc.update(
        source_sha256=prov.source_sha256, reader=prov.reader,
        format=prov.reader,  # readers are registered by format name (ingest.registry)
        units=rep.units, n_decoded=int(rep.decoded), n_rejected=int(rep.n_rejected),
        rejected={str(k): int(v) for k, v in sorted(rep.rejected.items())},
        n_gaps=len(rep.gaps), n_missing_samples=int(sum(g.n_missing for g in rep.gaps)),
        gaps=[{"channel": g.channel, "start_s": _finite(g.time_s), "n_missing": int(g.n_missing)}
              for g in rep.gaps[:MAX_GAPS_LISTED]],
        gaps_truncated=len(rep.gaps) > MAX_GAPS_LISTED, warnings=[str(w) for w in rep.warnings],
        channels={c.name: {"unit": c.unit, "n_samples": len(c),
                           "sample_rate_Hz": _finite(c.sample_rate_Hz)}
                  for c in rec.channels.values()},
        slow_signals=list(rec.slow), duration_s=_finite(rec.duration_s))
    return doc


def _finite(v: Any) -> float | None:
    f = float(v)
    return f if math.isfinite(f) else None


def _source(task: RunTask) -> tuple[str | None, int, str]:
    """SHA-256 and size of the run's recording (None, 0 when unreadable) and the ingest key."""
    try:
        sha: str | None = file_sha256(task.run.file)
        size = Path(task.run.file).stat().st_size
    except OSError:
        sha, size = None, 0
    return sha, size, stage_key("ingest", {**task.ingest_parts, "source_sha256": sha})


def cached_ingest(task: RunTask) -> IngestOutcome | None:
    """The run's ingest output when its key is current (reused), else None.

    Cheap (the recording is hashed, not read): the pipeline asks in its own process and sends
    only the runs that need work to the executor.
    """
    t0 = time.perf_counter()
    parquet, summary, key_file = _paths(task, INGEST_DIR)
    sha, size, key = _source(task)
    if not is_current(key_file, key, (summary,)):
        return None
    doc = json.loads(summary.read_text(encoding="utf-8"))
    if doc.get("status") == "ok" and not parquet.is_file():
        return None
    return IngestOutcome(task.run.id, task.stem, doc.get("status", "failed"), doc.get("error"),
                         sha, key, True, size, time.perf_counter() - t0)


def ingest_run(task: RunTask) -> IngestOutcome:
    """Ingest one run: read it with its sensors and write the normalized recording.

    Reuses ``ingest/<stem>.parquet`` when its key is current. Otherwise the key is removed
    first, the recording read (:func:`rigtools.campaign.read_run`) and written, the summary
    written, and the key written last.

    Parameters
    ----------
    task : RunTask

    Returns
    -------
    IngestOutcome
        A run that cannot be read is ``"failed"`` with the reason (the summary says so too).

    Raises
    ------
    OSError
        An output cannot be written (names the file).
    """
    t0 = time.perf_counter()
    cached = cached_ingest(task)
    if cached is not None:
        return cached
    parquet, summary, key_file = _paths(task, INGEST_DIR)
    run = task.run
    sha, size, key = _source(task)
    invalidate(key_file)
    parquet.parent.mkdir(parents=True, exist_ok=True)
    rec: Recording | None
    error: str | None = None
    internal = False
    try:
        rec = read_run(task.campaign, run)
    except Exception as exc:  # any failure of this run's input fails this run only
        rec = None
        error = _reason(exc)
        # a bug, not the input: recorded, but not cached, so the next run tries again
        internal = not isinstance(exc, _INPUT_ERRORS)
        if str(run.file_as_written) not in error and str(run.file) not in error:
            error = f"{run.file_as_written}: {error}"
    if rec is not None:
        with atomic_output(parquet) as tmp:
            write_parquet(rec, tmp)
    else:
        parquet.unlink(missing_ok=True)
    doc = ingest_document(run, rec, source_sha256=sha, error=error,
                          elapsed_s=time.perf_counter() - t0)
    atomic_write_json(summary, doc)
    if not internal:
        write_key(key_file, key)
    return IngestOutcome(run.id, task.stem, "ok" if rec is not None else "failed", error, sha,
                         key, False, size, time.perf_counter() - t0)


# --------------------------------------------------------------------------------------------
# observe


def write_spectra(path: Path, obs: RunObservations, *, nperseg: int) -> Path:
    """``spectra/<stem>.parquet``: a run's Welch spectra in long format, atomically.

    Columns ``channel`` (string), ``frequency_Hz`` and ``psd`` (float64, the channel's unit
    squared per Hz); key-value metadata ``rigtools``: JSON ``{"run_id", "units": {channel:
    psd unit}, "response": {channel: SDOF response fitted or null}, "nperseg"}``.

    Parameters
    ----------
    path : pathlib.Path
    obs : RunObservations
        The run's observations (``spectra``: channel -> (frequency_Hz, psd, psd unit)).
    nperseg : int
        Welch segment length used (samples).
    """
    names: list[str] = []
    freqs: list[np.ndarray] = []
    psds: list[np.ndarray] = []
    units: dict[str, str] = {}
    for ch, (f, p, unit) in obs.spectra.items():
        f = np.asarray(f, np.float64)
        p = np.asarray(p, np.float64)
        names += [ch] * f.size
        freqs.append(f)
        psds.append(p)
        units[ch] = str(unit)
    response: dict[str, str | None] = {ch: None for ch in units}
    for row in obs.rows:
        name, resp = row.get("channel"), row.get("response")
        if (isinstance(name, str) and name in response and response[name] is None
                and isinstance(resp, str) and resp):
            response[name] = resp
    meta = {"run_id": obs.run_id, "units": units, "response": response, "nperseg": int(nperseg)}
    empty = np.zeros(0, np.float64)
    table = pa.table({
        "channel": pa.array(names, pa.string()),
        "frequency_Hz": pa.array(np.concatenate(freqs) if freqs else empty, pa.float64()),
        "psd": pa.array(np.concatenate(psds) if psds else empty, pa.float64())})
    table = table.replace_schema_metadata(
        {SPECTRA_METADATA_KEY: json.dumps(meta, allow_nan=False)})
    with atomic_output(path) as tmp:
        pq.write_table(table, tmp, compression="zstd")
    return path


def failed_run_rows(campaign: Campaign, run: CampaignRun, message: str,
                    source_sha256: str | None = None) -> list[dict[str, Any]]:
    """The one failed ``run`` row of a run that could not be read (observations table).

    Parameters
    ----------
    campaign : Campaign
    run : CampaignRun
    message : str
        Why, naming the file.
    source_sha256 : str or None

    Returns
    -------
    list of dict
        One row (the columns of ``data_schemas/observations.schema.json`` it fills).
    """
    return [{
        "campaign": campaign.name, "run_id": run.id, "source_file": run.file_as_written,
        "source_sha256": source_sha256, "rigtools_version": __version__,
        **run.numeric_conditions(), "quantity": "run", "status": "failed", "message": message,
        "quality_flags": "run_failed", "flag_gaps": False, "flag_clipping": False,
        "flag_windows_dropped": False}]


def _observations_of(task: RunTask, rec: Recording | None, error: str | None
                     ) -> RunObservations:
    if rec is None:
        msg = error or "not ingested"
        return RunObservations(task.run.id, str(task.run.file),
                               tuple(failed_run_rows(task.campaign, task.run, msg)),
                               analysed=False, error=msg)
    try:
        return observe_recording(task.campaign, task.run, rec)
    except Exception as exc:  # observe_recording records bad runs; anything left fails the run
        msg = _reason(exc)
        return RunObservations(task.run.id, str(task.run.file),
                               tuple(failed_run_rows(task.campaign, task.run, msg,
                                                     rec.provenance.source_sha256)),
                               analysed=False, error=msg)


def observe_key(task: RunTask, ingest_key: str) -> str:
    """The observe key of a run: its ingest key, its entry and the analysis settings."""
    return stage_key("observe", {**task.observe_parts, "ingest_key": ingest_key})


def cached_observe(task: RunTask, ingest_key: str) -> ObserveOutcome | None:
    """The run's observe outputs when their key is current (reused), else None."""
    t0 = time.perf_counter()
    rows_file, doc_file, key_file = _paths(task, OBSERVE_DIR)
    spectra = Path(task.outdir) / SPECTRA_DIR / f"{task.stem}.parquet"
    key = observe_key(task, ingest_key)
    if not is_current(key_file, key, (rows_file, spectra, doc_file)):
        return None
    doc = json.loads(doc_file.read_text(encoding="utf-8"))
    return ObserveOutcome(task.run.id, task.stem, "ok" if doc["analysed"] else "failed",
                          doc.get("error"), key, True, time.perf_counter() - t0)


def observe_run_task(task: RunTask, ingest_key: str) -> ObserveOutcome:
    """Observe one ingested run: its rows of the observations table and its spectra.

    Reads ``ingest/<stem>.parquet`` (:func:`rigtools.ingest.read_parquet`) and analyses it
    (:func:`rigtools.campaign.observe_recording`); reuses the outputs when the key is current.

    Parameters
    ----------
    task : RunTask
    ingest_key : str
        The key of the run's ingest output (the observe key depends on it).

    Returns
    -------
    ObserveOutcome

    Raises
    ------
    OSError
        An output cannot be written (names the file).
    """
    t0 = time.perf_counter()
    cached = cached_observe(task, ingest_key)
    if cached is not None:
        return cached
    rows_file, doc_file, key_file = _paths(task, OBSERVE_DIR)
    spectra = Path(task.outdir) / SPECTRA_DIR / f"{task.stem}.parquet"
    key = observe_key(task, ingest_key)
    invalidate(key_file)
    rows_file.parent.mkdir(parents=True, exist_ok=True)
    spectra.parent.mkdir(parents=True, exist_ok=True)
    try:
        rec: Recording | None = read_parquet(Path(task.outdir) / INGEST_DIR
                                             / f"{task.stem}.parquet")
        error = None
    except _INPUT_ERRORS as exc:
        rec, error = None, f"ingest output unreadable: {_reason(exc)}"
    obs = _observations_of(task, rec, error)
    with atomic_output(rows_file) as tmp:
        write_observations(to_frame(obs.rows), tmp, metadata={"run_id": obs.run_id})
    write_spectra(spectra, obs, nperseg=task.campaign.analysis.nperseg)
    atomic_write_json(doc_file, {"run_id": obs.run_id, "file": obs.file,
                                 "analysed": obs.analysed, "error": obs.error,
                                 "warnings": list(obs.warnings)})
    write_key(key_file, key)
    return ObserveOutcome(task.run.id, task.stem, "ok" if obs.analysed else "failed",
                          obs.error, key, False, time.perf_counter() - t0)


def read_run_rows(outdir: str | Path, stem: str) -> tuple[pd.DataFrame, dict[str, Any]]:
    """A run's rows of the observations table and its ``observe/<stem>.json``, read back.

    Parameters
    ----------
    outdir : str or pathlib.Path
    stem : str

    Returns
    -------
    (pandas.DataFrame, dict)
    """
    base = Path(outdir) / OBSERVE_DIR
    rows = read_observations(base / f"{stem}.parquet")
    doc = json.loads((base / f"{stem}.json").read_text(encoding="utf-8"))
    return rows, doc
