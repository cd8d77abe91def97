r"""The judged sections of ``report.json``: the calibration against the campaign's checks.

Sections (schema ``data_schemas/report.schema.json``):

``verdict``
    Backlash ``c``, the critical gap ``c*(theta)`` at each temperature with its 90 % interval,
    margin ``c - c*`` and regime of every run with its probability, the flip temperature, the
    model variant the data favour, and the campaign's ``[report]`` checks (``backlash_range_um``,
    ``min_margin_um``).
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
``truth_comparison``
    For the demo: each true value against its posterior 90 % interval, and each run's true
    regime and mesh mode against the posterior's.

The ``[report]`` settings these are judged against (:func:`report_settings`) live here too.
The rest of the document is assembled in :mod:`rigtools.report.content`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any, Final

from rigtools.report.values import as_dict, as_float, as_int, as_quantity, as_str

__all__ = [
    "DEFAULT_TOLERANCES",
    "convergence",
    "model_vs_experiment",
    "report_settings",
    "truth_comparison",
    "verdict",
]

#: ``[report]`` defaults when the campaign does not set them.
DEFAULT_TOLERANCES: Final[dict[str, float]] = {"f_n_rel_tolerance": 0.02, "f_n_z_tolerance": 3.0}
#: Two-sided 90 % interval width of a normal distribution, in sd (2 x 1.6449).
_Z90_WIDTH: Final = 2.0 * 1.6448536269514722
_TEMPERATURE_KEY: Final = re.compile(r"^(critical_gap|thermal_closure|margin)@(.+)C$")


# --------------------------------------------------------------------------------------------
# small helpers


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


def report_settings(pipeline: dict[str, Any] | None, notes: list[str]) -> dict[str, Any]:
    """The ``[report]`` block (pipeline.json ``campaign.resolved.report``) with defaults.

    Parameters
    ----------
    pipeline : dict or None
        pipeline.json.
    notes : list of str
        Report notes; a ``backlash_range_um`` that is not a pair of numbers is noted here.

    Returns
    -------
    dict
        ``title``, the tolerances of :data:`DEFAULT_TOLERANCES` each with ``<key>_source``
        (``"default"`` or ``"campaign"``), ``backlash_range_um`` (um) and ``min_margin_um`` (um).
    """
    resolved = as_dict(as_dict(as_dict(pipeline).get("campaign")).get("resolved"))
    block = as_dict(resolved.get("report"))
    out: dict[str, Any] = {"title": as_str(block.get("title"))}
    for key, default in DEFAULT_TOLERANCES.items():
        v = as_float(block.get(key))
        out[key] = default if v is None else v
        out[f"{key}_source"] = "default" if v is None else "campaign"
    rng = block.get("backlash_range_um")
    if isinstance(rng, list) and len(rng) == 2 and all(as_float(x) is not None for x in rng):
        out["backlash_range_um"] = [float(rng[0]), float(rng[1])]
    else:
        out["backlash_range_um"] = None
        if rng is not None:
            notes.append("[report] backlash_range_um is not a pair of numbers: not checked")
    out["min_margin_um"] = as_float(block.get("min_margin_um"))
    return out



def verdict(summary: dict[str, Any] | None, run_ids: Sequence[str],
            settings: dict[str, Any]) -> dict[str, Any]:
    """The ``verdict`` section: backlash, critical gaps, margins, regimes and the checks.

    Parameters
    ----------
    summary : dict or None
        Calibration ``summary.json``; None when the calibration is absent or failed.
    run_ids : sequence of str
        The runs, in report order.
    settings : dict
        :func:`report_settings`.

    Returns
    -------
    dict
        ``available`` False (and every field empty) without a summary. Lengths in um,
        temperatures in degC.
    """
    if summary is None:
        return {"available": False, "backlash_um": None, "critical_gaps": [],
                "operating_temperature_C": None, "operating_margin_um": None,
                "flip_temperature_C": None, "runs": [], "model_variant": None,
                "favoured_model": None, "model_statement": None, "converged": None,
                "checks": []}
    params, derived = as_dict(summary.get("parameters")), as_dict(summary.get("derived"))
    conventions = as_dict(summary.get("conventions"))
    op_t = as_float(conventions.get("operating_temperature_C"))
    gaps: list[dict[str, Any]] = []
    for key, q in derived.items():
        m = _TEMPERATURE_KEY.match(key)
        if not m or m.group(1) != "critical_gap":
            continue
        t = _temperature(m.group(2))
        quantity = as_quantity(q)
        if t is None or quantity is None:
            continue
        closure = as_quantity(derived.get(f"thermal_closure@{m.group(2)}C"))
        gaps.append({"temperature_C": t, "critical_gap_um": quantity,
                     "thermal_closure_um": closure,
                     "margin_um": as_quantity(derived.get(f"margin@{m.group(2)}C")),
                     "operating": op_t is not None and abs(t - op_t) < 1e-9})
    gaps.sort(key=lambda g: float(g["temperature_C"]))
    runs_s = as_dict(summary.get("runs"))
    runs = []
    for rid in run_ids:
        r = runs_s.get(rid)
        if not isinstance(r, dict):
            continue
        runs.append({
            "run_id": rid,
            "torque_Nm": as_float(r.get("torque_Nm")),
            "bulk_temperature_C": as_float(r.get("bulk_temperature_C")),
            "margin_um": as_quantity(derived.get(f"margin@{rid}")),
            "relative_margin": as_quantity(derived.get(f"relative_margin@{rid}")),
            "regime": as_str(r.get("regime")),
            "regime_probability": as_float(r.get("regime_probability")),
            "p_c_lt_cstar": as_float(r.get("p_c_lt_cstar")),
            "jammed_probability": as_float(r.get("jammed_probability")),
            "left_out": as_str(r.get("left_out")),
        })
    comparison = as_dict(summary.get("model_comparison"))
    backlash = as_quantity(params.get("backlash"))
    op_margin = (as_quantity(derived.get(f"margin@{_tag(op_t)}C")) if op_t is not None else None)
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
        "flip_temperature_C": as_quantity(derived.get("flip_temperature_C")),
        "runs": runs,
        "model_variant": as_str(summary.get("model_variant")),
        "favoured_model": as_str(comparison.get("favoured")),
        "model_statement": as_str(comparison.get("statement")),
        "converged": summary.get("converged") if isinstance(summary.get("converged"), bool)
        else None,
        "checks": checks,
    }



def model_vs_experiment(summary: dict[str, Any] | None, runs: list[dict[str, Any]],
                        settings: dict[str, Any]) -> dict[str, Any]:
    """The ``model_vs_experiment`` section: measured against predicted mesh mode, per run.

    Parameters
    ----------
    summary : dict or None
        Calibration ``summary.json``; None when the calibration is absent or failed.
    runs : list of dict
        The ``runs`` section (:func:`rigtools.report.content.report_content`); a run without
        ``mesh_mode`` is not in the calibration and is left out.
    settings : dict
        :func:`report_settings` (the tolerances).

    Returns
    -------
    dict
        ``rows`` (frequencies in Hz, ``rel_error``, ``z``, pass/fail and why untested) and the
        counts of passed, failed and untested rows.

    Notes
    -----
    The relative error and z-score are those of the module docstring; a run passes when
    :math:`e_{rel}` is within ``f_n_rel_tolerance`` and :math:`z` (when the predictive sd is
    positive) within ``f_n_z_tolerance``.
    """
    rel_tol, z_tol = settings["f_n_rel_tolerance"], settings["f_n_z_tolerance"]
    tolerances = {"f_n_rel_tolerance": rel_tol, "f_n_z_tolerance": z_tol,
                  "source": {k: settings[f"{k}_source"] for k in DEFAULT_TOLERANCES}}
    if summary is None:
        return {"available": False, "tolerances": tolerances, "model_error": None, "rows": [],
                "n_pass": 0, "n_fail": 0, "n_untested": 0}
    me = as_quantity(as_dict(summary.get("parameters")).get("model_error"))
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


def convergence(summary: dict[str, Any] | None) -> dict[str, Any]:
    """The ``convergence`` section: sampler settings and diagnostics against their tolerances.

    Parameters
    ----------
    summary : dict or None
        Calibration ``summary.json``; None when the calibration is absent or failed.

    Returns
    -------
    dict
        ``available`` False without a summary; else the sampler settings, acceptance, and per
        parameter tau (steps), chain length over tau, ESS and R-hat with their checks.
    """
    if summary is None:
        return {"available": False}
    sampler = as_dict(summary.get("sampler"))
    tol = as_dict(as_dict(summary.get("config")).get("tolerances"))
    max_r_hat, min_ess = as_float(tol.get("max_r_hat")), as_float(tol.get("min_ess_bulk"))
    acc_range = tol.get("acceptance_range")
    acc_range = ([float(acc_range[0]), float(acc_range[1])]
                 if isinstance(acc_range, list) and len(acc_range) == 2
                 and all(as_float(a) is not None for a in acc_range) else None)
    n_steps = as_int(sampler.get("n_steps"))
    tau = {str(k): as_float(v) for k, v in as_dict(sampler.get("tau")).items()}
    params = []
    for name, q in as_dict(summary.get("parameters")).items():
        qd = as_dict(q)
        ess, r_hat = as_float(qd.get("ess_bulk")), as_float(qd.get("r_hat"))
        t = tau.get(name)
        params.append({
            "name": str(name), "unit": as_str(qd.get("unit")),
            "tau_steps": t,
            "chain_over_tau": (n_steps / t) if (n_steps and t) else None,
            "ess_bulk": ess, "r_hat": r_hat,
            "ess_ok": None if ess is None or min_ess is None else bool(ess >= min_ess),
            "r_hat_ok": None if r_hat is None or max_r_hat is None else bool(r_hat <= max_r_hat),
        })
    acc = as_float(sampler.get("acceptance_fraction"))
    return {
        "available": True,
        "converged": sampler.get("converged") if isinstance(sampler.get("converged"), bool)
        else None,
        "walkers": as_int(sampler.get("walkers")), "n_steps": n_steps,
        "burn_in": as_int(sampler.get("burn_in")), "thin": as_int(sampler.get("thin")),
        "draws": as_int(sampler.get("draws")), "seed": as_int(sampler.get("seed")),
        "resumed_from": as_int(sampler.get("resumed_from")),
        "acceptance_fraction": acc, "acceptance_range": acc_range,
        "acceptance_ok": (None if acc is None or acc_range is None
                          else bool(acc_range[0] <= acc <= acc_range[1])),
        "max_r_hat": max_r_hat, "min_ess_bulk": min_ess,
        "parameters": params,
        "notes": [str(n) for n in (sampler.get("notes") or [])],
        "warnings": [str(w) for w in (summary.get("warnings") or [])],
    }



def truth_comparison(truth: dict[str, Any] | None, summary: dict[str, Any] | None,
                     run_ids: Sequence[str]) -> dict[str, Any] | None:
    """The demo's ``truth_comparison``: true values against the posterior.

    Parameters
    ----------
    truth : dict or None
        The demo's truth file; None outside the demo.
    summary : dict or None
        Calibration ``summary.json``.
    run_ids : sequence of str
        The runs, in report order.

    Returns
    -------
    dict or None
        None without a truth; else ``quantities`` (each with whether its 90 % interval covers
        the true value) and ``runs`` (true and posterior regime and mesh mode, Hz).
    """
    if truth is None:
        return None
    s = as_dict(summary)
    posterior = {**as_dict(s.get("parameters")), **as_dict(s.get("derived"))}
    quantities = []
    for group in ("parameters", "derived"):
        for name, t in as_dict(truth.get(group)).items():
            value = as_float(as_dict(t).get("value")) if isinstance(t, dict) else as_float(t)
            q = as_quantity(posterior.get(name))
            covered = None
            if value is not None and q is not None and q["q05"] is not None \
                    and q["q95"] is not None:
                covered = bool(q["q05"] <= value <= q["q95"])
            if q is None:  # no posterior counterpart (a fixed parameter, a run not fitted)
                continue
            unit = as_str(as_dict(t).get("unit")) if isinstance(t, dict) else None
            quantities.append({"name": str(name), "truth": value, "unit": unit,
                               "posterior": q, "covered": covered})
    runs = []
    truth_runs, post_runs = as_dict(truth.get("runs")), as_dict(s.get("runs"))
    for rid in run_ids:
        t, p = as_dict(truth_runs.get(rid)), as_dict(post_runs.get(rid))
        if not t:
            continue
        t_regime, p_regime = as_str(t.get("regime")), as_str(p.get("regime"))
        t_f, p_f = as_float(t.get("mesh_mode_Hz")), as_float(p.get("mesh_mode_Hz"))
        runs.append({"run_id": rid, "regime_truth": t_regime, "regime_posterior": p_regime,
                     "regime_right": None if p_regime is None or t_regime is None
                     else p_regime == t_regime,
                     "mesh_mode_truth_Hz": t_f, "mesh_mode_posterior_Hz": p_f})
    return {"quantities": quantities, "runs": runs}

