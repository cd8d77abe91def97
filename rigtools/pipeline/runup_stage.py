"""The run-up part of the calibrate stage: the SDOF models against the measured Arms run-ups.

:func:`runup_part` runs :func:`rigtools.calibration.runup_api.calibrate_runups` when the
campaign's ``[calibration] models`` is not empty and the observations table has run-ups
(:func:`rigtools.calibration.runup_data.runup_runs`), with ``OUTDIR/calibration`` as its
folder (its checkpoint ``calibration/runup/chains.h5`` resumes a killed run). Its files::

    calibration/runup/comparison.json, comparison.csv
    calibration/runup/<model>/summary.json, posterior.nc
    calibration/runup/runup_<stem>.png          one figure per run (rigtools.plots.runup)
    calibration/runup/runup.key                 the part's key, written last

are written into a staging folder and moved into place one by one, then the key. The key
(:func:`runup_key`) covers the observations table, the gear sets of every run, the
``[calibration]`` settings the run-up calibration reads (``models``, ``[calibration.runup]``,
the equivalent mass, the sampler, the tolerances) and the seed, not the natural-frequency
calibration's own settings: changing a prior of the backlash calibration does not refit the
SDOF models, and the other way round.

A :class:`~rigtools.calibration.CalibrationError` (no usable run-up) or a
:class:`models.errors.ModelError` fails this part alone, with its message
(:class:`RunUpOutcome`, recorded in ``pipeline.json`` under ``stages.calibrate.runup``): the
natural-frequency calibration and the report go on.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
import pandas as pd

from models.errors import ModelError
from rigtools.calibration import CalibrationError, campaign_config
from rigtools.calibration.runup_api import calibrate_runups
from rigtools.calibration.runup_data import runup_runs
from rigtools.calibration.runup_outputs import RUNUP_DIR, RunUpResult, write_runup_outputs
from rigtools.campaign import Campaign, read_observations
from rigtools.pipeline.atomic import atomic_output, fsync_folder, remove_stale_temporaries
from rigtools.pipeline.cache import file_sha256, invalidate, is_current, key_path, stage_key
from rigtools.pipeline.cache import write_key as write_stage_key
from rigtools.pipeline.progress import Progress
from rigtools.pipeline.stems import run_file_stem
from rigtools.plots.runup import RunUpBand, RunUpFigureData, write_runup_figures

__all__ = [
    "FN_ONLY_KEYS",
    "RUNUP_KEY",
    "PartOutcome",
    "RunUpOutcome",
    "clear_runup_outputs",
    "figure_data",
    "run_gear_sets",
    "runup_figure_name",
    "runup_key",
    "runup_part",
]

#: Name of the part's key file in ``calibration/runup/`` (``runup.key``).
RUNUP_KEY: Final = "runup"
#: ``[calibration]`` keys only the natural-frequency calibration reads (left out of the key).
FN_ONLY_KEYS: Final = frozenset({
    "model_variant", "compare_variants", "thermal_model", "jammed_model", "likelihood",
    "student_t_dof", "detection_probability", "structural_modes", "band_Hz",
    "reference_temperature_C", "operating_temperature_C", "temperature_sd_K",
    "plan_torque_range_Nm", "plan_temperature_range_C", "priors", "fixed"})
_STAGING: Final = ".staging-"
_CHECKPOINT: Final = "chains.h5"


@dataclass(frozen=True)
class PartOutcome:
    """What one part of the calibrate stage did (natural-frequency or run-up calibration).

    Attributes
    ----------
    status : {'ok', 'failed', 'skipped'}
    error : str or None
        Why it failed or was skipped.
    key : str
        The part's key ("" when skipped).
    reused : bool
    elapsed_s : float
    """

    status: Literal["ok", "failed", "skipped"]
    error: str | None
    key: str
    reused: bool
    elapsed_s: float


@dataclass(frozen=True)
class RunUpOutcome(PartOutcome):
    """What the run-up part of the calibrate stage did.

    Attributes
    ----------
    status, error, key, reused, elapsed_s
        As :class:`PartOutcome`.
    models : tuple of str
        The models fitted (from ``comparison.json``).
    runs : tuple of str
        The runs calibrated against.
    warnings : tuple of str
        The run-up calibration's warnings (runs refused, parameters not identified, ...).
    """

    models: tuple[str, ...] = ()
    runs: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """``pipeline.json`` ``stages.calibrate.runup``."""
        return {"status": self.status, "error": self.error, "key": self.key,
                "reused": self.reused, "elapsed_s": self.elapsed_s,
                "models": list(self.models), "runs": list(self.runs),
                "n_warnings": len(self.warnings)}


def runup_figure_name(run_id: str) -> str:
    """``runup_<stem>.png``, the stem the pipeline gives the run (:func:`run_file_stem`)."""
    return f"runup_{run_file_stem(run_id)}.png"


def run_gear_sets(campaign: Campaign) -> dict[str, dict[str, Any]]:
    """Run id -> its own gear set (as written, file, SHA-256), for runs that name one."""
    out: dict[str, dict[str, Any]] = {}
    for entry in campaign.to_dict()["run"]:
        path = entry.get("gear_set_path")
        if path is None:
            continue
        f = Path(str(path))
        out[str(entry["id"])] = {"gear_set": entry.get("gear_set"), "path": str(path),
                                 "sha256": file_sha256(f) if f.is_file() else None}
    return out


def runup_key(campaign: Campaign, observations: Path, seed: int | None) -> str:
    """The key of the run-up part (module notes)."""
    d = campaign.to_dict()
    gear_file = Path(campaign.gear_set_path)
    block = {k: v for k, v in (campaign.calibration or {}).items() if k not in FN_ONLY_KEYS}
    return stage_key("calibrate-runup", {
        "observations_sha256": file_sha256(observations),
        "gear_set": d["campaign"]["gear_set_path"],
        "gear_set_sha256": file_sha256(gear_file) if gear_file.is_file() else None,
        "run_gear_sets": run_gear_sets(campaign),
        "calibration": block, "seed": seed})


def figure_data(result: RunUpResult) -> list[RunUpFigureData]:
    """What the figure of every calibrated run shows, from a :class:`RunUpResult`."""
    out = []
    for rid in result.runs:
        preds = [(m, fit.predictive_for(rid)) for m, fit in result.fits.items()
                 if any(p.run_id == rid for p in fit.predictive)]
        if not preds:
            continue
        first = preds[0][1]
        bands = []
        for model, p in preds:
            if p.arms_q50.shape != first.observed.shape:
                continue
            jumps = {}
            for d in ("up", "down"):
                q = p.jump_model_Hz.get(d)
                jumps[d] = (np.array([np.nan] * 3) if q is None else
                            np.array([q.get("q05", np.nan), q.get("q50", np.nan),
                                      q.get("q95", np.nan)], dtype=float))
            bands.append(RunUpBand(model, np.stack([p.arms_q05, p.arms_q50, p.arms_q95]),
                                   jumps["up"], jumps["down"]))
        out.append(RunUpFigureData(
            run_id=rid, channels=tuple(first.channels),
            mesh_frequency_Hz=np.asarray(first.mesh_frequency_Hz, dtype=float),
            direction=np.asarray(first.direction).astype(str),
            observed_m_s2=np.asarray(first.observed, dtype=float), bands=tuple(bands),
            measured_jump_up_Hz=first.jump_measured_Hz.get("up"),
            measured_jump_down_Hz=first.jump_measured_Hz.get("down"),
            torque_Nm=float(first.torque_Nm)))
    return out


def _expected_outputs(folder: Path) -> tuple[Path, ...] | None:
    """The files ``comparison.json`` vouches for; None when it is absent or unreadable."""
    try:
        doc = json.loads((folder / "comparison.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    models = [str(m) for m in doc.get("models") or []]
    runs = [str(r) for r in doc.get("runs") or []]
    files = [folder / "comparison.json", folder / "comparison.csv"]
    files += [folder / m / n for m in models for n in ("summary.json", "posterior.nc")]
    files += [folder / runup_figure_name(r) for r in runs]
    return tuple(files)


def _file_warnings(folder: Path) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    """(models, runs, warnings) from the written files (the same whether reused or not)."""
    doc = json.loads((folder / "comparison.json").read_text(encoding="utf-8"))
    models = tuple(str(m) for m in doc.get("models") or [])
    runs = tuple(str(r) for r in doc.get("runs") or [])
    warns = [f"run-up calibration: run {r}: {msg}" for r, msg in
             (doc.get("refused") or {}).items()]
    for m in models:
        with contextlib.suppress(OSError, ValueError):
            s = json.loads((folder / m / "summary.json").read_text(encoding="utf-8"))
            warns += [f"run-up calibration, {m}: {w}" for w in s.get("warnings") or []]
    return models, runs, tuple(warns)


def clear_runup_outputs(calibration_dir: Path) -> None:
    """Remove the run-up outputs and key of ``calibration_dir`` (not the checkpoint)."""
    folder = calibration_dir / RUNUP_DIR
    invalidate(key_path(folder, RUNUP_KEY))
    _clear(folder)


def _clear(folder: Path) -> None:
    """Remove the outputs of an earlier run-up calibration (not the checkpoint)."""
    if not folder.is_dir():
        return
    for p in folder.iterdir():
        if p.name == _CHECKPOINT:
            continue
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError):
                p.unlink()


def _has_runups(table: pd.DataFrame, min_span: float) -> bool:
    try:
        return bool(runup_runs(table, min_span=min_span))
    except CalibrationError:  # no arms rows at all (a table without the columns)
        return False


def _move_into_place(staging: Path, folder: Path) -> None:
    """Move every file of ``staging`` into ``folder`` (same relative path), atomically."""
    for src in sorted(p for p in staging.rglob("*") if p.is_file()):
        rel = src.relative_to(staging)
        dest = folder / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        with atomic_output(dest) as tmp:
            os.replace(src, tmp)
    for d in sorted({folder, *(folder / p.relative_to(staging)
                               for p in staging.rglob("*") if p.is_dir())}):
        fsync_folder(d)


def runup_part(campaign: Campaign, outdir: Path, observations: Path, *,
               seed: int | None, progress: Progress) -> RunUpOutcome:
    """Calibrate the SDOF models against the run-ups (module notes).

    Parameters
    ----------
    campaign : Campaign
    outdir : pathlib.Path
        OUTDIR (files go to ``OUTDIR/calibration/runup``).
    observations : pathlib.Path
        ``observations.parquet`` (read when a model is asked for; hashed into the key).
    seed : int, optional
        Overrides the ``[calibration]`` seed.
    progress : Progress

    Returns
    -------
    RunUpOutcome
        ``skipped`` when no model is asked for or the table has no run-up (the old outputs
        are removed), ``failed`` with the message of a CalibrationError or ModelError.

    Raises
    ------
    OSError
        An output could not be written (names the file).
    """
    t0 = time.perf_counter()
    cal = outdir / "calibration"
    folder = cal / RUNUP_DIR
    key_file = key_path(folder, RUNUP_KEY)
    if folder.is_dir():
        remove_stale_temporaries(folder)
    config = campaign_config(campaign)
    why = None
    table = read_observations(observations) if config.models else None
    if table is None:
        why = "no SDOF model asked for ([calibration] models is empty)"
    elif not _has_runups(table, config.runup.min_span):
        why = "the observations table has no run-up (no run's arms rows span the speed range)"
    if why is not None:
        invalidate(key_file)
        _clear(folder)
        return RunUpOutcome("skipped", why, "", False, time.perf_counter() - t0)
    key = runup_key(campaign, observations, seed)
    expected = _expected_outputs(folder)
    if expected is not None and is_current(key_file, key, expected):
        models, runs, warns = _file_warnings(folder)
        progress.info("calibrate (run-ups): reused (%s)", folder)
        return RunUpOutcome("ok", None, key, True, time.perf_counter() - t0, models, runs,
                            warns)
    invalidate(key_file)
    _clear(folder)
    folder.mkdir(parents=True, exist_ok=True)
    try:
        max_steps = config.runup.max_steps or config.max_steps
        steps = max_steps * len(config.models)
        with progress.stage("calibrate run-ups", steps, unit="step") as bar:
            result = calibrate_runups(campaign, table, config=config, outdir=cal, seed=seed,
                                      progress=bar.steps)
    except (CalibrationError, ModelError) as exc:  # the run-ups cannot be calibrated as asked
        progress.info("calibrate (run-ups): failed: %s", exc)
        _clear(folder)  # files a failed attempt may have left (the checkpoint stays)
        return RunUpOutcome("failed", str(exc), key, False, time.perf_counter() - t0)
    # calibrate_runups wrote its files when given outdir: they are rewritten through the
    # staging folder below, so that every file in place comes from one finished run.
    _clear(folder)
    staging = folder / f"{_STAGING}{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(parents=True)
    try:
        write_runup_outputs(result, staging)
        logging.disable(logging.WARNING)
        try:
            write_runup_figures(figure_data(result), staging / RUNUP_DIR,
                                file_name=runup_figure_name)
        finally:
            logging.disable(logging.NOTSET)
        _move_into_place(staging / RUNUP_DIR, folder)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    write_stage_key(key_file, key)
    models, runs, warns = _file_warnings(folder)
    return RunUpOutcome("ok", None, key, False, time.perf_counter() - t0, models, runs, warns)
