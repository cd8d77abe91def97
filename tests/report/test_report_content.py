"""The report of a complete demo OUTDIR: the schema, the numbers and a self-contained page."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import report_cases
from page_checks import scan

from rigtools.report import ReportPaths
from rigtools.report.assessment import DEFAULT_TOLERANCES
from rigtools.schemas import iter_errors


def _summary(outdir: Path) -> dict:
    return json.loads((outdir / "calibration" / "summary.json").read_text(encoding="utf-8"))


def test_report_json_is_valid_against_its_schema(demo_report: ReportPaths) -> None:
    doc = json.loads(demo_report.json.read_text(encoding="utf-8"))
    assert iter_errors(doc, "report.schema.json") == []
    assert doc == demo_report.content


def test_schema_marks_the_volatile_fields() -> None:
    from rigtools.schemas import load_schema

    schema = load_schema("report.schema.json")
    assert schema["properties"]["generated_at"]["volatile"] is True
    assert "provenance.stages.*.elapsed_s" in schema["volatile_fields"]
    stage = schema["properties"]["provenance"]["properties"]["stages"]["additionalProperties"]
    assert stage["properties"]["elapsed_s"]["volatile"] is True


def test_calibration_summary_is_embedded_as_written(demo_report: ReportPaths) -> None:
    assert demo_report.content["calibration"] == _summary(demo_report.json.parent)
    assert demo_report.content["demo_truth"] == json.loads(
        (demo_report.json.parent / "demo_truth.json").read_text(encoding="utf-8"))


def test_verdict_carries_the_posterior(demo_report: ReportPaths) -> None:
    summary = _summary(demo_report.json.parent)
    v = demo_report.content["verdict"]
    assert v["available"] is True
    assert v["backlash_um"]["q05"] == summary["parameters"]["backlash"]["q05"]
    assert v["backlash_um"]["q95"] == summary["parameters"]["backlash"]["q95"]
    temps = [g["temperature_C"] for g in v["critical_gaps"]]
    assert temps == sorted(temps) == [30.0, 55.0, 105.0]
    for g in v["critical_gaps"]:
        key = f"critical_gap@{g['temperature_C']:g}C"
        assert g["critical_gap_um"]["q50"] == summary["derived"][key]["q50"], key
    assert [r["run_id"] for r in v["runs"]] == list(report_cases.KEEP)
    for r in v["runs"]:
        s = summary["runs"][r["run_id"]]
        assert (r["regime"], r["regime_probability"]) == (s["regime"], s["regime_probability"])
        assert r["margin_um"]["mean"] == summary["derived"][f"margin@{r['run_id']}"]["mean"]
    assert v["favoured_model"] == summary["model_comparison"]["favoured"]
    flip = summary["derived"]["flip_temperature_C"]
    assert v["flip_temperature_C"]["q50"] == flip["q50"]


def test_report_checks_follow_the_report_block(demo_report: ReportPaths) -> None:
    v = demo_report.content["verdict"]
    checks = {c["name"]: c for c in v["checks"]}
    lo, hi = report_cases.REPORT_BLOCK["backlash_range_um"]
    b = v["backlash_um"]
    assert checks["backlash_range_um"]["pass"] is (b["q05"] >= lo and b["q95"] <= hi)
    m = v["operating_margin_um"]
    assert checks["min_margin_um"]["pass"] is (m["q05"] >= report_cases.REPORT_BLOCK[
        "min_margin_um"])


def test_model_versus_experiment_pass_fail(demo_report: ReportPaths) -> None:
    summary = _summary(demo_report.json.parent)
    mve = demo_report.content["model_vs_experiment"]
    sigma_m = summary["parameters"]["model_error"]["mean"]
    rows = {r["run_id"]: r for r in mve["rows"]}
    assert set(rows) == set(report_cases.KEEP)
    for rid, row in rows.items():
        s = summary["runs"][rid]
        pred = s["predicted_f_n_Hz"]
        assert row["measured_f_n_Hz"] == s["mesh_mode_Hz"]
        rel = abs(s["mesh_mode_Hz"] - pred["mean"]) / pred["mean"]
        sd = math.hypot((pred["q95"] - pred["q05"]) / 3.289707253902945, sigma_m * pred["mean"])
        z = abs(s["mesh_mode_Hz"] - pred["mean"]) / sd
        assert row["rel_error"] == pytest.approx(rel, rel=1e-12)
        assert row["z"] == pytest.approx(z, rel=1e-9)
        assert row["pass"] is (rel <= 0.02 and z <= 3.0), rid
    assert mve["n_pass"] + mve["n_fail"] + mve["n_untested"] == len(rows)


def test_default_tolerances_without_a_report_block(outdir_copy: Path) -> None:
    from rigtools.report import build_report

    doc = json.loads((outdir_copy / "pipeline.json").read_text(encoding="utf-8"))
    doc["campaign"]["resolved"]["report"] = {"f_n_rel_tolerance": 0.5}
    (outdir_copy / "pipeline.json").write_text(json.dumps(doc), encoding="utf-8")
    (outdir_copy / "spectra").rename(outdir_copy / "spectra-hidden")  # quicker: no spectra
    tol = build_report(outdir_copy).content["model_vs_experiment"]["tolerances"]
    assert tol == {"f_n_rel_tolerance": 0.5, "f_n_z_tolerance": DEFAULT_TOLERANCES[
        "f_n_z_tolerance"], "source": {"f_n_rel_tolerance": "campaign",
                                       "f_n_z_tolerance": "default"}}


def test_every_run_shows_its_peaks_and_the_mesh_mode(demo_report: ReportPaths) -> None:
    summary = _summary(demo_report.json.parent)
    for run in demo_report.content["runs"]:
        s = summary["runs"][run["run_id"]]
        assert run["spectrum"]["available"] is True
        assert run["spectrum"]["channels"] == ["accel_x", "accel_y", "accel_z"]
        taken = [p for p in run["peaks"] if p["mesh_mode"]]
        if s["mesh_mode_Hz"] is None:
            assert taken == []
        else:
            assert len(taken) == 1
            assert taken[0]["channel"] == s["mesh_mode_channel"]
            assert taken[0]["f_n_Hz"] == pytest.approx(s["mesh_mode_Hz"], rel=1e-9)
        assert len(run["peaks"]) >= 2


def test_data_quality_counts_come_from_the_ingest_summaries(demo_report: ReportPaths) -> None:
    out = demo_report.json.parent
    pipeline = json.loads((out / "pipeline.json").read_text(encoding="utf-8"))
    for entry, run in zip(demo_report.content["data_quality"], pipeline["runs"], strict=True):
        ing = json.loads((out / "ingest" / f"{run['stem']}.json").read_text(encoding="utf-8"))
        assert entry["run_id"] == run["run_id"]
        for key in ("n_decoded", "n_rejected", "n_gaps", "n_missing_samples", "rejected"):
            assert entry["ingest"][key] == ing[key], key
    assert any(e["ingest"]["n_gaps"] > 0 for e in demo_report.content["data_quality"]), \
        "the demo's CAN runs drop frames: at least one run shows gaps"


def test_convergence_and_provenance(demo_report: ReportPaths) -> None:
    summary = _summary(demo_report.json.parent)
    cv = demo_report.content["convergence"]
    assert cv["walkers"] == summary["sampler"]["walkers"] == 16
    assert cv["acceptance_fraction"] == summary["sampler"]["acceptance_fraction"]
    assert {p["name"] for p in cv["parameters"]} == set(summary["parameters"])
    for p in cv["parameters"]:
        assert p["r_hat"] == summary["parameters"][p["name"]]["r_hat"]
        assert p["tau_steps"] == summary["sampler"]["tau"][p["name"]]
    pv = demo_report.content["provenance"]
    assert pv["seeds"] == {"pipeline": 7, "calibration": summary["config"]["seed"],
                           "sampler": summary["sampler"]["seed"]}
    assert all(len(i["source_sha256"]) == 64 for i in pv["inputs"])
    assert pv["resolved_configuration"]["report"] == report_cases.REPORT_BLOCK


def test_truth_beside_the_posterior(demo_report: ReportPaths) -> None:
    tc = demo_report.content["truth_comparison"]
    names = {q["name"] for q in tc["quantities"]}
    assert {"backlash", "critical_gap@105C", "flip_temperature_C"} <= names
    assert all(q["posterior"] is not None for q in tc["quantities"])
    assert [r["run_id"] for r in tc["runs"]] == list(report_cases.KEEP)


def test_page_is_self_contained_and_has_no_script(demo_report: ReportPaths) -> None:
    html = demo_report.html.read_text(encoding="utf-8")
    page = scan(html)
    assert page.external_urls == []
    assert "script" not in page.tags
    assert page.event_handlers == []
    assert "link" not in page.tags and "iframe" not in page.tags
    assert "@import" not in html and "url(" not in html
    imgs = [a for a in page.attrs if a[0] == "img" and a[1] == "src"]
    # verdict + one spectrum per run + four calibration figures
    assert len(imgs) == 1 + len(report_cases.KEEP) + 4
    assert all((v or "").startswith("data:image/png;base64,") for _, _, v in imgs)


def test_page_shows_the_numbers_of_report_json(demo_report: ReportPaths) -> None:
    from rigtools.report.html import format_interval, format_number

    text = " ".join(scan(demo_report.html.read_text(encoding="utf-8")).text)
    v = demo_report.content["verdict"]
    assert format_interval(v["backlash_um"]) in text
    for g in v["critical_gaps"]:
        assert format_interval(g["critical_gap_um"]) in text
    for row in demo_report.content["model_vs_experiment"]["rows"]:
        assert format_number(row["measured_f_n_Hz"], 5) in text
