r"""The content of ``report.json``: every number the page shows, computed from the stage files.

Sections (schema ``data_schemas/report.schema.json``):

``verdict``
    Backlash ``c``, the critical gap ``c*(theta)`` at each temperature with its 90 % interval,
    margin ``c - c*`` and regime of every run with its probability, the flip temperature, the
    model variant the data favour, and the campaign's ``[report]`` checks (``backlash_range_um``,
    ``min_margin_um``).
``data_quality``
    Per recording: decoded and rejected counts by reason, gaps, warnings, the pipeline's status
    and, for a failed run, the stage and why.
``runs``
    Per run: conditions, the peaks found (observations ``natural_frequency`` rows), the peak
    taken as the mesh mode (calibration summary ``runs.<id>.mesh_mode_Hz`` and
    ``mesh_mode_channel``), the predicted natural frequency, and what spectra there are.
``model_vs_experiment``
    Per fitted run, the measured mesh mode against the posterior predictive natural frequency,
    with pass/fail against the ``[report]`` tolerances:

    .. math::

        e_{rel} = |f_{meas} - \bar f| / \bar f, \qquad
        z = |f_{meas} - \bar f| / \sqrt{s_f^2 + (\sigma_m \bar f)^2},

    where :math:`\bar f` is the posterior mean of the predicted frequency, :math:`s_f` its
    posterior sd taken from the 90 % interval (:math:`(q_{95} - q_{05}) / 3.29`, normal
    approximation) and :math:`\sigma_m` the posterior mean of the relative model error
    (``parameters.model_error``). A run passes when both are within tolerance.
``convergence``
    Sampler settings, tau per parameter, chain length in tau, acceptance, ESS and R-hat per
    parameter, each against the calibration's own tolerances.
``provenance``
    Campaign file and hash, the recordings' hashes, versions, the resolved configuration and
    every seed.
``calibration``
    The calibration's ``summary.json`` as written (null when the calibration is absent or
    failed); ``demo_truth`` and ``truth_comparison`` for the demo.

Numbers that are not finite become null. Strings from recordings and campaigns are carried as
they are; the page escapes them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import replace
from datetime import UTC, datetime
from typing import Any, Final

from rigtools import __version__
from rigtools.report.inputs import CALIBRATION_FIGURES, ReportInputs, run_list

__all__ = [
    "DEFAULT_TOLERANCES",
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
#: ``[report]`` defaults when the campaign does not set them.
DEFAULT_TOLERANCES: Final[dict[str, float]] = {"f_n_rel_tolerance": 0.02, "f_n_z_tolerance": 3.0}
#: Two-sided 90 % interval width of a normal distribution, in sd (2 x 1.6449).
_Z90_WIDTH: Final = 2.0 * 1.6448536269514722
_TEMPERATURE_KEY: Final = re.compile(r"^(critical_gap|thermal_closure|margin)@(.+)C$")
_QUANTITY_FIELDS: Final = ("mean", "sd", "q05", "q50", "q95")


# --------------------------------------------------------------------------------------------
# small helpers


def _num(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    f = float(v)
    return f if math.isfinite(f) else None


def _int(v: Any) -> int | None:
    if isinstance(v, bool) or not isinstance(v, int):
        return None
    return int(v)


def _str(v: Any) -> str | None:
    return v if isinstance(v, str) else None


def _dict(v: Any) -> dict[str, Any]:
    return v if isinstance(v, dict) else {}


def _plain(obj: Any) -> Any:
    """A JSON-safe copy: non-finite floats to None, keys to str, tuples to lists."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, str | int):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v) for v in obj]
    return str(obj)


def _quantity(q: Any) -> dict[str, Any] | None:
    """Mean, sd and quantiles of a summary quantity, or None when absent."""
    if not isinstance(q, dict):
        return None
    out: dict[str, Any] = {k: _num(q.get(k)) for k in _QUANTITY_FIELDS}
    unit = _str(q.get("unit"))
    out["unit"] = unit
    ff = _num(q.get("finite_fraction"))
    if ff is not None:
        out["finite_fraction"] = ff
    return out


def _temperature(text: str) -> float | None:
    try:
        t = float(text)
    except ValueError:
        return None
    return t if math.isfinite(t) else None


def _tag(t: float) -> str:
    return f"{t:g}"


# --------------------------------------------------------------------------------------------
# sections


def _report_settings(pipeline: dict[str, Any] | None, notes: list[str]) -> dict[str, Any]:
    """The ``[report]`` block (pipeline.json ``campaign.resolved.report``) with defaults."""
    block = _dict(_dict(_dict(_dict(pipeline).get("campaign")).get("resolved")).get("report"))
    out: dict[str, Any] = {"title": _str(block.get("title"))}
    for key, default in DEFAULT_TOLERANCES.items():
        v = _num(block.get(key))
        out[key] = default if v is None else v
        out[f"{key}_source"] = "default" if v is None else "campaign"
    rng = block.get("backlash_range_um")
    if isinstance(rng, list) and len(rng) == 2 and all(_num(x) is not None for x in rng):
        out["backlash_range_um"] = [float(rng[0]), float(rng[1])]
    else:
        out["backlash_range_um"] = None
        if rng is not None:
            notes.append("[report] backlash_range_um is not a pair of numbers: not checked")
    out["min_margin_um"] = _num(block.get("min_margin_um"))
    return out


def _calibration_status(inputs: ReportInputs) -> dict[str, Any]:
    stage = _dict(_dict(_dict(inputs.pipeline).get("stages")).get("calibrate"))
    status = _str(stage.get("status"))
    error = _str(stage.get("error"))
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


def _verdict(summary: dict[str, Any] | None, run_ids: Sequence[str],
             settings: dict[str, Any]) -> dict[str, Any]:
    if summary is None:
        return {"available": False, "backlash_um": None, "critical_gaps": [],
                "operating_temperature_C": None, "operating_margin_um": None,
                "flip_temperature_C": None, "runs": [], "model_variant": None,
                "favoured_model": None, "model_statement": None, "converged": None,
                "checks": []}
    params, derived = _dict(summary.get("parameters")), _dict(summary.get("derived"))
    conventions = _dict(summary.get("conventions"))
    op_t = _num(conventions.get("operating_temperature_C"))
    gaps: list[dict[str, Any]] = []
    for key, q in derived.items():
        m = _TEMPERATURE_KEY.match(key)
        if not m or m.group(1) != "critical_gap":
            continue
        t = _temperature(m.group(2))
        quantity = _quantity(q)
        if t is None or quantity is None:
            continue
        closure = _quantity(derived.get(f"thermal_closure@{m.group(2)}C"))
        gaps.append({"temperature_C": t, "critical_gap_um": quantity,
                     "thermal_closure_um": closure,
                     "margin_um": _quantity(derived.get(f"margin@{m.group(2)}C")),
                     "operating": op_t is not None and abs(t - op_t) < 1e-9})
    gaps.sort(key=lambda g: float(g["temperature_C"]))
    runs_s = _dict(summary.get("runs"))
    runs = []
    for rid in run_ids:
        r = runs_s.get(rid)
        if not isinstance(r, dict):
            continue
        runs.append({
            "run_id": rid,
            "torque_Nm": _num(r.get("torque_Nm")),
            "bulk_temperature_C": _num(r.get("bulk_temperature_C")),
            "margin_um": _quantity(derived.get(f"margin@{rid}")),
            "relative_margin": _quantity(derived.get(f"relative_margin@{rid}")),
            "regime": _str(r.get("regime")),
            "regime_probability": _num(r.get("regime_probability")),
            "p_c_lt_cstar": _num(r.get("p_c_lt_cstar")),
            "jammed_probability": _num(r.get("jammed_probability")),
            "left_out": _str(r.get("left_out")),
        })
    comparison = _dict(summary.get("model_comparison"))
    backlash = _quantity(params.get("backlash"))
    op_margin = (_quantity(derived.get(f"margin@{_tag(op_t)}C")) if op_t is not None else None)
    checks = []
    rng = settings.get("backlash_range_um")
    if rng is not None:
        lo, hi = rng
        ok = None
        if backlash is not None and backlash["q05"] is not None and backlash["q95"] is not None:
            ok = bool(backlash["q05"] >= lo and backlash["q95"] <= hi)
        checks.append({"name": "backlash_range_um",
                       "criterion": f"90 % interval of the backlash inside [{lo:g}, {hi:g}] um",
                       "value": [backlash["q05"], backlash["q95"]] if backlash else None,
                       "limit": [lo, hi], "pass": ok})
    mm = settings.get("min_margin_um")
    if mm is not None:
        q05 = op_margin["q05"] if op_margin else None
        where = f"{_tag(op_t)} degC" if op_t is not None else "the operating temperature"
        checks.append({"name": "min_margin_um",
                       "criterion": f"5 % quantile of the margin at {where} >= {mm:g} um",
                       "value": [q05], "limit": [mm],
                       "pass": None if q05 is None else bool(q05 >= mm)})
    return {
        "available": True,
        "backlash_um": backlash,
        "critical_gaps": gaps,
        "operating_temperature_C": op_t,
        "operating_margin_um": op_margin,
        "flip_temperature_C": _quantity(derived.get("flip_temperature_C")),
        "runs": runs,
        "model_variant": _str(summary.get("model_variant")),
        "favoured_model": _str(comparison.get("favoured")),
        "model_statement": _str(comparison.get("statement")),
        "converged": summary.get("converged") if isinstance(summary.get("converged"), bool)
        else None,
        "checks": checks,
    }


_INGEST_NUMBERS: Final = ("n_decoded", "n_rejected", "n_gaps", "n_missing_samples")


def _data_quality(inputs: ReportInputs, runs: list[dict[str, Any]],
                  obs_runs: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for run in runs:
        rid = run["run_id"]
        ing = inputs.ingest.get(rid)
        entry: dict[str, Any] = {
            "run_id": rid,
            "file": _str(run.get("file")) or (_str(ing.get("file")) if ing else None),
            "status": _str(run.get("status")),
            "stage": _str(run.get("stage")),
            "error": _str(run.get("error")),
            "source_sha256": _str(run.get("source_sha256")),
            "ingest": None,
            "observation": None,
        }
        if ing is not None:
            rejected = {str(k): _int(v) for k, v in _dict(ing.get("rejected")).items()}
            gaps = [{"channel": _str(g.get("channel")), "start_s": _num(g.get("start_s")),
                     "n_missing": _int(g.get("n_missing"))}
                    for g in (ing.get("gaps") or []) if isinstance(g, dict)][:50]
            channels = {str(k): {"unit": _str(_dict(v).get("unit")),
                                 "n_samples": _int(_dict(v).get("n_samples")),
                                 "sample_rate_Hz": _num(_dict(v).get("sample_rate_Hz"))}
                        for k, v in _dict(ing.get("channels")).items()}
            entry["ingest"] = {
                "status": _str(ing.get("status")),
                "error": _str(ing.get("error")),
                "reader": _str(ing.get("reader")),
                "format": _str(ing.get("format")),
                "units": _str(ing.get("units")),
                **{k: _int(ing.get(k)) for k in _INGEST_NUMBERS},
                "rejected": dict(sorted(rejected.items(), key=lambda kv: -(kv[1] or 0))),
                "gaps": gaps,
                "gaps_truncated": bool(ing.get("gaps_truncated", False)),
                "warnings": [str(w) for w in (ing.get("warnings") or [])],
                "channels": channels,
                "slow_signals": [str(s) for s in (ing.get("slow_signals") or [])],
                "duration_s": _num(ing.get("duration_s")),
            }
            if entry["source_sha256"] is None:
                entry["source_sha256"] = _str(ing.get("source_sha256"))
            if entry["status"] is None:
                entry["status"] = entry["ingest"]["status"]
        row = obs_runs.get(rid)
        if row is not None:
            entry["observation"] = {"status": _str(row.get("status")),
                                    "message": _str(row.get("message")),
                                    "quality_flags": _str(row.get("quality_flags"))}
            if entry["status"] is None:
                entry["status"] = "failed" if row.get("status") == "failed" else "ok"
            if entry["file"] is None:
                entry["file"] = _str(row.get("source_file"))
        out.append(entry)
    return out


def _same_peak(a: float | None, b: float | None) -> bool:
    return a is not None and b is not None and abs(a - b) <= 1e-6 * max(abs(a), abs(b), 1.0)


def _runs(inputs: ReportInputs, runs: list[dict[str, Any]], obs_runs: dict[str, dict[str, Any]]
          ) -> list[dict[str, Any]]:
    summary_runs = _dict(_dict(inputs.summary).get("runs"))
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
            mesh = {"f_Hz": _num(s.get("mesh_mode_Hz")),
                    "channel": _str(s.get("mesh_mode_channel")),
                    "probability": _num(s.get("mesh_mode_probability")),
                    "p_not_observed": _num(s.get("p_mesh_mode_not_observed"))}
        predicted = None
        if s is not None and isinstance(s.get("predicted_f_n_Hz"), dict):
            p = s["predicted_f_n_Hz"]
            predicted = {"mean": _num(p.get("mean")), "q05": _num(p.get("q05")),
                         "q95": _num(p.get("q95"))}
        peaks, lines = [], []
        for row in rows_by_run.get(rid, []):
            if row.get("quantity") == "natural_frequency":
                f = _num(row.get("f_n_Hz"))
                peaks.append({
                    "channel": _str(row.get("channel")),
                    "mode_index": _int(row.get("mode_index")),
                    "f_n_Hz": f, "f_n_std_Hz": _num(row.get("f_n_std_Hz")),
                    "zeta": _num(row.get("zeta")), "zeta_std": _num(row.get("zeta_std")),
                    "prominence_dB": _num(row.get("prominence_dB")),
                    "status": _str(row.get("status")),
                    "quality_flags": _str(row.get("quality_flags")) or "",
                    "mesh_mode": bool(mesh is not None and mesh["channel"] == row.get("channel")
                                      and _same_peak(mesh["f_Hz"], f)),
                })
            else:
                lines.append({"channel": _str(row.get("channel")), "f_Hz": _num(row.get("f_Hz")),
                              "peak_kind": _str(row.get("peak_kind")),
                              "mode_index": _int(row.get("mode_index"))})
        peaks.sort(key=lambda p: (p["channel"] or "", p["f_n_Hz"] or 0.0))
        sp = inputs.spectra.get(rid)
        spectrum = {"available": sp is not None,
                    "channels": list(sp.channels) if sp else [],
                    "psd_units": dict(sp.units) if sp else {},
                    "nperseg": sp.nperseg if sp else None}
        out.append({
            "run_id": rid,
            "status": _str(run.get("status")) or ("failed" if obs.get("status") == "failed"
                                                  else None),
            "torque_Nm": _num(obs.get("torque_Nm")) if obs else _num((s or {}).get("torque_Nm")),
            "bulk_temperature_C": (_num(obs.get("bulk_temperature_C")) if obs
                                   else _num((s or {}).get("bulk_temperature_C"))),
            "speed_rpm": _num(obs.get("speed_rpm")),
            "mesh_frequency_Hz": _num(obs.get("mesh_frequency_Hz")),
            "notes": None,
            "left_out": _str((s or {}).get("left_out")),
            "mesh_mode": mesh,
            "predicted_f_n_Hz": predicted,
            "peaks": peaks,
            "lines": lines,
            "spectrum": spectrum,
        })
    return out


def _model_vs_experiment(summary: dict[str, Any] | None, runs: list[dict[str, Any]],
                         settings: dict[str, Any]) -> dict[str, Any]:
    rel_tol, z_tol = settings["f_n_rel_tolerance"], settings["f_n_z_tolerance"]
    tolerances = {"f_n_rel_tolerance": rel_tol, "f_n_z_tolerance": z_tol,
                  "source": {k: settings[f"{k}_source"] for k in DEFAULT_TOLERANCES}}
    if summary is None:
        return {"available": False, "tolerances": tolerances, "model_error": None, "rows": [],
                "n_pass": 0, "n_fail": 0, "n_untested": 0}
    me = _quantity(_dict(summary.get("parameters")).get("model_error"))
    sigma_m = me["mean"] if me and me["mean"] is not None else 0.0
    rows = []
    for run in runs:
        if run["mesh_mode"] is None:  # not in the calibration
            continue
        pred = run["predicted_f_n_Hz"] or {}
        meas = run["mesh_mode"]["f_Hz"]
        mean, q05, q95 = pred.get("mean"), pred.get("q05"), pred.get("q95")
        row: dict[str, Any] = {"run_id": run["run_id"], "measured_f_n_Hz": meas,
                               "channel": run["mesh_mode"]["channel"],
                               "predicted_f_n_Hz": mean, "predicted_q05_Hz": q05,
                               "predicted_q95_Hz": q95, "predictive_sd_Hz": None,
                               "rel_error": None, "z": None, "pass_rel": None, "pass_z": None,
                               "pass": None, "reason": None}
        if meas is None:
            row["reason"] = "no peak taken as the mesh mode"
        elif mean is None or mean <= 0:
            row["reason"] = "no predicted natural frequency"
        else:
            s_f = (q95 - q05) / _Z90_WIDTH if q05 is not None and q95 is not None else 0.0
            sd = math.hypot(s_f, sigma_m * mean)
            row["predictive_sd_Hz"] = sd
            row["rel_error"] = abs(meas - mean) / mean
            row["pass_rel"] = bool(row["rel_error"] <= rel_tol)
            if sd > 0:
                row["z"] = abs(meas - mean) / sd
                row["pass_z"] = bool(row["z"] <= z_tol)
            row["pass"] = bool(row["pass_rel"] and row["pass_z"] is not False)
        rows.append(row)
    return {"available": True, "tolerances": tolerances, "model_error": me, "rows": rows,
            "n_pass": sum(r["pass"] is True for r in rows),
            "n_fail": sum(r["pass"] is False for r in rows),
            "n_untested": sum(r["pass"] is None for r in rows)}


def _convergence(summary: dict[str, Any] | None) -> dict[str, Any]:
    if summary is None:
        return {"available": False}
    sampler = _dict(summary.get("sampler"))
    tol = _dict(_dict(summary.get("config")).get("tolerances"))
    max_r_hat, min_ess = _num(tol.get("max_r_hat")), _num(tol.get("min_ess_bulk"))
    acc_range = tol.get("acceptance_range")
    acc_range = ([float(acc_range[0]), float(acc_range[1])]
                 if isinstance(acc_range, list) and len(acc_range) == 2
                 and all(_num(a) is not None for a in acc_range) else None)
    n_steps = _int(sampler.get("n_steps"))
    tau = {str(k): _num(v) for k, v in _dict(sampler.get("tau")).items()}
    params = []
    for name, q in _dict(summary.get("parameters")).items():
        qd = _dict(q)
        ess, r_hat = _num(qd.get("ess_bulk")), _num(qd.get("r_hat"))
        t = tau.get(name)
        params.append({
            "name": str(name), "unit": _str(qd.get("unit")),
            "tau_steps": t,
            "chain_over_tau": (n_steps / t) if (n_steps and t) else None,
            "ess_bulk": ess, "r_hat": r_hat,
            "ess_ok": None if ess is None or min_ess is None else bool(ess >= min_ess),
            "r_hat_ok": None if r_hat is None or max_r_hat is None else bool(r_hat <= max_r_hat),
        })
    acc = _num(sampler.get("acceptance_fraction"))
    return {
        "available": True,
        "converged": sampler.get("converged") if isinstance(sampler.get("converged"), bool)
        else None,
        "walkers": _int(sampler.get("walkers")), "n_steps": n_steps,
        "burn_in": _int(sampler.get("burn_in")), "thin": _int(sampler.get("thin")),
        "draws": _int(sampler.get("draws")), "seed": _int(sampler.get("seed")),
        "resumed_from": _int(sampler.get("resumed_from")),
        "acceptance_fraction": acc, "acceptance_range": acc_range,
        "acceptance_ok": (None if acc is None or acc_range is None
                          else bool(acc_range[0] <= acc <= acc_range[1])),
        "max_r_hat": max_r_hat, "min_ess_bulk": min_ess,
        "parameters": params,
        "notes": [str(n) for n in (sampler.get("notes") or [])],
        "warnings": [str(w) for w in (summary.get("warnings") or [])],
    }


def _provenance(inputs: ReportInputs, data_quality: list[dict[str, Any]]) -> dict[str, Any]:
    p = _dict(inputs.pipeline)
    camp = _dict(p.get("campaign"))
    settings = _dict(p.get("settings"))
    summary = _dict(inputs.summary)
    stages = {str(k): _plain(v) for k, v in _dict(p.get("stages")).items()}
    return {
        "pipeline_rigtools_version": _str(p.get("rigtools_version")),
        "pipeline_generated_at": _str(p.get("generated_at")),
        "campaign": {"path": _str(camp.get("path")), "name": _str(camp.get("name")),
                     "sha256": _str(camp.get("sha256"))},
        "inputs": [{"run_id": d["run_id"], "file": d["file"], "source_sha256": d["source_sha256"]}
                   for d in data_quality],
        "settings": _plain(settings),
        "seeds": {"pipeline": _int(settings.get("seed")),
                  "calibration": _int(_dict(summary.get("config")).get("seed")),
                  "sampler": _int(_dict(summary.get("sampler")).get("seed"))},
        "versions": {str(k): str(v) for k, v in _dict(p.get("versions")).items()},
        "stages": stages,
        "resolved_configuration": _plain(camp.get("resolved")) if "resolved" in camp else None,
        "calibration_config": _plain(summary.get("config")) if inputs.summary else None,
    }


def _truth_comparison(truth: dict[str, Any] | None, summary: dict[str, Any] | None,
                      run_ids: Sequence[str]) -> dict[str, Any] | None:
    if truth is None:
        return None
    s = _dict(summary)
    posterior = {**_dict(s.get("parameters")), **_dict(s.get("derived"))}
    quantities = []
    for group in ("parameters", "derived"):
        for name, t in _dict(truth.get(group)).items():
            value = _num(_dict(t).get("value")) if isinstance(t, dict) else _num(t)
            q = _quantity(posterior.get(name))
            covered = None
            if value is not None and q is not None and q["q05"] is not None \
                    and q["q95"] is not None:
                covered = bool(q["q05"] <= value <= q["q95"])
            if q is None:  # no posterior counterpart (a fixed parameter, a run not fitted)
                continue
            quantities.append({"name": str(name), "truth": value,
                               "unit": _str(_dict(t).get("unit")) if isinstance(t, dict) else None,
                               "posterior": q, "covered": covered})
    runs = []
    truth_runs, post_runs = _dict(truth.get("runs")), _dict(s.get("runs"))
    for rid in run_ids:
        t, p = _dict(truth_runs.get(rid)), _dict(post_runs.get(rid))
        if not t:
            continue
        t_regime, p_regime = _str(t.get("regime")), _str(p.get("regime"))
        t_f, p_f = _num(t.get("mesh_mode_Hz")), _num(p.get("mesh_mode_Hz"))
        runs.append({"run_id": rid, "regime_truth": t_regime, "regime_posterior": p_regime,
                     "regime_right": None if p_regime is None or t_regime is None
                     else p_regime == t_regime,
                     "mesh_mode_truth_Hz": t_f, "mesh_mode_posterior_Hz": p_f})
    return {"quantities": quantities, "runs": runs}


# --------------------------------------------------------------------------------------------
# the whole report


def report_content(inputs: ReportInputs, *, generated_at: datetime | None = None
                   ) -> dict[str, Any]:
    """The report.json document of an OUTDIR's files.

    Parameters
    ----------
    inputs : ReportInputs
        :func:`rigtools.report.inputs.read_inputs` of the OUTDIR.
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
    settings = _report_settings(inputs.pipeline, notes)
    camp = _dict(_dict(inputs.pipeline).get("campaign"))
    resolved = _dict(camp.get("resolved"))
    campaign_name = (_str(camp.get("name")) or _str(_dict(resolved.get("campaign")).get("name"))
                     or _str(resolved.get("name")))
    quality = _data_quality(inputs, runs, obs_runs)
    per_run = _runs(inputs, runs, obs_runs)
    listed = resolved.get("run")
    listed = listed if isinstance(listed, list) else []
    resolved_runs = {str(r.get("id")): r for r in listed if isinstance(r, dict)}
    for r in per_run:
        r["notes"] = _str(resolved_runs.get(r["run_id"], {}).get("notes")) or None
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
        "verdict": _verdict(inputs.summary, run_ids, settings),
        "data_quality": quality,
        "runs": per_run,
        "model_vs_experiment": _model_vs_experiment(inputs.summary, per_run, settings),
        "convergence": _convergence(inputs.summary),
        "provenance": _provenance(inputs, quality),
        "calibration": _plain(inputs.summary) if inputs.summary is not None else None,
    }
    if inputs.truth is not None:
        doc["demo_truth"] = _plain(inputs.truth)
        doc["truth_comparison"] = _truth_comparison(inputs.truth, inputs.summary, run_ids)
    return _plain(doc)
