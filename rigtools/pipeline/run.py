"""``run_campaign``: recordings to a report, cached, resumable and spread over workers.

::

    from rigtools.pipeline import run_campaign

    result = run_campaign("campaign.toml", "out", jobs=2)
    result.summary["parameters"]["backlash"]        # calibration/summary.json
    [r.error for r in result.failed_runs]           # runs that could not be read, and why

OUTDIR (issue 19 contract)::

    pipeline.json                  runs, stems, keys, stage times, settings, versions
    ingest/<stem>.parquet, .json   normalized recording, what ingest found
    observe/<stem>.parquet, .json  the run's rows of the table (the observe cache)
    spectra/<stem>.parquet         the Welch spectra the peaks were found on
    observations.parquet           the observations table of the campaign
    calibration/                   summary.json, summary.csv, posterior.nc, chains.h5, PNGs
    calibration/runup/             the SDOF run-up calibration: <model>/posterior.nc and
                                   summary.json, comparison.json/.csv, runup_<stem>.png
    demo_truth.json                the demo's truth (with ``truth``)
    report.json, report.html       rigtools.report

Caching (:mod:`~rigtools.pipeline.cache`): every per-run output and the calibration carry a
key (SHA-256 of the input file, the settings that shape the output, the keys of the outputs it
reads, the rigtools version) written after the output; a re-run with nothing changed reuses
everything, and a changed recording is ingested and observed again alone (then the
calibration and the report follow). Every write is atomic (:mod:`~rigtools.pipeline.atomic`):
a run killed at any point and started again ends with the numbers of an uninterrupted run
(the calibration resumes from its ``chains.h5`` checkpoint).

A recording that cannot be read or analysed is a failed run, listed with why; the other runs
go on. When every run fails, the table, ``pipeline.json`` and the report are still written
(the calibration is skipped). A calibration that cannot be done
(:class:`~rigtools.calibration.CalibrationError`) is a failed stage, recorded with its error.
"""

from __future__ import annotations

import hashlib
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rigtools.calibration import campaign_config
from rigtools.campaign import Campaign, load_campaign
from rigtools.pipeline.atomic import atomic_write_bytes, atomic_write_json, remove_stale_temporaries
from rigtools.pipeline.cache import file_sha256
from rigtools.pipeline.errors import PipelineError
from rigtools.pipeline.executor import OnDemand
from rigtools.pipeline.progress import Progress
from rigtools.pipeline.result import (
    PIPELINE_FILE,
    STAGES,
    PipelineResult,
    RunStatus,
    pipeline_document,
)
from rigtools.pipeline.run_tasks import (
    INGEST_DIR,
    OBSERVE_DIR,
    SPECTRA_DIR,
    IngestOutcome,
    ObserveOutcome,
    RunTask,
    observe_key,
)
from rigtools.pipeline.stages import (
    CALIBRATION_DIR,
    CalibrateOutcome,
    calibrate_stage,
    ingest_stage,
    library_versions,
    observe_stage,
    report_stage,
    write_observations_table,
)
from rigtools.pipeline.stems import run_file_stem

__all__ = ["DEMO_TRUTH_FILE", "run_campaign"]

#: The demo's truth, copied into OUTDIR.
DEMO_TRUTH_FILE = "demo_truth.json"


def _stages(stages: Sequence[str]) -> tuple[str, ...]:
    got = tuple(stages)
    if not got or got != STAGES[:len(got)]:
        raise PipelineError(f"`stages` must be the first stages of {STAGES} in order, "
                            f"was {got!r}")
    return got


def _prepare_outdir(out: Path) -> None:
    if out.exists() and not out.is_dir():
        raise PipelineError(f"{out}: expected a folder, found a file")
    base = out
    while not base.exists():
        base = base.parent
    if not base.is_dir():
        raise PipelineError(f"{out}: cannot create the folder: {base} is a file")
    if not os.access(base, os.W_OK | os.X_OK):
        raise PipelineError(f"{out}: cannot create or fill the folder: {base} is not writable")
    out.mkdir(parents=True, exist_ok=True)
    for sub in (INGEST_DIR, OBSERVE_DIR, SPECTRA_DIR):
        (out / sub).mkdir(exist_ok=True)
    for folder in (out, out / INGEST_DIR, out / OBSERVE_DIR, out / SPECTRA_DIR,
                   out / CALIBRATION_DIR):
        remove_stale_temporaries(folder)


class _FileHashes:
    """SHA-256 of the layout files (DBC, mapping, gear set), each hashed once."""

    def __init__(self) -> None:
        self._seen: dict[str, str | None] = {}

    def of(self, path: Path | str | None) -> dict[str, Any] | None:
        if path is None:
            return None
        p = str(path)
        if p not in self._seen:
            self._seen[p] = file_sha256(p) if Path(p).is_file() else None
        return {"path": p, "sha256": self._seen[p]}


def _tasks(campaign: Campaign, out: Path) -> list[RunTask]:
    hashes = _FileHashes()
    d = campaign.to_dict()
    shared = {k: v for k, v in d.items() if k not in ("path", "run", "report")}
    shared["gear_set_file"] = hashes.of(campaign.gear_set_path)
    tasks = []
    for run, entry in zip(campaign.runs, d["run"], strict=True):
        s = campaign.sensors_for(run)
        ingest_parts = {
            "file": str(run.file), "dbc": hashes.of(s.dbc), "map": hashes.of(s.mapping),
            "format": s.format,
            "metadata": {"run_id": run.id, "rig": campaign.rig or None,
                         "gear_set": campaign.gear_set_for(run.id),
                         "conditions": run.numeric_conditions()}}
        observe_parts: dict[str, Any] = {"run": entry, "campaign": shared}
        if run.gear_set_path is not None:   # a run on its own pair: that file's contents too
            observe_parts["run_gear_set_file"] = hashes.of(run.gear_set_path)
        tasks.append(RunTask(campaign=campaign, run=run, outdir=str(out),
                             stem=run_file_stem(run.id), ingest_parts=ingest_parts,
                             observe_parts=observe_parts))
    return tasks


def _run_status(task: RunTask, ing: IngestOutcome, obs: ObserveOutcome | None) -> RunStatus:
    okey = obs.key if obs is not None else observe_key(task, ing.key)
    if ing.status == "failed":
        return RunStatus(task.run.id, task.stem, task.run.file_as_written, ing.source_sha256,
                         "failed", ing.error, "ingest", ing.key, okey)
    if obs is not None and obs.status == "failed":
        return RunStatus(task.run.id, task.stem, task.run.file_as_written, ing.source_sha256,
                         "failed", obs.error, "observe", ing.key, okey)
    return RunStatus(task.run.id, task.stem, task.run.file_as_written, ing.source_sha256,
                     "ok", None, None, ing.key, okey)


def _reuse(outcomes: Sequence[IngestOutcome | ObserveOutcome | None], key: str,
           elapsed: float) -> dict[str, Any]:
    done = [o for o in outcomes if o is not None]
    return {"key": key, "elapsed_s": elapsed, "reused": sum(o.reused for o in done),
            "computed": sum(not o.reused for o in done)}


def _combined_key(keys: Sequence[str]) -> str:
    return hashlib.sha256("\n".join(keys).encode("ascii")).hexdigest()


def run_campaign(campaign: Campaign | str | Path, outdir: str | Path, *, jobs: int = 1,
                 dask: str | None = None, progress: bool | None = None,
                 seed: int | None = None, truth: str | Path | None = None,
                 stages: Sequence[str] = STAGES) -> PipelineResult:
    """Run a campaign from its recordings to the report (module notes).

    Parameters
    ----------
    campaign : Campaign, str or pathlib.Path
        The loaded campaign or its file (TOML).
    outdir : str or pathlib.Path
        OUTDIR: created when absent; the cache of an earlier run in it is reused.
    jobs : int
        Processes for ingest and observe (1: in this process).
    dask : str, optional
        ``"local"`` (a cluster in this process) or a dask scheduler's address: ingest and
        observe of each run go there (takes precedence over ``jobs``).
    progress : bool, optional
        tqdm bars (True), log lines (False), or bars when stderr is a terminal (None).
    seed : int, optional
        The calibration's seed (default: the ``[calibration]`` block's).
    truth : str or pathlib.Path, optional
        A demo campaign's ``truth.json``, copied to ``demo_truth.json`` for the report.
    stages : sequence of str
        The first stages to run: ``("ingest",)`` up to all four (the default).

    Returns
    -------
    PipelineResult

    Raises
    ------
    CampaignError
        The campaign file is malformed (its ``[calibration]`` block included: checked before
        any work).
    PipelineError
        OUTDIR is a file or cannot be written; ``stages`` out of order.
    ValueError
        ``jobs`` below 1 or an empty ``dask``.
    OSError
        An output cannot be written (a full disk): the error names the file, and no file is
        left half-written under its final name.
    """
    todo = _stages(stages)
    executor = OnDemand(jobs, dask)  # checks the settings before any work
    camp = campaign if isinstance(campaign, Campaign) else load_campaign(campaign)
    if "calibrate" in todo:
        campaign_config(camp)  # a wrong [calibration] block fails before any work
    out = Path(outdir)
    _prepare_outdir(out)
    prog = Progress(progress)
    if truth is not None:
        atomic_write_bytes(out / DEMO_TRUTH_FILE, Path(truth).read_bytes())
    tasks = _tasks(camp, out)
    times: dict[str, float] = {}
    prog.info("%d run(s) of %r, %s, into %s", len(tasks), camp.name, executor.description,
              out)
    try:
        t0 = time.perf_counter()
        ingested = ingest_stage(tasks, executor, prog)
        times["ingest"] = time.perf_counter() - t0
        observed: list[ObserveOutcome | None] = [None] * len(tasks)
        if "observe" in todo:
            t0 = time.perf_counter()
            observed = observe_stage(tasks, ingested, executor, prog)
            write_observations_table(camp, out, tasks, ingested, observed)
            times["observe"] = time.perf_counter() - t0
    finally:
        executor.close()
    runs = tuple(_run_status(t, i, o)
                 for t, i, o in zip(tasks, ingested, observed, strict=True))
    any_ok = any(r.status == "ok" for r in runs) and "observe" in todo
    if "calibrate" in todo:
        cal = calibrate_stage(camp, out, seed=seed, progress=prog, run_ok=any_ok)
    else:
        cal = CalibrateOutcome("skipped", "not asked for", "", False, 0.0)
    stage_doc: dict[str, dict[str, Any]] = {
        "ingest": _reuse(ingested, _combined_key([i.key for i in ingested]),
                         times.get("ingest", 0.0)),
        "observe": _reuse(observed, _combined_key([r.observe_key for r in runs]),
                          times.get("observe", 0.0)),
        "calibrate": cal.stage_document(),
        "report": {"elapsed_s": 0.0},
    }
    settings = {"jobs": int(jobs), "dask": dask, "seed": seed}
    campaign_sha = file_sha256(camp.path) if Path(camp.path).is_file() else ""
    versions = library_versions()
    doc_path = out / PIPELINE_FILE
    atomic_write_json(doc_path, pipeline_document(camp, campaign_sha, settings, runs, stage_doc,
                                                  versions))
    report = None
    if "report" in todo:
        report, stage_doc["report"]["elapsed_s"] = report_stage(out, prog)
        atomic_write_json(doc_path, pipeline_document(camp, campaign_sha, settings, runs,
                                                      stage_doc, versions))
    return PipelineResult(outdir=out, runs=runs, stages=stage_doc, summary=cal.summary,
                          report=report, pipeline_json=doc_path, warnings=cal.warnings)
