"""A run killed inside ingest, sampling or report writing ends like an uninterrupted one.

Issue 19 item 3: killed with SIGKILL, then run again, it ends with the same numbers.

The killed run is ``rigtools run`` in a subprocess, killed when its log lines (stderr is not a
terminal) say it is inside the stage; the re-run is in process. The numbers compared are
``calibration/summary.json`` (the parameters, derived quantities and runs; ``resumed_from``
says where the sampler picked up) and the observations table.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pandas as pd

from rigtools.campaign import read_observations
from rigtools.pipeline import PipelineResult, run_campaign
from rigtools.pipeline.atomic import TMP_MARKER

ROOT = Path(__file__).resolve().parents[2]
CLI = "import sys; from rigtools.cli import main; sys.exit(main(sys.argv[1:]))"


def campaign_of(res: PipelineResult) -> Path:
    return Path(json.loads(res.pipeline_json.read_text(encoding="utf-8"))["campaign"]["path"])


def kill_when(out: Path, campaign: Path, pattern: str) -> str:
    """Start ``rigtools run`` and SIGKILL it at the first stderr line matching ``pattern``."""
    proc = subprocess.Popen([sys.executable, "-c", CLI, "run", str(campaign), "-o", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT)
    assert proc.stderr is not None
    seen = []
    killed_at = None
    for line in proc.stderr:
        seen.append(line)
        if re.search(pattern, line):
            os.kill(proc.pid, signal.SIGKILL)
            killed_at = line.strip()
            break
    proc.wait(timeout=120)
    assert killed_at is not None and proc.returncode == -signal.SIGKILL, (
        "not killed where asked; stderr:\n" + "".join(seen))
    return killed_at


def numbers(summary: dict[str, Any]) -> dict[str, Any]:
    return {k: summary[k] for k in ("parameters", "derived", "runs", "model_comparison")}


def same_as_whole(out: Path, res: PipelineResult, whole: PipelineResult) -> None:
    assert res.calibration_status == "ok"
    a = json.loads((out / "calibration" / "summary.json").read_text(encoding="utf-8"))
    b = json.loads((whole.outdir / "calibration" / "summary.json").read_text(encoding="utf-8"))
    assert numbers(a) == numbers(b)
    pd.testing.assert_frame_equal(read_observations(out / "observations.parquet"),
                                  read_observations(whole.outdir / "observations.parquet"),
                                  check_exact=True)
    for r in res.runs:
        assert (out / "spectra" / f"{r.stem}.parquet").read_bytes() == (
            whole.outdir / "spectra" / f"{r.stem}.parquet").read_bytes()
    assert (out / "report.html").is_file() and (out / "report.json").is_file()
    json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert not list(out.rglob(f"*{TMP_MARKER}*"))


def test_killed_inside_ingest(whole_run: PipelineResult, tmp_path: Path) -> None:
    out = tmp_path / "out"
    kill_when(out, campaign_of(whole_run), r"ingest \[1/4\]")
    keys = sorted((out / "ingest").glob("*.key"))
    assert 1 <= len(keys) < 4, "killed after the first run was ingested, before the last"
    assert not (out / "observations.parquet").exists()
    again = run_campaign(campaign_of(whole_run), out, progress=False)
    assert again.stages["ingest"]["reused"] == len(keys)
    assert again.stages["ingest"]["computed"] == 4 - len(keys)
    same_as_whole(out, again, whole_run)


def test_killed_inside_sampling(whole_run: PipelineResult, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(whole_run.outdir, out)  # ingest and observe reused; calibration from scratch
    shutil.rmtree(out / "calibration")
    for f in ("report.html", "report.json", "pipeline.json"):
        (out / f).unlink()
    kill_when(out, campaign_of(whole_run), r"calibrate: step (1[5-9]\d|2\d\d)/")
    assert (out / "calibration" / "chains.h5").is_file()
    assert not (out / "calibration" / "summary.key").exists()
    assert not (out / "report.html").exists()
    again = run_campaign(campaign_of(whole_run), out, progress=False)
    summary = json.loads((out / "calibration" / "summary.json").read_text(encoding="utf-8"))
    assert summary["sampler"]["resumed_from"] >= 150
    same_as_whole(out, again, whole_run)


def test_killed_inside_report_writing(whole_run: PipelineResult, tmp_path: Path) -> None:
    out = tmp_path / "out"
    shutil.copytree(whole_run.outdir, out)
    for f in ("report.html", "report.json"):
        (out / f).unlink()
    kill_when(out, campaign_of(whole_run), r"report: writing")
    if (out / "report.json").exists():  # complete or absent, never half-written
        json.loads((out / "report.json").read_text(encoding="utf-8"))
    if (out / "report.html").exists():
        assert (out / "report.html").read_text(encoding="utf-8").rstrip().endswith("</html>")
    again = run_campaign(campaign_of(whole_run), out, progress=False)
    assert again.stages["calibrate"]["reused"] is True
    same_as_whole(out, again, whole_run)
