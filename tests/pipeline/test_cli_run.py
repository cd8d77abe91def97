"""``rigtools run``: the verdict, exit codes, and nothing half-written on bad input."""

from __future__ import annotations

import errno
import json
import shutil
from pathlib import Path

import pytest
from pipeline_cases import CALIBRATION, small_campaign

import rigtools.pipeline.run_tasks as run_tasks
from rigtools.cli import main
from rigtools.pipeline import PipelineResult
from rigtools.pipeline.atomic import TMP_MARKER

MISSING = ('\n[[run]]\nid = "gone"\nfile = "runs/missing.mcap"\ntorque_Nm = 100.0\n'
           'bulk_temperature_C = 40.0\n')
GARBAGE = ('\n[[run]]\nid = "junk"\nfile = "runs/junk.mcap"\ntorque_Nm = 100.0\n'
           'bulk_temperature_C = 40.0\n')


def copy_of(res: PipelineResult, dest: Path) -> tuple[Path, Path]:
    """A copy of an OUTDIR that keeps pointing at the same campaign (so it is reused)."""
    doc = json.loads(res.pipeline_json.read_text(encoding="utf-8"))
    shutil.copytree(res.outdir, dest)
    return Path(doc["campaign"]["path"]), dest


def test_run_prints_the_verdict_and_the_report(whole_run: PipelineResult, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    camp, out = copy_of(whole_run, tmp_path / "out")
    assert main(["run", str(camp), "-o", str(out)]) == 0
    cap = capsys.readouterr()
    assert cap.out.startswith("backlash c: ")
    for temp in ("30C", "105C"):
        assert f"c* at {temp}: " in cap.out
    for r in whole_run.runs:
        assert f"run {r.run_id}: " in cap.out
    assert f"report: {out / 'report.html'}" in cap.out
    assert "rigtools: ingest [4/4]" in cap.err  # stderr is not a terminal: log lines
    assert "reused" in cap.err


def test_quiet_prints_only_the_verdict(whole_run: PipelineResult, tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    camp, out = copy_of(whole_run, tmp_path / "out")
    assert main(["run", str(camp), "-o", str(out), "--quiet"]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    assert cap.out.startswith("backlash c: ")


def test_a_campaign_whose_runs_all_fail_exits_3_with_everything_written(
        demo_source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    camp = small_campaign(demo_source, tmp_path / "c", (), extra_runs=MISSING + GARBAGE)
    (camp.parent / "runs" / "junk.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\xff" * 300)
    out = tmp_path / "out"
    assert main(["run", str(camp), "-o", str(out)]) == 3
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("rigtools: error:")]
    assert len(lines) == 1
    assert "every run of the campaign failed (2)" in lines[0]
    assert "missing.mcap" in lines[0] and "junk.mcap" in lines[0]
    doc = json.loads((out / "pipeline.json").read_text(encoding="utf-8"))
    assert [r["status"] for r in doc["runs"]] == ["failed", "failed"]
    assert doc["stages"]["calibrate"]["status"] == "skipped"
    assert (out / "observations.parquet").is_file()
    assert not (out / "calibration" / "summary.json").exists()
    assert not list(out.rglob(f"*{TMP_MARKER}*"))


def test_an_outdir_that_is_a_file_exits_3_before_any_work(
        demo_source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "out"
    target.write_text("x")
    assert main(["run", str(tmp_path / "no-such-campaign.toml"), "-o", str(target)]) == 3
    assert "expected a folder, found a file" in capsys.readouterr().err
    assert target.read_text() == "x"


def test_an_outdir_that_cannot_be_written_exits_3_before_any_work(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    monkeypatch.setattr("rigtools.cli.common.os.access", lambda path, mode: False)
    assert main(["run", str(tmp_path / "no-such-campaign.toml"), "-o",
                 str(locked / "out")]) == 3
    assert "is not writable" in capsys.readouterr().err
    assert list(locked.iterdir()) == []


def test_a_full_disk_names_the_file_and_leaves_no_partial_file(
        demo_source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C",), accel=("accel_x",))

    def full_disk(rec: object, path: Path) -> Path:
        Path(path).write_bytes(b"PAR1 half a recording")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(run_tasks, "write_parquet", full_disk)
    out = tmp_path / "out"
    assert main(["run", str(camp), "-o", str(out)]) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("rigtools: error: ")
    assert "No space left on device" in err
    assert str(out / "ingest") in err and ".parquet" in err
    assert list((out / "ingest").glob("*.parquet")) == []
    assert list((out / "ingest").glob("*.key")) == []
    assert not list(out.rglob(f"*{TMP_MARKER}*"))
    assert not (out / "pipeline.json").exists()


def test_a_calibration_that_cannot_be_done_exits_3_and_the_report_is_written(
        demo_source: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    no_such_channel = CALIBRATION.replace("[calibration]\n",
                                          '[calibration]\nchannels = ["accel_q"]\n')
    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C", "LS9-105C"),
                          accel=("accel_x",), calibration=no_such_channel)
    out = tmp_path / "out"
    assert main(["run", str(camp), "-o", str(out)]) == 3
    cap = capsys.readouterr()
    errors = [ln for ln in cap.err.splitlines() if ln.startswith("rigtools: error:")]
    assert len(errors) == 1 and "calibration failed: " in errors[0]
    assert "no run of the observations table can be fitted" in errors[0]
    assert "accel_q" in errors[0]
    assert f"report: {out / 'report.html'}" in errors[0]
    doc = json.loads((out / "pipeline.json").read_text(encoding="utf-8"))
    assert doc["stages"]["calibrate"]["status"] == "failed"
    assert "accel_q" in doc["stages"]["calibrate"]["error"]
    assert [r["status"] for r in doc["runs"]] == ["ok", "ok"]
    assert (out / "report.html").is_file() and (out / "report.json").is_file()
    assert not (out / "calibration" / "summary.json").exists()
    assert not (out / "calibration" / "summary.key").exists()
