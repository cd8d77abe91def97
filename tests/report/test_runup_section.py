"""The report's run-up section (issue 20) from a fake ``calibration/runup`` folder.

The folder is written here from a small fixture in the layout of
``rigtools.calibration.runup_outputs`` (comparison.json as ``RunUpResult.comparison_dict``,
``<model>/summary.json`` as the run-up summary, one PNG per run named after the pipeline's
stem), not by a real calibration: the section's numbers, the schema, the escaping, the
truth beside the posterior, the section's absence without run-ups and a failed run-up part.
"""

from __future__ import annotations

import json
import struct
import zlib
from pathlib import Path
from typing import Any

import pytest
import report_cases
from page_checks import scan

from rigtools.report import build_report
from rigtools.schemas import iter_errors, load_schema

RUN = "KB-runup-300Nm"
HOSTILE_RUN = '<script>alert(1)</script>" onerror="alert(1)'


def _png() -> bytes:
    """A valid 1 x 1 PNG."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    ihdr = struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
            + chunk(b"IDAT", zlib.compress(b"\x00\xff\x00\x00")) + chunk(b"IEND", b""))


def _q(mean: float | None, sd: float, q05: float | None, q50: float | None,
       q95: float | None, unit: str, identified: bool | None = True,
       statement: str | None = None) -> dict[str, Any]:
    return {"mean": mean, "sd": sd, "q05": q05, "q50": q50, "q95": q95, "unit": unit,
            "ess_bulk": 812.0, "r_hat": 1.004, "identified": identified, "prior": "x",
            "prior_sd": 1.0, "statement": statement}


NO_BACKSIDE = ("no back-side contact in any posterior draw: the run-up does not identify the "
               "backlash (posterior probability of a back-side impact 0.000)")


def _summary(model: str, f_n: float, zeta: float, runs: list[str]) -> dict[str, Any]:
    return {
        "model": model, "converged": model != "fvms",
        "parameters": {
            "zeta": _q(zeta, 0.001, zeta - 0.002, zeta, zeta + 0.002, "1"),
            "mesh_stiffness_scale": _q(0.9, 0.01, 0.88, 0.9, 0.92, "1"),
            "fluctuation_scale": _q(None, 0.29, None, None, None, "1", False,
                                    "the data do not identify fluctuation_scale"),
            "backlash": _q(None, 86.0, None, None, None, "um", False, NO_BACKSIDE),
            "model_error": _q(0.05, 0.004, 0.044, 0.05, 0.057, "1"),
        },
        "identified": {"zeta": True, "backlash": False},
        "derived": {
            "mesh_natural_frequency_Hz": _q(f_n, 12.0, f_n - 20, f_n, f_n + 20, "Hz"),
            **{f"mesh_natural_frequency_Hz@{r}": _q(f_n + 40, 12.0, f_n + 20, f_n + 40,
                                                    f_n + 60, "Hz") for r in runs},
        },
        "gains": {f"{r}/accel_x": {"mean": 0.0101, "sd": 1e-4, "q05": 0.0099, "q50": 0.0101,
                                   "q95": 0.0103, "unit": "1"} for r in runs},
        "backlash": {"backside_impact_probability": 0.0, "identified": False,
                     "statement": NO_BACKSIDE},
        "runs": {r: {"gear_set": "kahraman-blankenship", "torque_Nm": 300.0,
                     "channels": ["accel_x"], "mesh_frequency_range_Hz": [1700.0, 4500.0],
                     "points": 180,
                     "jump_measured_Hz": {"up": 3350.0, "down": None},
                     "jump_model_Hz": {"up": {"q05": 3300.0, "q50": 3340.0, "q95": 3390.0},
                                       "down": None},
                     "backside_impact_probability": 0.0, "contact_loss_probability": 0.97}
                 for r in runs},
        "conventions": {"k_ref": "k_ref = s kbar_F0"},
        "warnings": [f"backlash: {NO_BACKSIDE}"],
    }


def _comparison(runs: list[str], statement: str) -> dict[str, Any]:
    def row(elpd: float, diff: float, dse: float, rank: int) -> dict[str, Any]:
        return {"elpd_loo": elpd, "se": 11.0, "p_loo": 5.2, "pareto_k_max": 0.41,
                "n_pareto_k_bad": 0, "elpd_diff": diff, "dse": dse, "weight": 0.5,
                "rank": rank}

    point = {"criterion": "psis-loo", "variants": {"vvms": row(412.5, 0.0, 0.0, 0),
                                                   "fvms": row(371.0, 41.5, 9.1, 1)},
             "favoured": "vvms", "statement": "the data favour vvms"}
    return {"criterion": "psis-loo", "models": ["vvms", "fvms"], "pointwise": point,
            "blocked": {**point, "statement": "blocked: the data favour vvms"},
            "favoured": "vvms", "statement": statement, "runs": runs,
            "refused": {"KB-short": "too few speed points (12 < 20)"}}


def _pipeline(runs: list[str], runup: dict[str, Any] | None) -> dict[str, Any]:
    calibrate: dict[str, Any] = {"key": "", "elapsed_s": 0.0, "reused": False,
                                 "status": "failed", "error": "no usable run"}
    if runup is not None:
        calibrate["runup"] = runup
    return {"format": "rigtools pipeline", "rigtools_version": "0.1.0",
            "generated_at": "2026-11-27T04:00:00+00:00",
            "campaign": {"path": "c.toml", "name": "runup", "sha256": "0" * 64,
                         "resolved": {"campaign": {"name": "runup"}, "run": []}},
            "settings": {"jobs": 1, "dask": None, "seed": None},
            "runs": [{"run_id": r, "stem": report_cases.file_stem(r), "file": "r.mcap",
                      "source_sha256": None, "status": "ok", "stage": None, "error": None,
                      "ingest_key": "a", "observe_key": "b"} for r in runs],
            "stages": {"calibrate": calibrate}, "versions": {"python": "3"}}


def make_outdir(base: Path, *, runs: tuple[str, ...] = (RUN,), status: str | None = "ok",
                statement: str = "the data favour vvms: elpd_loo 412.5 against fvms 371.0",
                truth: bool = True, files: bool = True) -> Path:
    """An OUTDIR with pipeline.json, a fake calibration/runup folder and a demo truth."""
    out = base / "out"
    out.mkdir(parents=True)
    runup = None if status is None else {
        "status": status, "error": "no usable run-up for the SDOF calibration (KB: too few "
                                   "speed points)" if status == "failed" else None,
        "key": "k", "reused": False, "elapsed_s": 1.0, "models": [], "runs": [],
        "n_warnings": 0}
    (out / "pipeline.json").write_text(json.dumps(_pipeline(list(runs), runup)),
                                       encoding="utf-8")
    if files:
        folder = out / "calibration" / "runup"
        for model, f_n, zeta in (("vvms", 3210.0, 0.025), ("fvms", 3080.0, 0.031)):
            (folder / model).mkdir(parents=True)
            (folder / model / "summary.json").write_text(
                json.dumps(_summary(model, f_n, zeta, list(runs))), encoding="utf-8")
        (folder / "comparison.json").write_text(json.dumps(_comparison(list(runs), statement)),
                                                encoding="utf-8")
        for r in runs:
            (folder / f"runup_{report_cases.file_stem(r)}.png").write_bytes(_png())
    if truth:
        block = {"run_id": runs[0], "model": "vvms", "torque_Nm": 300.0,
                 "parameters": {"zeta": {"value": 0.025, "unit": "1"},
                                "mesh_stiffness_scale": {"value": 0.9, "unit": "1"},
                                "backlash": {"value": 136.0, "unit": "um"},
                                "gain@accel_x": {"value": 0.0101, "unit": "1"}},
                 "derived": {"mesh_natural_frequency_Hz": {"value": 3215.0, "unit": "Hz"},
                             f"jump_frequency_up_Hz@{runs[0]}": {"value": 3345.0,
                                                                  "unit": "Hz"}},
                 "backside_impact": False}
        (out / "demo_truth.json").write_text(json.dumps({"runup": block}), encoding="utf-8")
    return out


def test_section_numbers_schema_and_page(tmp_path: Path) -> None:
    paths = build_report(make_outdir(tmp_path))
    doc = paths.content
    assert iter_errors(doc, "report.schema.json") == []
    ru = doc["runup_calibration"]
    assert ru["status"] == "ok" and ru["models"] == ["vvms", "fvms"]
    cmp = ru["comparison"]
    assert cmp["favoured"] == "vvms" and cmp["statement"].startswith("the data favour vvms")
    assert [r["model"] for r in cmp["rows"]] == ["vvms", "fvms"]
    fvms = cmp["rows"][1]
    assert (fvms["elpd_loo"], fvms["se"], fvms["elpd_diff"], fvms["dse"],
            fvms["pareto_k_max"]) == (371.0, 11.0, 41.5, 9.1, 0.41)
    assert cmp["refused"] == {"KB-short": "too few speed points (12 < 20)"}
    vv = ru["fits"][0]
    assert vv["model"] == "vvms"
    assert (vv["zeta"]["q05"], vv["zeta"]["q95"], vv["zeta"]["identified"]) == \
        (pytest.approx(0.023), pytest.approx(0.027), True)
    assert vv["mesh_natural_frequency_Hz"]["q50"] == 3210.0
    assert vv["mesh_natural_frequency_Hz"]["identified"] is True
    assert vv["backlash"]["identified"] is False
    assert vv["backlash"]["statement"] == NO_BACKSIDE
    (run,) = vv["runs"]
    assert run["jump_measured_up_Hz"] == 3350.0 and run["jump_measured_down_Hz"] is None
    assert run["jump_model_up_Hz"] == {"q05": 3300.0, "q50": 3340.0, "q95": 3390.0}
    assert run["mesh_natural_frequency_Hz"]["q50"] == 3250.0
    assert ru["figures"] == [{"run_id": RUN, "key": f"runup:{RUN}"}]
    # the truth beside each model's posterior
    truth = {q["name"]: q for q in ru["truth"]["quantities"]}
    assert truth["zeta"]["models"]["vvms"]["covered"] is True
    assert truth["mesh_natural_frequency_Hz"]["models"]["vvms"]["covered"] is True
    assert truth["mesh_natural_frequency_Hz"]["models"]["fvms"]["covered"] is False
    assert truth["backlash"]["models"]["vvms"]["covered"] is None  # not identified: no interval
    assert truth["gain@accel_x"]["models"]["vvms"]["covered"] is True
    assert truth[f"jump_frequency_up_Hz@{RUN}"]["models"]["vvms"]["covered"] is True
    html = paths.html.read_text(encoding="utf-8")
    assert "Run-up calibration (SDOF models)" in html
    assert NO_BACKSIDE in html
    page = scan(html)
    n_img = sum(1 for t in page.tags if t == "img")
    assert n_img == 1  # the run's figure (no other calibration here)
    assert any(v and v.startswith("data:image/png;base64,") for t, k, v in page.attrs
               if t == "img" and k == "src")


def test_markup_from_runs_and_statements_is_text(tmp_path: Path) -> None:
    hostile = '<img src=x onerror="alert(1)"><script>alert(1)</script>'
    out = make_outdir(tmp_path, runs=(HOSTILE_RUN,), statement=hostile)
    paths = build_report(out)
    assert iter_errors(paths.content, "report.schema.json") == []
    assert paths.content["runup_calibration"]["comparison"]["statement"] == hostile
    html = paths.html.read_text(encoding="utf-8")
    page = scan(html)
    assert "script" not in page.tags
    assert page.event_handlers == []
    assert page.external_urls == []
    text = "".join(page.text)
    assert hostile in text and HOSTILE_RUN in text
    assert "<script>" not in html


def test_section_absent_without_runups(tmp_path: Path, bare_outdir: Path) -> None:
    for out in (bare_outdir, make_outdir(tmp_path, status="skipped", files=False,
                                         truth=False)):
        paths = build_report(out)
        assert "runup_calibration" not in paths.content
        assert iter_errors(paths.content, "report.schema.json") == []
        html = paths.html.read_text(encoding="utf-8")
        assert "Run-up calibration" not in html


def test_failed_runup_part_is_reported_and_old_files_not_used(tmp_path: Path) -> None:
    paths = build_report(make_outdir(tmp_path, status="failed"))
    assert iter_errors(paths.content, "report.schema.json") == []
    ru = paths.content["runup_calibration"]
    assert ru["status"] == "failed" and "no usable run-up" in ru["error"]
    assert ru["fits"] == [] and ru["comparison"] is None and ru["figures"] == []
    assert any("left over" in n for n in ru["notes"])
    assert any(n.startswith("run-up calibration failed") for n in paths.content["notes"])
    html = paths.html.read_text(encoding="utf-8")
    assert "The run-up calibration failed" in html
    assert sum(1 for t in scan(html).tags if t == "img") == 0


def test_files_without_pipeline_status_are_reported(tmp_path: Path) -> None:
    """A report built from the files alone (no run-up status in pipeline.json)."""
    paths = build_report(make_outdir(tmp_path, status=None, truth=False))
    ru = paths.content["runup_calibration"]
    assert ru["status"] == "ok" and ru["truth"] is None
    assert iter_errors(paths.content, "report.schema.json") == []


def test_schema_marks_the_runup_part_volatile() -> None:
    schema = load_schema("report.schema.json")
    assert "provenance.stages.calibrate.runup.elapsed_s" in schema["volatile_fields"]
    assert "provenance.stages.calibrate.runup.reused" in schema["volatile_fields"]
    assert "runup_calibration" not in schema["required"]
