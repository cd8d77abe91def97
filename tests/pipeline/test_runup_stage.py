"""The run-up part of the calibrate stage (issue 20): wiring, its own key, failing alone.

``calibrate_runups`` and ``write_runup_outputs`` are replaced by fakes (a small synthetic
:class:`RunUpResult` and its files) so the tests take seconds; the natural-frequency
calibration is the real one of :func:`pipeline_cases.small_campaign`. The demo's runs are
steady speeds, so the check that the table has run-ups is replaced too (it is H2's
``runup_runs``, tested with the data).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from pipeline_cases import CALIBRATION, small_campaign

import rigtools.pipeline.runup_stage as runup_stage
from rigtools.calibration import CalibrationError
from rigtools.calibration.runup_outputs import RunPredictive, RunUpResult
from rigtools.campaign import load_campaign
from rigtools.pipeline import run_campaign, run_file_stem
from rigtools.pipeline.progress import Progress
from rigtools.pipeline.stages import CalibrateOutcome, calibrate_stage
from rigtools.report import build_report
from rigtools.schemas import iter_errors

RUNS = ("LS9-30C", "LS9-105C")
UP_TO_CALIBRATION = ("ingest", "observe", "calibrate")
MODELS = 'models = ["vvms", "fvms"]\n'


class _Fit:
    """The part of a RunUpFit the figure reads."""

    def __init__(self, predictive: tuple[RunPredictive, ...]) -> None:
        self.predictive = predictive

    def predictive_for(self, run_id: str) -> RunPredictive:
        return next(p for p in self.predictive if p.run_id == run_id)


def _predictive(run_id: str, scale: float) -> RunPredictive:
    f = np.concatenate([np.linspace(1500.0, 4500.0, 10), np.linspace(4500.0, 1500.0, 10)])
    arms = 1e-5 * f[None, :] ** 2 / np.abs(1.2 - (f[None, :] / 3200.0) ** 2)
    return RunPredictive(
        run_id=run_id, gear_set="kahraman-blankenship", torque_Nm=300.0,
        channels=("accel_x",), mesh_frequency_Hz=f,
        direction=np.array(["up"] * 10 + ["down"] * 10), observed=arms,
        arms_q05=0.8 * scale * arms, arms_q50=scale * arms, arms_q95=1.2 * scale * arms,
        jump_measured_Hz={"up": 3300.0, "down": None},
        jump_model_Hz={"up": {"q05": 3250.0, "q50": 3310.0, "q95": 3360.0}, "down": None},
        backside_impact_probability=0.0, contact_loss_probability=0.5)


def fake_result(runs: tuple[str, ...]) -> RunUpResult:
    fits: dict[str, Any] = {m: _Fit(tuple(_predictive(r, s) for r in runs))
                            for m, s in (("vvms", 1.0), ("fvms", 1.3))}
    return RunUpResult(models=("vvms", "fvms"), fits=fits, comparison=None,
                       blocked_comparison=None, statement="the data favour vvms", runs=runs,
                       refused={}, warnings=(), notes=(), config={}, seed=3)


def fake_write(result: RunUpResult, outdir: str | Path) -> dict[str, Path]:
    """The files of write_runup_outputs, with made-up content."""
    root = Path(outdir) / "runup"
    for m in result.models:
        (root / m).mkdir(parents=True, exist_ok=True)
        summary = {"model": m, "converged": True,
                   "parameters": {"zeta": {"mean": 0.025, "sd": 0.001, "q05": 0.023,
                                           "q50": 0.025, "q95": 0.027, "unit": "1",
                                           "identified": True}},
                   "derived": {}, "runs": {}, "warnings": [f"{m} says hello"]}
        (root / m / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
        (root / m / "posterior.nc").write_bytes(b"not really netCDF")
    comparison = {"criterion": "psis-loo", "models": list(result.models), "pointwise": None,
                  "blocked": None, "favoured": "vvms", "statement": result.statement,
                  "runs": list(result.runs), "refused": {}}
    (root / "comparison.json").write_text(json.dumps(comparison), encoding="utf-8")
    (root / "comparison.csv").write_text("model\nvvms\nfvms\n", encoding="utf-8")
    return {}


@pytest.fixture
def patched(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    calls: dict[str, Any] = {"n": 0, "raise": None}

    def calibrate_runups(campaign: Any, observations: Any, **kwargs: Any) -> RunUpResult:
        calls["n"] += 1
        calls["kwargs"] = kwargs
        if calls["raise"] is not None:
            raise calls["raise"]
        return fake_result(RUNS)

    monkeypatch.setattr(runup_stage, "calibrate_runups", calibrate_runups)
    monkeypatch.setattr(runup_stage, "write_runup_outputs", fake_write)
    monkeypatch.setattr(runup_stage, "runup_runs", lambda table, min_span=None: list(RUNS))
    return calls


def _campaign(demo_source: Path, dest: Path, extra: str = MODELS) -> Path:
    """Two FZG-C runs with the short calibration (the demo's own blocks replaced)."""
    camp = small_campaign(demo_source, dest, RUNS, accel=("accel_x",), calibration="")
    text = re.sub(r"^\[calibration[^\n]*\]\n(?:(?!\[)[^\n]*\n)*", "",
                  camp.read_text(encoding="utf-8"), flags=re.M)
    camp.write_text(text + CALIBRATION + extra, encoding="utf-8")
    return camp


def _calibrate(camp: Path, out: Path) -> CalibrateOutcome:
    return calibrate_stage(load_campaign(camp), out, seed=None, progress=Progress(False),
                           run_ok=True)


def _files(folder: Path) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_runup_part_runs_under_its_own_key(demo_source: Path, tmp_path: Path,
                                           patched: dict[str, Any],
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    camp = _campaign(demo_source, tmp_path / "c", extra="")
    out = tmp_path / "out"
    run_campaign(camp, out, stages=("ingest", "observe"), progress=False)
    folder = out / "calibration" / "runup"

    # no model asked for: the part is skipped, the natural-frequency part runs
    cal = _calibrate(camp, out)
    assert cal.status == "ok" and cal.reused is False
    assert cal.runup is not None and cal.runup.status == "skipped"
    assert "models is empty" in (cal.runup.error or "") and patched["n"] == 0
    assert "runup" in cal.stage_document()

    # models added: the run-up part runs; the natural-frequency part is reused
    camp.write_text(camp.read_text(encoding="utf-8").replace(
        "[calibration]\n", "[calibration]\n" + MODELS), encoding="utf-8")
    cal = _calibrate(camp, out)
    assert cal.reused is True and patched["n"] == 1
    assert cal.runup is not None and cal.runup.status == "ok" and not cal.runup.reused
    assert cal.runup.models == ("vvms", "fvms") and cal.runup.runs == RUNS
    assert patched["kwargs"]["outdir"] == out / "calibration"
    for f in ("comparison.json", "comparison.csv", "vvms/summary.json", "fvms/posterior.nc",
              "runup.key"):
        assert (folder / f).is_file(), f
    for r in RUNS:
        png = folder / f"runup_{run_file_stem(r)}.png"
        assert png.read_bytes().startswith(b"\x89PNG"), png
    assert not list(folder.glob(".staging-*"))
    assert "run-up calibration, vvms: vvms says hello" in cal.warnings
    doc = cal.stage_document()
    assert doc["runup"]["status"] == "ok" and doc["runup"]["models"] == ["vvms", "fvms"]

    # the report reads the files
    report = build_report(out).content
    assert iter_errors(report, "report.schema.json") == []
    ru = report["runup_calibration"]
    assert ru["status"] == "ok" and ru["models"] == ["vvms", "fvms"]
    assert [f["run_id"] for f in ru["figures"]] == list(RUNS)

    # nothing changed: both parts reused, not a byte rewritten
    before = _files(folder)
    again = _calibrate(camp, out)
    assert patched["n"] == 1 and again.reused is True
    assert again.runup is not None and again.runup.reused is True
    assert _files(folder) == before
    assert again.warnings == cal.warnings

    # a run-up setting changed: the run-up part alone is redone
    camp.write_text(camp.read_text(encoding="utf-8")
                    + "\n[calibration.runup]\nmin_speed_points = 12\n", encoding="utf-8")
    third = _calibrate(camp, out)
    assert patched["n"] == 2 and third.reused is True
    assert third.runup is not None and third.runup.status == "ok"

    # no run-up in the table any more: skipped, the old outputs removed
    monkeypatch.setattr(runup_stage, "runup_runs", lambda table, min_span=None: [])
    fourth = _calibrate(camp, out)
    assert fourth.runup is not None and fourth.runup.status == "skipped"
    assert "no run-up" in (fourth.runup.error or "") and patched["n"] == 2
    assert not (folder / "comparison.json").exists() and not (folder / "runup.key").exists()
    assert not list(folder.glob("runup_*.png"))


def test_runup_failure_fails_that_part_alone(demo_source: Path, tmp_path: Path,
                                             patched: dict[str, Any]) -> None:
    camp = _campaign(demo_source, tmp_path / "c")
    out = tmp_path / "out"
    run_campaign(camp, out, stages=("ingest", "observe"), progress=False)
    stale = out / "calibration" / "runup" / "vvms"
    stale.mkdir(parents=True)
    (stale / "summary.json").write_text("{}", encoding="utf-8")  # from an earlier run
    patched["raise"] = CalibrationError("no usable run-up for the SDOF calibration "
                                        "(LS9-30C: too few speed points)")
    cal = _calibrate(camp, out)
    assert cal.status == "ok" and cal.summary is not None           # the f_n part
    assert (out / "calibration" / "summary.json").is_file()
    assert cal.runup is not None and cal.runup.status == "failed"
    assert "too few speed points" in (cal.runup.error or "")
    assert any("run-up calibration (SDOF models) failed" in w for w in cal.warnings)
    assert not (stale / "summary.json").exists()                    # no stale result kept
    doc = cal.stage_document()
    assert doc["status"] == "ok" and doc["runup"]["status"] == "failed"
    assert "too few speed points" in doc["runup"]["error"]
    # the whole pipeline completes, report included
    res = run_campaign(camp, out, progress=False)
    assert res.calibration_status == "ok" and res.summary is not None
    assert res.report is not None and res.report.is_file()
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert iter_errors(report, "report.schema.json") == []
    assert report["verdict"]["available"] is True


def test_runup_key_follows_its_own_settings_only(demo_source: Path, tmp_path: Path) -> None:
    camp = _campaign(demo_source, tmp_path / "c")
    table = tmp_path / "observations.parquet"
    table.write_bytes(b"a table")
    text = camp.read_text(encoding="utf-8")

    def key(extra: str = "", seed: int | None = None) -> str:
        camp.write_text(text + extra, encoding="utf-8")
        return runup_stage.runup_key(load_campaign(camp), table, seed)

    base = key()
    # the natural-frequency calibration's own settings do not refit the SDOF models
    assert key('\n[calibration.priors]\nbacklash = {dist = "uniform", lower = 0.0, '
               'upper = 80.0}\n') == base
    assert key("\n[calibration.runup]\nmin_speed_points = 12\n") != base
    assert key(seed=5) != base
    table.write_bytes(b"another table")
    assert key() != base
