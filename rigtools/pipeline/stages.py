"""The four stages of ``rigtools run``: ingest, observe, calibrate, report.

Each stage reads the files the stage before wrote into OUTDIR and writes its own
(:mod:`rigtools.pipeline.run_tasks` for the per-run files):

:func:`ingest_stage`
    Every run through :func:`~rigtools.pipeline.run_tasks.ingest_run` on the executor;
    progress in bytes of the recordings.
:func:`observe_stage`
    Every run that was read through :func:`~rigtools.pipeline.run_tasks.observe_run_task`;
    progress per run.
:func:`write_observations_table`
    ``observations.parquet`` from the per-run rows read back from disk (so a cold run and a
    re-run build it from the same bytes), failed runs included as failed ``run`` rows.
:func:`calibrate_stage`
    :func:`rigtools.calibration.calibrate` of the table with ``OUTDIR/calibration`` as its
    folder (its ``chains.h5`` checkpoint resumes a killed run bit for bit), then
    :func:`rigtools.calibration.write_outputs` and
    :func:`rigtools.plots.calibration.calibration_figures` into a staging folder whose files
    are moved into place one by one, then ``calibration/summary.key``. A
    :class:`~rigtools.calibration.CalibrationError` (no usable run, priors that exclude the
    data; or a :class:`models.errors.ModelError` of the physics) is a failed stage, not a
    crash. Then the run-up part (:func:`rigtools.pipeline.runup_stage.runup_part`: the SDOF
    models against the Arms run-ups when ``[calibration] models`` is not empty and the table
    has run-ups), under its own key in ``calibration/runup``; it fails alone
    (:attr:`CalibrateOutcome.runup`), whatever the natural-frequency part did.
:func:`report_stage`
    :func:`rigtools.report.build_report` of OUTDIR.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import logging
import os
import platform
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Final

from models.errors import ModelError
from rigtools.calibration import (
    CalibrationError,
    calibrate,
    campaign_config,
    write_outputs,
)
from rigtools.campaign import (
    Campaign,
    Observations,
    read_observations,
    to_frame,
    write_observations,
)
from rigtools.campaign.observe import observations_metadata
from rigtools.pipeline.atomic import atomic_output, fsync_folder
from rigtools.pipeline.cache import file_sha256, invalidate, is_current, key_path, stage_key
from rigtools.pipeline.cache import write_key as write_stage_key
from rigtools.pipeline.executor import RunExecutor
from rigtools.pipeline.progress import Progress
from rigtools.pipeline.run_tasks import (
    IngestOutcome,
    ObserveOutcome,
    RunTask,
    cached_ingest,
    cached_observe,
    failed_run_rows,
    ingest_run,
    observe_run_task,
    read_run_rows,
)
from rigtools.pipeline.runup_stage import (
    PartOutcome,
    RunUpOutcome,
    clear_runup_outputs,
    run_gear_sets,
    runup_part,
)
from rigtools.plots.calibration import calibration_figures
from rigtools.report import build_report

__all__ = [
    "CALIBRATION_DIR",
    "CALIBRATION_FILES",
    "OBSERVATIONS_FILE",
    "CalibrateOutcome",
    "calibrate_stage",
    "ingest_stage",
    "library_versions",
    "observe_stage",
    "report_stage",
    "write_observations_table",
]

OBSERVATIONS_FILE: Final = "observations.parquet"
CALIBRATION_DIR: Final = "calibration"
#: The files of a finished calibration stage (the checkpoint ``chains.h5`` aside).
CALIBRATION_FILES: Final = ("summary.json", "summary.csv", "posterior.nc", "corner.png",
                            "traces.png", "f_n_vs_torque.png", "stiffness_vs_torque.png")
#: Libraries whose versions are recorded (those the numbers depend on).
_LIBRARIES: Final = ("numpy", "scipy", "pandas", "pyarrow", "emcee", "arviz", "numba",
                     "matplotlib", "python-can", "cantools", "tqdm", "dask", "distributed")
_CALIBRATION_KEY: Final = "summary"
_STAGING: Final = ".staging-"


def library_versions() -> dict[str, str]:
    """Versions of Python, rigtools and the libraries the numbers depend on."""
    out = {"python": platform.python_version()}
    for name in ("rigtools", *_LIBRARIES):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            continue
    return out


# --------------------------------------------------------------------------------------------
# ingest and observe


def ingest_stage(tasks: Sequence[RunTask], executor: RunExecutor, progress: Progress
                 ) -> list[IngestOutcome]:
    """Ingest every run (module notes); results in campaign order.

    Raises
    ------
    OSError
        An output could not be written (names the file).
    """
    sizes = []
    for t in tasks:
        try:
            sizes.append(Path(t.run.file).stat().st_size)
        except OSError:
            sizes.append(0)
    out: list[IngestOutcome | None] = [cached_ingest(t) for t in tasks]
    todo = [i for i, o in enumerate(out) if o is None]
    with progress.stage("ingest", sum(sizes), unit="B", items=len(tasks)) as bar:
        done = [(i, o) for i, o in enumerate(out) if o is not None]
        work = executor.map_unordered(ingest_run, [(tasks[i],) for i in todo]) if todo else ()
        for i, res in itertools.chain(done, ((todo[j], r) for j, r in work)):
            out[i] = res
            what = "reused" if res.reused else (
                f"read in {res.elapsed_s:.1f} s" if res.status == "ok" else "FAILED")
            bar.advance(sizes[i], label=f"{res.run_id}: {what}")
            if res.status == "failed":
                bar.note(f"run {res.run_id!r} failed: {res.error}")
            progress.debug("ingest %s: key %s", res.run_id, res.key)
    return [o for o in out if o is not None]


def observe_stage(tasks: Sequence[RunTask], ingested: Sequence[IngestOutcome],
                  executor: RunExecutor, progress: Progress) -> list[ObserveOutcome | None]:
    """Observe every run that was read (module notes); None for a run that was not.

    Raises
    ------
    OSError
        An output could not be written (names the file).
    """
    read = [i for i, ing in enumerate(ingested) if ing.status == "ok"]
    out: list[ObserveOutcome | None] = [None] * len(tasks)
    for i in read:
        out[i] = cached_observe(tasks[i], ingested[i].key)
    todo = [i for i in read if out[i] is None]
    with progress.stage("observe", len(read), unit="run") as bar:
        done = [(i, o) for i, o in enumerate(out) if o is not None]
        items = [(tasks[i], ingested[i].key) for i in todo]
        work = executor.map_unordered(observe_run_task, items) if todo else ()
        for i, res in itertools.chain(done, ((todo[j], r) for j, r in work)):
            out[i] = res
            what = "reused" if res.reused else (
                f"analysed in {res.elapsed_s:.1f} s" if res.status == "ok" else "FAILED")
            bar.advance(1, label=f"{res.run_id}: {what}")
            if res.status == "failed":
                bar.note(f"run {res.run_id!r} failed: {res.error}")
            progress.debug("observe %s: key %s", res.run_id, res.key)
    return out


def write_observations_table(campaign: Campaign, outdir: Path, tasks: Sequence[RunTask],
                             ingested: Sequence[IngestOutcome],
                             observed: Sequence[ObserveOutcome | None]) -> Path:
    """Write ``observations.parquet`` from the per-run files (atomically).

    Parameters
    ----------
    campaign : Campaign
    outdir : pathlib.Path
    tasks, ingested, observed
        The runs and what ingest and observe did (campaign order).

    Returns
    -------
    pathlib.Path
    """
    rows: list[dict[str, Any]] = []
    runs: list[dict[str, Any]] = []
    for task, ing, obs in zip(tasks, ingested, observed, strict=True):
        if obs is None:
            msg = ing.error or "not read"
            rows.extend(to_frame(failed_run_rows(campaign, task.run, msg, ing.source_sha256)
                                 ).to_dict("records"))
            runs.append({"id": task.run.id, "file": str(task.run.file), "analysed": False,
                         "error": msg})
            continue
        frame, doc = read_run_rows(outdir, task.stem)
        rows.extend(frame.to_dict("records"))
        runs.append({"id": task.run.id, "file": str(task.run.file),
                     "analysed": bool(doc["analysed"]), "error": doc.get("error")})
    table = to_frame(rows)
    obs_all = Observations(table=table, runs=(),
                           metadata=observations_metadata(campaign, runs))
    path = outdir / OBSERVATIONS_FILE
    with atomic_output(path) as tmp:
        write_observations(obs_all, tmp)
    return path


# --------------------------------------------------------------------------------------------
# calibrate


@dataclass(frozen=True)
class CalibrateOutcome(PartOutcome):
    """What the calibration stage did.

    Attributes
    ----------
    status, error, key, reused, elapsed_s
        As :class:`~rigtools.pipeline.runup_stage.PartOutcome` (``key``: the stage key).
    summary : dict or None
        ``calibration/summary.json`` when the stage is ok.
    warnings : tuple of str
        The calibration's warnings (not converged, runs left out, ...), the run-up part's
        after them.
    runup : RunUpOutcome or None
        The run-up part (None when the stage did not get to it). ``status``, ``error``,
        ``key``, ``reused`` and ``elapsed_s`` above are the natural-frequency part's.
    """

    summary: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()
    runup: RunUpOutcome | None = None

    def stage_document(self) -> dict[str, Any]:
        """``pipeline.json`` ``stages.calibrate``.

        This part's status, error, key, reuse and time, and the run-up part under ``runup``
        (:meth:`RunUpOutcome.to_dict`).
        """
        doc: dict[str, Any] = {"key": self.key, "elapsed_s": self.elapsed_s,
                               "reused": self.reused, "status": self.status,
                               "error": self.error}
        if self.runup is not None:
            doc["runup"] = self.runup.to_dict()
        return doc


#: ``[calibration]`` keys only the run-up part reads (left out of the natural-frequency key).
_RUNUP_ONLY_KEYS: Final = frozenset({"models", "runup"})


def _calibration_key(campaign: Campaign, observations: Path, seed: int | None) -> str:
    d = campaign.to_dict()
    gear_file = Path(campaign.gear_set_path)
    block = campaign.calibration
    if block is not None:
        block = {k: v for k, v in block.items() if k not in _RUNUP_ONLY_KEYS}
    parts: dict[str, Any] = {
        "observations_sha256": file_sha256(observations),
        "gear_set": d["campaign"]["gear_set_path"],
        "gear_set_sha256": file_sha256(gear_file) if gear_file.is_file() else None,
        "thermal": d["thermal"], "calibration": block, "seed": seed}
    own = run_gear_sets(campaign)
    if own:  # which runs are on the campaign's gear set decides which runs are fitted
        parts["run_gear_sets"] = own
    return stage_key("calibrate", parts)


def _clear_calibration(cal: Path) -> None:
    """Remove the outputs of an earlier calibration (not the checkpoint) and stray staging."""
    for name in CALIBRATION_FILES:
        with contextlib.suppress(FileNotFoundError):
            (cal / name).unlink()
    for stray in cal.glob(f"{_STAGING}*"):
        shutil.rmtree(stray, ignore_errors=True)


def calibrate_stage(campaign: Campaign, outdir: Path, *, seed: int | None,
                    progress: Progress, run_ok: bool) -> CalibrateOutcome:
    """Calibrate the campaign from ``observations.parquet`` (module notes).

    Parameters
    ----------
    campaign : Campaign
    outdir : pathlib.Path
    seed : int, optional
        Overrides the ``[calibration]`` block's seed.
    progress : Progress
    run_ok : bool
        At least one run was analysed (else the stage is skipped).

    Returns
    -------
    CalibrateOutcome

    Raises
    ------
    OSError
        An output could not be written (names the file).
    """
    t0 = time.perf_counter()
    fn = _fn_part(campaign, outdir, seed=seed, progress=progress, run_ok=run_ok)
    if not run_ok:
        runup = RunUpOutcome("skipped", "no run could be read and analysed", "", False, 0.0)
        clear_runup_outputs(outdir / CALIBRATION_DIR)
    else:
        runup = runup_part(campaign, outdir, outdir / OBSERVATIONS_FILE, seed=seed,
                           progress=progress)
    warnings = fn.warnings + runup.warnings
    if runup.status == "failed":
        warnings += (f"the run-up calibration (SDOF models) failed: {runup.error}",)
    progress.debug("calibrate: %.1f s in all", time.perf_counter() - t0)
    return replace(fn, warnings=warnings, runup=runup)


def _fn_part(campaign: Campaign, outdir: Path, *, seed: int | None, progress: Progress,
             run_ok: bool) -> CalibrateOutcome:
    """The natural-frequency calibration (the stage before the run-up part)."""
    t0 = time.perf_counter()
    cal = outdir / CALIBRATION_DIR
    key_file = key_path(cal, _CALIBRATION_KEY)
    if not run_ok:
        invalidate(key_file)
        if cal.is_dir():
            _clear_calibration(cal)
        return CalibrateOutcome("skipped", "no run could be read and analysed", "", False,
                                time.perf_counter() - t0)
    key = _calibration_key(campaign, outdir / OBSERVATIONS_FILE, seed)
    outputs = tuple(cal / n for n in CALIBRATION_FILES)
    if is_current(key_file, key, outputs):
        summary = json.loads((cal / "summary.json").read_text(encoding="utf-8"))
        progress.info("calibrate: reused (%s)", cal)
        return CalibrateOutcome("ok", None, key, True, time.perf_counter() - t0, summary,
                                _warnings(summary))
    invalidate(key_file)
    cal.mkdir(parents=True, exist_ok=True)
    _clear_calibration(cal)
    table = read_observations(outdir / OBSERVATIONS_FILE)
    try:
        config = campaign_config(campaign)
        steps = config.max_steps * len({config.model_variant, *config.compare_variants})
        with progress.stage("calibrate", steps, unit="step") as bar:
            result = calibrate(campaign, table, config=config, outdir=cal, seed=seed,
                               progress=bar.steps)
    except (CalibrationError, ModelError) as exc:  # the data cannot be calibrated as asked
        progress.info("calibrate: failed: %s", exc)
        return CalibrateOutcome("failed", str(exc), key, False, time.perf_counter() - t0)
    staging = cal / f"{_STAGING}{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    try:
        write_outputs(result, staging)
        logging.disable(logging.WARNING)  # corner logs "too few points" for narrow panels
        try:
            calibration_figures(result, staging)
        finally:
            logging.disable(logging.NOTSET)
        for name in CALIBRATION_FILES:
            src = staging / name
            with atomic_output(cal / name) as tmp:
                os.replace(src, tmp)
        fsync_folder(cal)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    write_stage_key(key_file, key)
    summary = json.loads((cal / "summary.json").read_text(encoding="utf-8"))
    return CalibrateOutcome("ok", None, key, False, time.perf_counter() - t0, summary,
                            _warnings(summary))


def _warnings(summary: dict[str, Any]) -> tuple[str, ...]:
    """The calibration's warnings, from ``summary.json`` (the same whether reused or not)."""
    out = [str(w) for w in summary.get("warnings", ())]
    if not summary.get("converged", True):
        out.append("the sampler did not converge within the step cap; the result is flagged "
                   "(summary.json) and its intervals are not to be trusted")
    return tuple(out)


# --------------------------------------------------------------------------------------------
# report


def report_stage(outdir: Path, progress: Progress) -> tuple[Path, float]:
    """Build ``report.html`` and ``report.json`` from OUTDIR's files.

    Returns
    -------
    (pathlib.Path, float)
        The HTML report and the time it took (s).
    """
    t0 = time.perf_counter()
    progress.info("report: writing report.json and report.html")
    paths = build_report(outdir)
    elapsed = time.perf_counter() - t0
    progress.info("report: written in %.1f s (%s)", elapsed, paths.html)
    return paths.html, elapsed
