"""The content of ``report.json``: every number the page shows, computed from the stage files.

Sections (schema ``data_schemas/report.schema.json``):

``verdict``, ``model_vs_experiment``, ``convergence``
    The calibration judged against the campaign's ``[report]`` checks and tolerances and its
    own convergence tolerances: :mod:`rigtools.report.assessment`.
``data_quality``
    Per recording: decoded and rejected counts by reason, gaps, warnings, the pipeline's status
    and, for a failed run, the stage and why.
``runs``
    Per run: conditions, the peaks found (observations ``natural_frequency`` rows), the peak
    taken as the mesh mode (calibration summary ``runs.<id>.mesh_mode_Hz`` and
    ``mesh_mode_channel``), the predicted natural frequency, and what spectra there are.
``provenance``
    Campaign file and hash, the recordings' hashes, versions, the resolved configuration and
    every seed.
``calibration``
    The calibration's ``summary.json`` as written (null when the calibration is absent or
    failed); ``demo_truth`` and ``truth_comparison`` (:mod:`rigtools.report.assessment`) for
    the demo.
``runup_calibration``
    Only when the campaign has a run-up calibration (issue 20): the SDOF models compared,
    their damping and mesh natural frequency, the backlash statement, the figures and the
    demo's truth beside them (:mod:`rigtools.report.runup_section`).

Numbers that are not finite become null (:mod:`rigtools.report.values`). Strings from
recordings and campaigns are carried as they are; the page escapes them.
"""

from __future__ import annotations

from dataclasses import replace
from datetime import UTC, datetime
from typing import Any, Final

from rigtools import __version__
from rigtools.report.assessment import (
    convergence,
    model_vs_experiment,
    report_settings,
    truth_comparison,
    verdict,
)
from rigtools.report.inputs import CALIBRATION_FIGURES, ReportInputs, run_list
from rigtools.report.runup_section import RunUpInputs, runup_section
from rigtools.report.values import as_dict, as_float, as_int, as_str, plain

__all__ = [
    "FORMAT",
    "SCHEMA",
    "SCHEMA_VERSION",
    "report_content",
]

#: ``format`` of report.json.
FORMAT: Final = "rigtools report"
#: Schema file of report.json in ``data_schemas/``.
SCHEMA: Final = "report.schema.json"
SCHEMA_VERSION: Final = 1


# --------------------------------------------------------------------------------------------
# sections


def _calibration_status(inputs: ReportInputs) -> dict[str, Any]:
    stage = as_dict(as_dict(as_dict(inputs.pipeline).get("stages")).get("calibrate"))
    status = as_str(stage.get("status"))
    error = as_str(stage.get("error"))
    if inputs.summary is not None and status in (None, "ok"):
        state = "ok"
    elif status in ("failed", "skipped"):
        state = status
    else:
        state = "absent"
    if state == "absent" and error is None:
        error = "calibration/summary.json is absent"
    return {"status": state, "error": error if state != "ok" else None,
            "figures": [n for n in CALIBRATION_FIGURES if n in inputs.figures]}



_INGEST_NUMBERS: Final = ("n_decoded", "n_rejected", "n_gaps", "n_missing_samples")


def _data_quality(inputs: ReportInputs, runs: list[dict[str, Any]],
                  obs_runs: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for run in runs:
        rid = run["run_id"]
        ing = inputs.ingest.get(rid)
        entry: dict[str, Any] = {
            "run_id": rid,
            "file": as_str(run.get("file")) or (as_str(ing.get("file")) if ing else None),
            "status": as_str(run.get("status")),
            "stage": as_str(run.get("stage")),
            "error": as_str(run.get("error")),
            "source_sha256": as_str(run.get("source_sha256")),
            "ingest": None,
            "observation": None,
        }
        if ing is not None:
            rejected = {str(k): as_int(v) for k, v in as_dict(ing.get("rejected")).items()}
            gaps = [{"channel": as_str(g.get("channel")), "start_s": as_float(g.get("start_s")),
                     "n_missing": as_int(g.get("n_missing"))}
                    for g in (ing.get("gaps") or []) if isinstance(g, dict)][:50]
            channels = {str(k): {"unit": as_str(as_dict(v).get("unit")),
                                 "n_samples": as_int(as_dict(v).get("n_samples")),
                                 "sample_rate_Hz": as_float(as_dict(v).get("sample_rate_Hz"))}
                        for k, v in as_dict(ing.get("channels")).items()}
            entry["ingest"] = {
                "status": as_str(ing.get("status")),
                "error": as_str(ing.get("error")),
                "reader": as_str(ing.get("reader")),
                "format": as_str(ing.get("format")),
                "units": as_str(ing.get("units")),
                **{k: as_int(ing.get(k)) for k in _INGEST_NUMBERS},
                "rejected": dict(sorted(rejected.items(), key=lambda kv: -(kv[1] or 0))),
                "gaps": gaps,
                "gaps_truncated": bool(ing.get("gaps_truncated", False)),
                "warnings": [str(w) for w in (ing.get("warnings") or [])],
                "channels": channels,
                "slow_signals": [str(s) for s in (ing.get("slow_signals") or [])],
                "duration_s": as_float(ing.get("duration_s")),
            }
            if entry["source_sha256"] is None:
                entry["source_sha256"] = as_str(ing.get("source_sha256"))
            if entry["status"] is None:
                entry["status"] = entry["ingest"]["status"]
        row = obs_runs.get(rid)
        if row is not None:
            entry["observation"] = {"status": as_str(row.get("status")),
                                    "message": as_str(row.get("message")),
                                    "quality_flags": as_str(row.get("quality_flags"))}
            if entry["status"] is None:
                entry["status"] = "failed" if row.get("status") == "failed" else "ok"
            if entry["file"] is None:
                entry["file"] = as_str(row.get("source_file"))
        out.append(entry)
    return out


def _same_peak(a: float | None, b: float | None) -> bool:
    return a is not None and b is not None and abs(a - b) <= 1e-6 * max(abs(a), abs(b), 1.0)


def _runs(inputs: ReportInputs, runs: list[dict[str, Any]], obs_runs: dict[str, dict[str, Any]]
          ) -> list[dict[str, Any]]:
    summary_runs = as_dict(as_dict(inputs.summary).get("runs"))
    rows_by_run: dict[str, list[dict[str, Any]]] = {}
    for row in inputs.observations or []:
        if row.get("quantity") in ("natural_frequency", "line"):
            rows_by_run.setdefault(str(row.get("run_id")), []).append(row)
    out = []
    for run in runs:
        rid = run["run_id"]
        s = summary_runs.get(rid)
        s = s if isinstance(s, dict) else None
        obs = obs_runs.get(rid, {})
        mesh: dict[str, Any] | None = None
        if s is not None:
            mesh = {"f_Hz": as_float(s.get("mesh_mode_Hz")),
                    "channel": as_str(s.get("mesh_mode_channel")),
                    "probability": as_float(s.get("mesh_mode_probability")),
                    "p_not_observed": as_float(s.get("p_mesh_mode_not_observed"))}
        predicted = None
        if s is not None and isinstance(s.get("predicted_f_n_Hz"), dict):
            p = s["predicted_f_n_Hz"]
            predicted = {"mean": as_float(p.get("mean")), "q05": as_float(p.get("q05")),
                         "q95": as_float(p.get("q95"))}
        peaks, lines = [], []
        for row in rows_by_run.get(rid, []):
            if row.get("quantity") == "natural_frequency":
                f = as_float(row.get("f_n_Hz"))
                peaks.append({
                    "channel": as_str(row.get("channel")),
                    "mode_index": as_int(row.get("mode_index")),
                    "f_n_Hz": f, "f_n_std_Hz": as_float(row.get("f_n_std_Hz")),
                    "zeta": as_float(row.get("zeta")), "zeta_std": as_float(row.get("zeta_std")),
                    "prominence_dB": as_float(row.get("prominence_dB")),
                    "status": as_str(row.get("status")),
                    "quality_flags": as_str(row.get("quality_flags")) or "",
                    "mesh_mode": bool(mesh is not None and mesh["channel"] == row.get("channel")
                                      and _same_peak(mesh["f_Hz"], f)),
                })
            else:
                lines.append({"channel": as_str(row.get("channel")),
                              "f_Hz": as_float(row.get("f_Hz")),
                              "peak_kind": as_str(row.get("peak_kind")),
                              "mode_index": as_int(row.get("mode_index"))})
        peaks.sort(key=lambda p: (p["channel"] or "", p["f_n_Hz"] or 0.0))
        sp = inputs.spectra.get(rid)
        spectrum = {"available": sp is not None,
                    "channels": list(sp.channels) if sp else [],
                    "psd_units": dict(sp.units) if sp else {},
                    "nperseg": sp.nperseg if sp else None}
        out.append({
            "run_id": rid,
            "status": as_str(run.get("status")) or ("failed" if obs.get("status") == "failed"
                                                  else None),
            "torque_Nm": (as_float(obs.get("torque_Nm")) if obs
                          else as_float((s or {}).get("torque_Nm"))),
            "bulk_temperature_C": (as_float(obs.get("bulk_temperature_C")) if obs
                                   else as_float((s or {}).get("bulk_temperature_C"))),
            "speed_rpm": as_float(obs.get("speed_rpm")),
            "mesh_frequency_Hz": as_float(obs.get("mesh_frequency_Hz")),
            "notes": None,
            "left_out": as_str((s or {}).get("left_out")),
            "mesh_mode": mesh,
            "predicted_f_n_Hz": predicted,
            "peaks": peaks,
            "lines": lines,
            "spectrum": spectrum,
        })
    return out



def _provenance(inputs: ReportInputs, data_quality: list[dict[str, Any]]) -> dict[str, Any]:
    p = as_dict(inputs.pipeline)
    camp = as_dict(p.get("campaign"))
    settings = as_dict(p.get("settings"))
    summary = as_dict(inputs.summary)
    stages = {str(k): plain(v) for k, v in as_dict(p.get("stages")).items()}
    return {
        "pipeline_rigtools_version": as_str(p.get("rigtools_version")),
        "pipeline_generated_at": as_str(p.get("generated_at")),
        "campaign": {"path": as_str(camp.get("path")), "name": as_str(camp.get("name")),
                     "sha256": as_str(camp.get("sha256"))},
        "inputs": [{"run_id": d["run_id"], "file": d["file"], "source_sha256": d["source_sha256"]}
                   for d in data_quality],
        "settings": plain(settings),
        "seeds": {"pipeline": as_int(settings.get("seed")),
                  "calibration": as_int(as_dict(summary.get("config")).get("seed")),
                  "sampler": as_int(as_dict(summary.get("sampler")).get("seed"))},
        "versions": {str(k): str(v) for k, v in as_dict(p.get("versions")).items()},
        "stages": stages,
        "resolved_configuration": plain(camp.get("resolved")) if "resolved" in camp else None,
        "calibration_config": plain(summary.get("config")) if inputs.summary else None,
    }



# --------------------------------------------------------------------------------------------
# the whole report


def report_content(inputs: ReportInputs, *, runup: RunUpInputs | None = None,
                   generated_at: datetime | None = None) -> dict[str, Any]:
    """The report.json document of an OUTDIR's files.

    Parameters
    ----------
    inputs : ReportInputs
        :func:`rigtools.report.inputs.read_inputs` of the OUTDIR.
    runup : RunUpInputs, optional
        :func:`rigtools.report.runup_section.read_runup_inputs` of the OUTDIR; without it (or
        without run-up files) the document has no ``runup_calibration`` section.
    generated_at : datetime, optional
        Time stamp of the report (volatile); default now (UTC).

    Returns
    -------
    dict
        JSON-ready; valid against ``data_schemas/report.schema.json``.
    """
    notes = list(inputs.notes)
    calibration = _calibration_status(inputs)
    if calibration["status"] != "ok":
        notes.append(f"calibration {calibration['status']}: {calibration['error']}")
        if inputs.summary is not None:  # stale: the pipeline says this calibration did not run
            notes.append("calibration/summary.json is left over from an earlier calibration: "
                         "not used")
        inputs = replace(inputs, summary=None, figures={})
    runs = run_list(inputs.pipeline, inputs.summary, inputs.observations)
    run_ids = [r["run_id"] for r in runs]
    obs_runs = {str(r.get("run_id")): r for r in inputs.observations or []
                if r.get("quantity") == "run"}
    settings = report_settings(inputs.pipeline, notes)
    camp = as_dict(as_dict(inputs.pipeline).get("campaign"))
    resolved = as_dict(camp.get("resolved"))
    campaign_name = (as_str(camp.get("name"))
                     or as_str(as_dict(resolved.get("campaign")).get("name"))
                     or as_str(resolved.get("name")))
    quality = _data_quality(inputs, runs, obs_runs)
    per_run = _runs(inputs, runs, obs_runs)
    listed = resolved.get("run")
    listed = listed if isinstance(listed, list) else []
    resolved_runs = {str(r.get("id")): r for r in listed if isinstance(r, dict)}
    for r in per_run:
        r["notes"] = as_str(resolved_runs.get(r["run_id"], {}).get("notes")) or None
    stamp = (generated_at or datetime.now(UTC)).isoformat(timespec="seconds")
    doc: dict[str, Any] = {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "rigtools_version": __version__,
        "generated_at": stamp,
        "title": settings["title"] or (f"Validation report: {campaign_name}" if campaign_name
                                       else "rigtools validation report"),
        "campaign_name": campaign_name,
        "report_settings": settings,
        "status": {
            "pipeline_json": inputs.pipeline is not None,
            "calibration": calibration["status"],
            "calibration_error": calibration["error"],
            "calibration_figures": calibration["figures"],
            "n_runs": len(runs),
            "n_runs_failed": sum(d["status"] == "failed" for d in quality),
            "n_spectra": len(inputs.spectra),
        },
        "notes": notes,
        "verdict": verdict(inputs.summary, run_ids, settings),
        "data_quality": quality,
        "runs": per_run,
        "model_vs_experiment": model_vs_experiment(inputs.summary, per_run, settings),
        "convergence": convergence(inputs.summary),
        "provenance": _provenance(inputs, quality),
        "calibration": plain(inputs.summary) if inputs.summary is not None else None,
    }
    if inputs.truth is not None:
        doc["demo_truth"] = plain(inputs.truth)
        doc["truth_comparison"] = truth_comparison(inputs.truth, inputs.summary, run_ids)
    section = runup_section(runup, inputs.truth)
    if section is not None:
        doc["runup_calibration"] = section
        if section["status"] == "failed":
            notes.append(f"run-up calibration failed: {section['error']}")
    return plain(doc)
