"""``rigtools report OUTDIR``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rigtools.cli import main
from rigtools.schemas import iter_errors


def test_rebuilds_the_report(bare_outdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(bare_outdir)]) == 0
    out = capsys.readouterr().out
    assert f"report: {bare_outdir / 'report.html'}" in out
    doc = json.loads((bare_outdir / "report.json").read_text(encoding="utf-8"))
    assert iter_errors(doc, "report.schema.json") == []


def test_no_pipeline_json_is_exit_3_with_one_line(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(tmp_path)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith(f"rigtools: error: {tmp_path}: expected pipeline.json")
    assert not (tmp_path / "report.html").exists()


def test_missing_folder_is_exit_3(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(tmp_path / "nope")]) == 3
    assert "found no such folder" in capsys.readouterr().err


def test_malformed_json_is_exit_3_naming_the_file(bare_outdir: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    (bare_outdir / "pipeline.json").write_text("{", encoding="utf-8")
    assert main(["report", str(bare_outdir)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{bare_outdir / 'pipeline.json'} at line 1 column 2: expected valid JSON" in err
