"""Partial OUTDIRs render: calibration failed or absent, runs failed, no spectra; bad JSON named."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import report_cases
from page_checks import scan

from rigtools.report import ReportInputError, build_report
from rigtools.schemas import iter_errors


def _valid(doc: dict) -> None:
    assert iter_errors(doc, "report.schema.json") == []


def test_calibration_failed(outdir_copy: Path) -> None:
    report_cases.drop_calibration(outdir_copy)
    paths = build_report(outdir_copy)
    doc = paths.content
    _valid(doc)
    assert doc["status"]["calibration"] == "failed"
    assert doc["calibration"] is None and doc["verdict"]["available"] is False
    assert doc["model_vs_experiment"]["rows"] == []
    assert any("4 walkers" in n for n in doc["notes"])
    html = paths.html.read_text(encoding="utf-8")
    assert "4 walkers for 4 free parameters" in html
    # the rest is still there: data quality and every run's spectrum
    assert len(doc["data_quality"]) == 3
    assert all(r["spectrum"]["available"] for r in doc["runs"])
    assert scan(html).tags.count("img") == 3


def test_stale_summary_of_a_failed_calibration_is_not_used(outdir_copy: Path) -> None:
    doc = json.loads((outdir_copy / "pipeline.json").read_text(encoding="utf-8"))
    doc["stages"]["calibrate"].update(status="failed", error="sampler killed")
    (outdir_copy / "pipeline.json").write_text(json.dumps(doc), encoding="utf-8")
    report_cases.drop_spectra(outdir_copy)
    content = build_report(outdir_copy).content
    _valid(content)
    assert content["calibration"] is None and content["verdict"]["available"] is False
    assert any("left over" in n for n in content["notes"])


def test_calibration_absent_without_a_stage_entry(outdir_copy: Path) -> None:
    report_cases.drop_spectra(report_cases.drop_calibration(outdir_copy))
    doc = json.loads((outdir_copy / "pipeline.json").read_text(encoding="utf-8"))
    del doc["stages"]["calibrate"]
    (outdir_copy / "pipeline.json").write_text(json.dumps(doc), encoding="utf-8")
    content = build_report(outdir_copy).content
    _valid(content)
    assert content["status"]["calibration"] == "absent"
    assert any("summary.json is absent" in n for n in content["notes"])


def test_failed_run_is_listed_with_why(outdir_copy: Path) -> None:
    why = "runs/ls7_55c.log at line 12: expected a candump line, found b'garbage'"
    report_cases.fail_run(outdir_copy, "LS7-55C", why)
    paths = build_report(outdir_copy)
    _valid(paths.content)
    entry = next(d for d in paths.content["data_quality"] if d["run_id"] == "LS7-55C")
    assert (entry["status"], entry["stage"], entry["error"]) == ("failed", "ingest", why)
    assert paths.content["status"]["n_runs_failed"] == 1
    assert not any("no spectrum file" in n for n in paths.content["notes"])
    text = " ".join(scan(paths.html.read_text(encoding="utf-8")).text)
    assert why in text


def test_no_spectra(outdir_copy: Path) -> None:
    report_cases.drop_spectra(report_cases.drop_calibration(outdir_copy))
    paths = build_report(outdir_copy)
    _valid(paths.content)
    assert paths.content["status"]["n_spectra"] == 0
    assert all(not r["spectrum"]["available"] for r in paths.content["runs"])
    assert sum("no spectrum file" in n for n in paths.content["notes"]) == 3
    assert "No spectrum for this run." in paths.html.read_text(encoding="utf-8")


def test_only_pipeline_json(bare_outdir: Path) -> None:
    paths = build_report(bare_outdir)
    _valid(paths.content)
    assert paths.content["data_quality"][0]["status"] == "failed"
    assert "no usable run" in paths.html.read_text(encoding="utf-8")


def test_no_pipeline_json_still_renders_what_there_is(outdir_copy: Path) -> None:
    (outdir_copy / "pipeline.json").unlink()
    report_cases.drop_spectra(outdir_copy)
    paths = build_report(outdir_copy)
    _valid(paths.content)
    assert paths.content["status"]["pipeline_json"] is False
    assert [r["run_id"] for r in paths.content["runs"]] == list(report_cases.KEEP)
    assert paths.content["verdict"]["available"] is True


def test_damaged_spectrum_is_noted_not_fatal(outdir_copy: Path) -> None:
    report_cases.drop_calibration(outdir_copy)
    victim = sorted((outdir_copy / "spectra").glob("*.parquet"))[0]
    victim.write_bytes(b"PAR1 not really")
    paths = build_report(outdir_copy)
    _valid(paths.content)
    assert paths.content["status"]["n_spectra"] == 2
    assert any(f"spectra/{victim.name} is unreadable" in n for n in paths.content["notes"])


@pytest.mark.parametrize("name", ["pipeline.json", "calibration/summary.json",
                                  "demo_truth.json", "ingest/{stem}.json"])
def test_malformed_json_names_the_file(outdir_copy: Path, name: str) -> None:
    stem = json.loads((outdir_copy / "pipeline.json").read_text(encoding="utf-8")
                      )["runs"][0]["stem"]
    path = outdir_copy / name.format(stem=stem)
    path.write_text('{"runs": [1, 2,\n', encoding="utf-8")
    with pytest.raises(ReportInputError, match=rf"^{path}: at line 2 column 1: expected valid "
                       r"JSON, found 'Expecting value'$".replace(": at", " at")):
        build_report(outdir_copy)
    assert not (outdir_copy / "report.html").exists()


def test_json_that_is_not_an_object(bare_outdir: Path) -> None:
    (bare_outdir / "pipeline.json").write_text("[1, 2]", encoding="utf-8")
    with pytest.raises(ReportInputError, match=r"pipeline.json: expected a JSON object, "
                       r"found a JSON list$"):
        build_report(bare_outdir)


def test_stem_that_leaves_outdir_is_not_followed(bare_outdir: Path) -> None:
    doc = json.loads((bare_outdir / "pipeline.json").read_text(encoding="utf-8"))
    doc["runs"][0]["stem"] = "../../etc/passwd"
    (bare_outdir / "pipeline.json").write_text(json.dumps(doc), encoding="utf-8")
    content = build_report(bare_outdir).content
    assert any("not a plain file name" in n for n in content["notes"])
