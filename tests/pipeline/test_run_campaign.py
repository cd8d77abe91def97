"""run_campaign: cached stages, failed runs that do not stop the others, one result per engine."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from pipeline_cases import small_campaign

from rigtools.campaign import read_observations
from rigtools.demo.campaign import generate_demo_campaign
from rigtools.pipeline import PipelineError, run_campaign, run_file_stem
from rigtools.pipeline.atomic import TMP_MARKER

UP_TO_CALIBRATION = ("ingest", "observe", "calibrate")
VOLATILE_COUNTS = ("reused", "computed")


def snapshot(out: Path) -> dict[str, bytes]:
    """Every file of OUTDIR but pipeline.json and the report, by relative path."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.name not in ("pipeline.json", "report.json", "report.html")}


def _drop(doc: Any, path: list[str]) -> None:
    """Remove the field at a dotted ``path`` (``*`` matches every key) from ``doc``."""
    if not isinstance(doc, dict):
        return
    head, rest = path[0], path[1:]
    keys = list(doc) if head == "*" else [head]
    for k in keys:
        if k not in doc:
            continue
        if rest:
            _drop(doc[k], rest)
        else:
            del doc[k]


def without_volatile_report_fields(doc: dict[str, Any]) -> dict[str, Any]:
    """report.json without the fields its schema lists in ``volatile_fields``."""
    schema = json.loads((Path(__file__).parents[2] / "data_schemas" / "report.schema.json")
                        .read_text(encoding="utf-8"))
    for field in schema["volatile_fields"]:
        _drop(doc, field.split("."))
    return doc


def stable(doc: Any) -> Any:
    """pipeline.json without its volatile fields and the reuse counts."""
    if isinstance(doc, dict):
        return {k: stable(v) for k, v in doc.items()
                if k != "generated_at" and not k.endswith("elapsed_s")
                and k not in VOLATILE_COUNTS}
    if isinstance(doc, list):
        return [stable(v) for v in doc]
    return doc


def pipeline_json(out: Path) -> dict[str, Any]:
    return json.loads((out / "pipeline.json").read_text(encoding="utf-8"))


def no_temporaries(out: Path) -> list[str]:
    return [str(p) for p in out.rglob(f"*{TMP_MARKER}*")]


def test_rerun_reuses_everything_and_a_changed_recording_is_redone_alone(
        demo_source: Path, tmp_path: Path) -> None:
    camp = small_campaign(demo_source, tmp_path / "c")
    out = tmp_path / "out"
    first = run_campaign(camp, out, progress=False)
    assert [r.status for r in first.runs] == ["ok"] * 4
    assert first.stages["ingest"]["computed"] == first.stages["observe"]["computed"] == 4
    assert first.calibration_status == "ok" and first.summary is not None
    for r in first.runs:
        assert r.stem == run_file_stem(r.run_id)
        for f in (f"ingest/{r.stem}.parquet", f"ingest/{r.stem}.json",
                  f"spectra/{r.stem}.parquet"):
            assert (out / f).is_file(), f
    for f in ("summary.json", "summary.csv", "posterior.nc", "chains.h5", "corner.png",
              "traces.png", "f_n_vs_torque.png", "stiffness_vs_torque.png"):
        assert (out / "calibration" / f).is_file(), f
    before, doc_before = snapshot(out), pipeline_json(out)
    report_before = json.loads((out / "report.json").read_text(encoding="utf-8"))

    again = run_campaign(camp, out, progress=False)
    assert again.stages["ingest"]["reused"] == again.stages["observe"]["reused"] == 4
    assert again.stages["ingest"]["computed"] == again.stages["observe"]["computed"] == 0
    assert again.stages["calibrate"]["reused"] is True
    assert snapshot(out) == before, "a re-run with nothing changed must not change a byte"
    assert stable(pipeline_json(out)) == stable(doc_before)
    assert again.summary == first.summary
    # the report: identical apart from what its schema marks volatile (issue 19 item 3)
    report_after = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert report_after != report_before                  # generated_at, times, reuse counts
    assert without_volatile_report_fields(report_after) == \
        without_volatile_report_fields(report_before)

    # another recording of the same run (another seed of the demo): only that run is redone
    other = generate_demo_campaign(tmp_path / "other", size="ci", seed=4, duration_s=1.0,
                                   runup=False)
    changed = "LS9-30C"
    shutil.copyfile(other.run_files[changed], camp.parent / "runs" / "ls9_30c.mcap")
    third = run_campaign(camp, out, stages=UP_TO_CALIBRATION, progress=False)
    assert third.stages["ingest"]["computed"] == third.stages["observe"]["computed"] == 1
    assert third.stages["ingest"]["reused"] == third.stages["observe"]["reused"] == 3
    assert third.stages["calibrate"]["reused"] is False
    assert third.calibration_status == "ok"
    after = snapshot(out)
    for r in third.runs:
        for f in (f"ingest/{r.stem}.parquet", f"spectra/{r.stem}.parquet"):
            assert (after[f] == before[f]) == (r.run_id != changed), f
    assert after["observations.parquet"] != before["observations.parquet"]
    assert no_temporaries(out) == []


def test_runs_that_fail_are_listed_with_why_and_the_others_go_on(
        demo_source: Path, tmp_path: Path) -> None:
    extra = ('\n[[run]]\nid = "gone"\nfile = "runs/missing.mcap"\ntorque_Nm = 100.0\n'
             'bulk_temperature_C = 40.0\n'
             '\n[[run]]\nid = "junk/<b>"\nfile = "runs/junk.blf"\ntorque_Nm = 100.0\n'
             'bulk_temperature_C = 40.0\n')
    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C",), extra_runs=extra,
                          accel=("accel_x",))
    (camp.parent / "runs" / "junk.blf").write_bytes(b"LOGG" + bytes(range(256)) * 8)
    out = tmp_path / "out"
    res = run_campaign(camp, out, stages=("ingest", "observe"), progress=False)
    by_id = {r.run_id: r for r in res.runs}
    assert by_id["LS9-30C"].status == "ok"
    for rid, file in (("gone", "missing.mcap"), ("junk/<b>", "junk.blf")):
        r = by_id[rid]
        assert (r.status, r.stage) == ("failed", "ingest")
        assert file in (r.error or ""), r.error
        doc = json.loads((out / "ingest" / f"{r.stem}.json").read_text(encoding="utf-8"))
        assert doc["status"] == "failed" and file in doc["error"]
        assert not (out / "ingest" / f"{r.stem}.parquet").exists()
    assert by_id["gone"].source_sha256 is None
    runs = {r["run_id"]: r for r in pipeline_json(out)["runs"]}
    assert runs["junk/<b>"]["status"] == "failed" and "junk.blf" in runs["junk/<b>"]["error"]
    assert runs["junk/<b>"]["stem"] == run_file_stem("junk/<b>")
    table = read_observations(out / "observations.parquet")
    run_rows = table[table["quantity"] == "run"].set_index("run_id")
    assert run_rows.loc["gone", "status"] == "failed"
    assert "missing.mcap" in run_rows.loc["gone", "message"]
    assert run_rows.loc["LS9-30C", "status"] in ("ok", "flagged")
    assert (table["run_id"] == "LS9-30C").sum() > 1


def test_an_outdir_that_is_a_file_is_refused_before_any_work(demo_source: Path,
                                                             tmp_path: Path) -> None:
    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C",))
    target = tmp_path / "out"
    target.write_text("not a folder")
    with pytest.raises(PipelineError, match="expected a folder, found a file"):
        run_campaign(camp, target, progress=False)
    with pytest.raises(PipelineError, match="is a file"):
        run_campaign(camp, target / "sub", progress=False)


def test_stages_must_come_in_order(demo_source: Path, tmp_path: Path) -> None:
    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C",))
    with pytest.raises(PipelineError, match="`stages` must be the first stages"):
        run_campaign(camp, tmp_path / "out", stages=("ingest", "calibrate"))
    assert not (tmp_path / "out").exists()


def test_process_pool_and_dask_give_the_serial_results(demo_source: Path,
                                                       tmp_path: Path) -> None:
    camp = small_campaign(demo_source, tmp_path / "c", ("LS3-30C", "LS9-30C"),
                          accel=("accel_x",))
    outs = {}
    for name, kw in (("serial", {}), ("pool", {"jobs": 2}), ("dask", {"dask": "local"})):
        outs[name] = tmp_path / name
        res = run_campaign(camp, outs[name], stages=("ingest", "observe"), progress=False,
                           **kw)
        assert [r.status for r in res.runs] == ["ok", "ok"], name
    serial = read_observations(outs["serial"] / "observations.parquet")
    for name in ("pool", "dask"):
        pd.testing.assert_frame_equal(
            read_observations(outs[name] / "observations.parquet"), serial, check_exact=True)
        a, b = snapshot(outs["serial"]), snapshot(outs[name])
        assert a.keys() == b.keys()
        for f in a:
            if f.startswith(("spectra/", "observe/", "ingest/")) and f.endswith(".parquet"):
                assert a[f] == b[f], f"{name}: {f} differs from the serial run's"
    settings = pipeline_json(outs["dask"])["settings"]
    assert settings == {"jobs": 1, "dask": "local", "seed": None}


def test_a_bug_while_reading_fails_the_run_without_caching_it(
        demo_source: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A reader bug (not bad input) is a failed run, but the next run tries the file again."""
    import rigtools.pipeline.run_tasks as run_tasks

    camp = small_campaign(demo_source, tmp_path / "c", ("LS9-30C",), accel=("accel_x",))
    out = tmp_path / "out"
    real = run_tasks.read_run

    def buggy(*args: Any, **kwargs: Any) -> Any:
        raise TypeError("a bug in a reader")

    monkeypatch.setattr(run_tasks, "read_run", buggy)
    first = run_campaign(camp, out, stages=("ingest",), progress=False)
    (run,) = first.runs
    assert run.status == "failed" and "internal error TypeError" in (run.error or "")
    assert not list((out / "ingest").glob("*.key"))
    monkeypatch.setattr(run_tasks, "read_run", real)
    again = run_campaign(camp, out, stages=("ingest",), progress=False)
    assert again.runs[0].status == "ok" and again.stages["ingest"]["computed"] == 1
