"""The report's section "Run-up calibration (SDOF models)": read its files, build its content.

The run-up calibration (issue 20, :func:`rigtools.calibration.calibrate_runups`, run by the
pipeline's calibrate stage) writes into ``OUTDIR/calibration/runup/``::

    comparison.json          PSIS-LOO of the SDOF models (pointwise and blocked), statement
    <model>/summary.json     parameters, derived natural frequencies, backlash, jumps per run
    runup_<stem>.png         one figure per run (stems from pipeline.json)

:func:`read_runup_inputs` reads these files (as :mod:`rigtools.report.inputs` reads the
others: JSON parsed, PNGs checked for their signature, nothing else) and
:func:`runup_section` turns them into the ``runup_calibration`` section of report.json
(schema ``data_schemas/report.schema.json``):

``status``, ``error``
    ``"ok"`` with files; ``"failed"`` with the pipeline's message (``pipeline.json``
    ``stages.calibrate.runup``) when the run-up part failed.
``comparison``
    Per model elpd_loo, se, elpd_diff, dse, the largest Pareto k (pointwise, and the blocked
    check over neighbouring points), the favoured model and the statement.
``fits``
    Per model: convergence, ``zeta`` and ``mesh_natural_frequency_Hz`` with their 90 %
    intervals and identified flags, every parameter, the load-dependent natural frequency
    of each run, the backlash statement, the jump frequencies (measured and modelled), warnings.
``figures``
    Run id -> figure key (``runup:<run id>``) of the runs that have a figure.
``truth``
    The demo's truth (``demo_truth.json`` ``runup``) beside each model's posterior.

The section is ``None`` (absent from report.json, not empty) when the campaign has no
run-up calibration: no ``calibration/runup`` files and no failed run-up part in
``pipeline.json``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

from rigtools.report.inputs import read_json_object
from rigtools.report.values import as_dict, as_float, as_int, as_quantity, as_str, plain

__all__ = [
    "FIGURE_PREFIX",
    "RUNUP_FOLDER",
    "RUNUP_QUANTITIES",
    "RunUpInputs",
    "read_runup_inputs",
    "runup_section",
    "runup_stage_status",
]

#: Folder of the run-up calibration's files, relative to OUTDIR.
RUNUP_FOLDER: Final = "calibration/runup"
#: Key prefix of the run-up figures in the page's figure mapping (``runup:<run id>``).
FIGURE_PREFIX: Final = "runup:"
#: The quantities shown first for every model (summary ``parameters`` or ``derived``).
RUNUP_QUANTITIES: Final = ("zeta", "mesh_natural_frequency_Hz")
#: A stem as the pipeline writes it (the rule of :mod:`rigtools.report.inputs`).
_STEM: Final = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,80}")
_MODEL_NAME_CHARS: Final = frozenset("abcdefghijklmnopqrstuvwxyz0123456789_-")
_PNG_SIGNATURE: Final = b"\x89PNG\r\n\x1a\n"
_MAX_FIGURE_BYTES: Final = 20 * 1024 * 1024
_COMPARISON_FIELDS: Final = ("elpd_loo", "se", "p_loo", "elpd_diff", "dse", "weight",
                             "pareto_k_max")


@dataclass(frozen=True)
class RunUpInputs:
    """The files of the run-up calibration in an OUTDIR.

    Attributes
    ----------
    status : dict
        ``pipeline.json`` ``stages.calibrate.runup`` (empty when the pipeline says nothing).
    comparison : dict or None
        ``comparison.json``.
    summaries : dict of str to dict
        Model -> ``<model>/summary.json``, in the comparison's model order.
    figures : dict of str to bytes
        Run id -> PNG bytes of ``runup_<stem>.png``.
    notes : tuple of str
        What is absent or unreadable.
    """

    status: dict[str, Any] = field(default_factory=dict)
    comparison: dict[str, Any] | None = None
    summaries: dict[str, dict[str, Any]] = field(default_factory=dict)
    figures: dict[str, bytes] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    @property
    def present(self) -> bool:
        """Whether any run-up output is there."""
        return self.comparison is not None or bool(self.summaries) or bool(self.figures)


def runup_stage_status(pipeline: dict[str, Any] | None) -> dict[str, Any]:
    """``stages.calibrate.runup`` of ``pipeline.json`` (empty dict when absent)."""
    return as_dict(as_dict(as_dict(as_dict(pipeline).get("stages")).get("calibrate"))
                   .get("runup"))


def _model_names(folder: Path, comparison: dict[str, Any] | None) -> list[str]:
    listed = (comparison or {}).get("models")
    names = [str(m) for m in listed] if isinstance(listed, list) else []
    if folder.is_dir():
        names += sorted(p.name for p in folder.iterdir()
                        if p.is_dir() and (p / "summary.json").is_file())
    # a model name becomes a folder name: only plain lower-case names are read
    return [m for m in dict.fromkeys(names) if m and set(m) <= _MODEL_NAME_CHARS]


def _png(path: Path, name: str, notes: list[str]) -> bytes | None:
    if not path.is_file():
        return None
    if path.stat().st_size > _MAX_FIGURE_BYTES:
        notes.append(f"{name} is larger than {_MAX_FIGURE_BYTES} bytes: not embedded")
        return None
    data = path.read_bytes()
    if not data.startswith(_PNG_SIGNATURE):
        notes.append(f"{name} is not a PNG file: not embedded")
        return None
    return data


def read_runup_inputs(outdir: str | Path, pipeline: dict[str, Any] | None) -> RunUpInputs:
    """Read the run-up calibration's files of ``outdir`` (module notes).

    Parameters
    ----------
    outdir : str or pathlib.Path
    pipeline : dict or None
        ``pipeline.json`` (the run stems and the run-up part's status).

    Returns
    -------
    RunUpInputs

    Raises
    ------
    ReportInputError
        A JSON file present but malformed (file, line and column named).
    """
    folder = Path(outdir) / RUNUP_FOLDER
    status = runup_stage_status(pipeline)
    notes: list[str] = []
    comparison = read_json_object(folder / "comparison.json")
    summaries: dict[str, dict[str, Any]] = {}
    for model in _model_names(folder, comparison):
        s = read_json_object(folder / model / "summary.json")
        if s is None:
            notes.append(f"run-up calibration: {RUNUP_FOLDER}/{model}/summary.json is absent")
        else:
            summaries[model] = s
    figures: dict[str, bytes] = {}
    runs = as_dict(pipeline).get("runs")
    for run in runs if isinstance(runs, list) else []:
        rid, stem = as_str(as_dict(run).get("run_id")), as_str(as_dict(run).get("stem"))
        if rid is None or stem is None or not _STEM.fullmatch(stem) or stem in {".", ".."}:
            continue  # a stem that is not a plain file name could point outside OUTDIR
        name = f"runup_{stem}.png"
        data = _png(folder / name, f"{RUNUP_FOLDER}/{name}", notes)
        if data is not None:
            figures[rid] = data
    return RunUpInputs(status=status, comparison=comparison, summaries=summaries,
                       figures=figures, notes=tuple(notes))


# --------------------------------------------------------------------------------------------
# content


def _comparison_rows(block: dict[str, Any], models: list[str]) -> list[dict[str, Any]]:
    rows_in = as_dict(block.get("variants"))
    order = [m for m in models if m in rows_in] + [str(m) for m in rows_in if m not in models]
    rows = []
    for m in order:
        r = as_dict(rows_in.get(m))
        row: dict[str, Any] = {"model": m, **{k: as_float(r.get(k)) for k in _COMPARISON_FIELDS}}
        row["n_pareto_k_bad"] = as_int(r.get("n_pareto_k_bad"))
        row["rank"] = as_int(r.get("rank"))
        rows.append(row)
    rows.sort(key=lambda x: (x["rank"] is None, x["rank"] if x["rank"] is not None else 0))
    return rows


def _comparison(doc: dict[str, Any] | None, models: list[str]) -> dict[str, Any] | None:
    if doc is None:
        return None
    pointwise = as_dict(doc.get("pointwise"))
    if not pointwise and isinstance(doc.get("variants"), dict):
        pointwise = doc  # a flat comparison (ModelComparison.to_dict)
    blocked = as_dict(doc.get("blocked"))
    refused = {str(k): str(v) for k, v in as_dict(doc.get("refused")).items()}
    return {
        "criterion": as_str(doc.get("criterion")) or as_str(pointwise.get("criterion")),
        "favoured": as_str(doc.get("favoured")) or as_str(pointwise.get("favoured")),
        "statement": as_str(doc.get("statement")) or as_str(pointwise.get("statement")),
        "rows": _comparison_rows(pointwise, models),
        "blocked_rows": _comparison_rows(blocked, models),
        "blocked_statement": as_str(blocked.get("statement")),
        "runs": [str(r) for r in doc.get("runs") or [] if isinstance(r, str)],
        "refused": refused,
    }


def _quantity(summary: dict[str, Any], name: str) -> dict[str, Any] | None:
    """A summary quantity with its identified flag (parameters, derived, or top level)."""
    for group in (as_dict(summary.get("parameters")), as_dict(summary.get("derived")),
                  summary):
        q = group.get(name)
        if isinstance(q, dict):
            out = as_quantity(q) or {}
            ident = q.get("identified")
            return {**out, "identified": ident if isinstance(ident, bool) else None,
                    "statement": as_str(q.get("statement"))}
    return None


def _backlash(summary: dict[str, Any]) -> dict[str, Any]:
    block = as_dict(summary.get("backlash"))
    param = as_dict(as_dict(summary.get("parameters")).get("backlash"))
    statement = (as_str(block.get("statement")) or as_str(summary.get("backlash_statement"))
                 or as_str(param.get("statement")))
    ident = param.get("identified", block.get("identified"))
    p_impact = as_float(block.get("backside_impact_probability"))
    if p_impact is None:
        p_impact = as_float(summary.get("backside_impact_probability"))
    return {"identified": ident if isinstance(ident, bool) else None,
            "statement": statement, "backside_impact_probability": p_impact,
            "posterior": _quantity(summary, "backlash")}


def _jump(v: Any) -> dict[str, Any] | None:
    if isinstance(v, dict):
        return {"q05": as_float(v.get("q05")), "q50": as_float(v.get("q50")),
                "q95": as_float(v.get("q95"))}
    f = as_float(v)
    return None if f is None else {"q05": None, "q50": f, "q95": None}


def _fit_runs(summary: dict[str, Any]) -> list[dict[str, Any]]:
    derived = as_dict(summary.get("derived"))
    out = []
    for rid, r in as_dict(summary.get("runs")).items():
        rd = as_dict(r)
        measured, model = as_dict(rd.get("jump_measured_Hz")), as_dict(rd.get("jump_model_Hz"))
        f_run = _quantity(summary, f"mesh_natural_frequency_Hz@{rid}")
        if f_run is None:
            f_run = as_quantity(derived.get(f"model_natural_frequency_Hz@{rid}"))
        out.append({
            "run_id": str(rid),
            "gear_set": as_str(rd.get("gear_set")),
            "torque_Nm": as_float(rd.get("torque_Nm")),
            "mesh_natural_frequency_Hz": f_run,
            "jump_measured_up_Hz": as_float(measured.get("up")),
            "jump_measured_down_Hz": as_float(measured.get("down")),
            "jump_model_up_Hz": _jump(model.get("up")),
            "jump_model_down_Hz": _jump(model.get("down")),
            "backside_impact_probability": as_float(rd.get("backside_impact_probability")),
            "contact_loss_probability": as_float(rd.get("contact_loss_probability")),
        })
    return out


def _parameters(summary: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for name, q in as_dict(summary.get("parameters")).items():
        qd = as_dict(q)
        ident = qd.get("identified")
        out.append({"name": str(name), "posterior": as_quantity(qd),
                    "identified": ident if isinstance(ident, bool) else None,
                    "ess_bulk": as_float(qd.get("ess_bulk")), "r_hat": as_float(qd.get("r_hat")),
                    "statement": as_str(qd.get("statement"))})
    return out


def _fit(model: str, summary: dict[str, Any]) -> dict[str, Any]:
    converged = summary.get("converged")
    return {
        "model": model,
        "converged": converged if isinstance(converged, bool) else None,
        "zeta": _quantity(summary, "zeta"),
        "mesh_natural_frequency_Hz": _quantity(summary, "mesh_natural_frequency_Hz"),
        "backlash": _backlash(summary),
        "parameters": _parameters(summary),
        "runs": _fit_runs(summary),
        "conventions": plain(as_dict(summary.get("conventions"))),
        "warnings": [str(w) for w in summary.get("warnings") or [] if isinstance(w, str)],
    }


def _posterior_for(summary: dict[str, Any], name: str, run_ids: list[str]
                   ) -> dict[str, Any] | None:
    """The summary's counterpart of a truth quantity, None when it has none.

    A parameter or derived quantity, a gain ``gain@<channel>`` (the summary's ``gains``
    ``<run>/<channel>``) or a jump frequency ``jump_frequency_<up|down>_Hz@<run>`` (the
    run's modelled jump).
    """
    q = _quantity(summary, name)
    if q is not None or "@" not in name:
        return q
    head, _, tail = name.partition("@")
    if head == "gain":
        gains = as_dict(summary.get("gains"))
        for rid in run_ids:
            g = gains.get(f"{rid}/{tail}")
            if isinstance(g, dict):
                return {**(as_quantity(g) or {}), "identified": None, "statement": None}
        return None
    for d in ("up", "down"):
        if head == f"jump_frequency_{d}_Hz":
            j = as_dict(as_dict(as_dict(summary.get("runs")).get(tail)).get("jump_model_Hz"))
            jd = j.get(d)
            if isinstance(jd, dict):
                return {"mean": None, "sd": None, "q05": as_float(jd.get("q05")),
                        "q50": as_float(jd.get("q50")), "q95": as_float(jd.get("q95")),
                        "unit": "Hz", "identified": None, "statement": None}
    return None


def _truth_blocks(truth: dict[str, Any] | None) -> list[dict[str, Any]]:
    block = as_dict(truth).get("runup")
    if isinstance(block, dict):
        return [block]
    if isinstance(block, list):
        return [b for b in block if isinstance(b, dict)]
    return []


def _truth(truth: dict[str, Any] | None, summaries: dict[str, dict[str, Any]]
           ) -> dict[str, Any] | None:
    blocks = _truth_blocks(truth)
    if not blocks:
        return None
    quantities: list[dict[str, Any]] = []
    seen: set[str] = set()
    run_ids = [r for r in (as_str(b.get("run_id")) for b in blocks) if r is not None]
    for b in blocks:
        for group in ("parameters", "derived"):
            for name, t in as_dict(b.get(group)).items():
                if name in seen:
                    continue
                seen.add(str(name))
                td = as_dict(t)
                value = as_float(td.get("value")) if td else as_float(t)
                per_model = {}
                for model, s in summaries.items():
                    q = _posterior_for(s, str(name), run_ids)
                    if q is None:
                        continue
                    covered = None
                    if value is not None and q.get("q05") is not None \
                            and q.get("q95") is not None:
                        covered = bool(q["q05"] <= value <= q["q95"])
                    per_model[model] = {"posterior": q, "covered": covered}
                quantities.append({"name": str(name), "unit": as_str(td.get("unit")),
                                   "truth": value, "models": per_model})
    first = blocks[0]
    impact = first.get("backside_impact")
    return {"model": as_str(first.get("model")), "run_ids": run_ids,
            "backside_impact": impact if isinstance(impact, bool) else None,
            "quantities": quantities}


def runup_section(runup: RunUpInputs | None, truth: dict[str, Any] | None
                  ) -> dict[str, Any] | None:
    """The ``runup_calibration`` section of report.json (module notes).

    Parameters
    ----------
    runup : RunUpInputs or None
        :func:`read_runup_inputs`; None: no run-up section.
    truth : dict or None
        The demo's truth file (its ``runup`` block is shown beside the posteriors).

    Returns
    -------
    dict or None
        None when there is no run-up calibration to report (the section is then absent).
    """
    if runup is None:
        return None
    state = as_str(runup.status.get("status"))
    error = as_str(runup.status.get("error"))
    if state == "failed":
        return {"status": "failed", "error": error or "the run-up calibration failed",
                "models": [], "comparison": None, "fits": [], "figures": [],
                "truth": None, "notes": list(runup.notes) + (
                    ["files of an earlier run-up calibration are left over: not used"]
                    if runup.present else [])}
    if state == "skipped" or not runup.present:
        return None
    models = list(runup.summaries)
    comparison = _comparison(runup.comparison, models)
    notes = list(runup.notes)
    if runup.comparison is None:
        notes.append(f"run-up calibration: {RUNUP_FOLDER}/comparison.json is absent")
    order = list(dict.fromkeys([*(comparison or {}).get("runs", []),
                                *(r for s in runup.summaries.values()
                                  for r in as_dict(s.get("runs"))),
                                *runup.figures]))
    return {
        "status": "ok",
        "error": None,
        "models": models,
        "comparison": comparison,
        "fits": [_fit(m, s) for m, s in runup.summaries.items()],
        "figures": [{"run_id": rid, "key": f"{FIGURE_PREFIX}{rid}"}
                    for rid in order if rid in runup.figures],
        "truth": _truth(truth, runup.summaries),
        "notes": notes,
    }
