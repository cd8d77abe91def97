r"""The files of a calibration: ``posterior.nc``, ``summary.json``, ``summary.csv``.

``posterior.nc``
    arviz :class:`~arviz.InferenceData` (arviz 0.23, the format Python 3.11 supports) of the
    headline variant as netCDF (h5netcdf). Groups: ``posterior`` (chains are emcee walkers;
    the parameters, ``temperature_offset`` over ``run`` when sampled, and the derived
    ``critical_gap`` and ``thermal_closure`` over ``temperature_C``, ``margin`` over ``run``,
    ``margin_operating``, ``flip_temperature_C``, ``mesh_stiffness_elastic``),
    ``posterior_predictive`` (``f_n``: a new mesh-mode measurement of each run, model
    prediction plus the model error and the run's typical fit sd; ``f_n_model`` without
    them), ``log_likelihood`` (``f_n``: the per-run mixture log-likelihood), ``observed_data``
    (``f_n``: the peak chosen as the mesh mode, NaN where none; ``candidate_f_n``),
    ``constant_data`` (conditions, candidate sds and channels) and ``sample_stats`` (``lp``,
    ``n_jammed``). Attributes: the resolved configuration (``calibration_config``, JSON),
    variant, convergence, sampler settings, rigtools version.
``summary.json``
    :attr:`CalibrationResult.summary`, valid against
    ``data_schemas/calibration_summary.schema.json``.
``summary.csv``
    One row per parameter and derived quantity: ``name, kind, unit, mean, sd, q05, q50, q95,
    ess_bulk, r_hat`` (empty where not finite).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Final

import arviz as az
import numpy as np

from rigtools.calibration.derived import temperature_label
from rigtools.calibration.model import TEMPERATURE_OFFSET
from rigtools.calibration.result import CalibrationResult, VariantFit

__all__ = [
    "CSV_COLUMNS",
    "csv_cell",
    "inference_data",
    "replace_atomically",
    "rigtools_version",
    "write_outputs",
    "write_summary_csv",
    "write_summary_json",
]

#: Columns of ``summary.csv``.
CSV_COLUMNS: Final = ("name", "kind", "unit", "mean", "sd", "q05", "q50", "q95", "ess_bulk",
                      "r_hat")


def rigtools_version() -> str:
    """The installed rigtools version recorded in the outputs ("unknown" when not installed)."""
    try:
        return version("rigtools")
    except PackageNotFoundError:
        return "unknown"


def inference_data(fit: VariantFit, *, config: dict[str, Any], seed: int,
                   attrs: dict[str, Any] | None = None) -> az.InferenceData:
    """InferenceData of one fitted variant (module notes).

    Parameters
    ----------
    fit : VariantFit
    config : dict
        The resolved configuration (stored as JSON in the attributes).
    seed : int
        Seeds the noise of the posterior predictive.
    attrs : dict, optional
        More attributes (scalars or strings).

    Returns
    -------
    arviz.InferenceData
    """
    model = fit.model
    runs = list(model.data.runs.run_id)
    posterior: dict[str, np.ndarray] = {}
    offsets = []
    for i, n in enumerate(model.names):
        if n.startswith(TEMPERATURE_OFFSET):
            offsets.append(fit.samples[..., i])
        else:
            posterior[n] = fit.samples[..., i]
    if offsets:
        posterior["temperature_offset"] = np.stack(offsets, axis=-1)
    q = {x.name: x for x in fit.quantities}
    temps = [t for t in (float(k.split("@")[1][:-1]) for k in q if k.startswith("critical_gap@"))]
    posterior["critical_gap"] = np.stack(
        [q[f"critical_gap@{temperature_label(t)}"].draws for t in temps], axis=-1)
    posterior["thermal_closure"] = np.stack(
        [q[f"thermal_closure@{temperature_label(t)}"].draws for t in temps], axis=-1)
    posterior["margin"] = np.stack([q[f"margin@{r}"].draws for r in runs], axis=-1)
    op = [k for k in q if k.startswith("margin@") and k.endswith("C")
          and k[len("margin@"):] not in runs]
    if op:
        posterior["margin_operating"] = q[op[0]].draws
    posterior["flip_temperature_C"] = q["flip_temperature_C"].draws
    posterior["mesh_stiffness_elastic"] = q["mesh_stiffness_elastic"].draws
    cand = model.data.candidates
    rng = np.random.default_rng([seed, 2])
    typical_sd = np.array([np.median(cand.sd_Hz[r, :cand.count[r]]) for r in range(len(runs))])
    me = model.unpack(fit.samples)["model_error"][..., None]
    f = fit.f_pred_Hz
    sd = np.sqrt(typical_sd**2 + (me * np.nan_to_num(f)) ** 2)
    noisy = f + sd * rng.standard_normal(f.shape)
    chosen = np.array([np.nan if fit.runs[r]["mesh_mode_Hz"] is None
                       else fit.runs[r]["mesh_mode_Hz"] for r in runs])
    n_j = cand.f_Hz.shape[1]
    cf = np.where(cand.mask, cand.f_Hz, np.nan)
    csd = np.where(cand.mask, cand.sd_Hz, np.nan)
    chan = np.where(cand.mask, cand.channel, "").astype(str)
    dims = {"temperature_offset": ["run"], "critical_gap": ["temperature_C"],
            "thermal_closure": ["temperature_C"], "margin": ["run"], "f_n": ["run"],
            "f_n_model": ["run"], "candidate_f_n": ["run", "candidate"],
            "candidate_sd_Hz": ["run", "candidate"], "candidate_channel": ["run", "candidate"],
            "torque_Nm": ["run"], "bulk_temperature_C": ["run"]}
    coords = {"run": runs, "temperature_C": temps, "candidate": list(range(n_j))}
    base_attrs = {"calibration_config": json.dumps(config), "model_variant": fit.variant,
                  "converged": int(fit.converged), "n_steps": fit.run.n_steps,
                  "burn_in": fit.run.burn_in, "thin": fit.run.thin,
                  "tau": json.dumps([float(t) for t in fit.run.tau]),
                  "walkers": int(fit.samples.shape[0]), "seed": int(seed),
                  "rigtools_version": rigtools_version()}
    base_attrs.update(attrs or {})
    return az.from_dict(
        posterior=posterior,
        posterior_predictive={"f_n": noisy, "f_n_model": f},
        log_likelihood={"f_n": fit.log_likelihood},
        observed_data={"f_n": chosen, "candidate_f_n": cf},
        constant_data={"torque_Nm": model.data.runs.torque_Nm,
                       "bulk_temperature_C": model.data.runs.bulk_temperature_C,
                       "candidate_sd_Hz": csd, "candidate_channel": chan},
        sample_stats={"lp": fit.log_prob, "n_jammed": fit.jammed.sum(axis=-1)},
        coords=coords, dims=dims, attrs=base_attrs,
    )


def csv_cell(v: Any) -> str:
    """``v`` as a CSV cell: empty for None and for a non-finite float, else its repr/str."""
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if not math.isfinite(v) else repr(v)
    return str(v)


def replace_atomically(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, fsync it, then rename it over."""
    tmp = path.with_name(f"{path.name}.tmp-{os.getpid()}")
    try:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_summary_csv(result: CalibrationResult, path: Path) -> None:
    """``summary.csv`` (module notes), written atomically."""
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(CSV_COLUMNS)
    for kind in ("parameters", "derived"):
        for name, s in result.summary[kind].items():
            w.writerow([name, kind[:-1] if kind == "parameters" else kind, s["unit"],
                        *(csv_cell(s[c]) for c in CSV_COLUMNS[3:])])
    replace_atomically(path, buf.getvalue())


def write_summary_json(result: CalibrationResult, path: Path) -> None:
    """``summary.json`` (module notes), written atomically."""
    replace_atomically(path, json.dumps(result.summary, indent=2, allow_nan=False) + "\n")


def write_outputs(result: CalibrationResult, outdir: str | Path) -> dict[str, Path]:
    """Write ``posterior.nc``, ``summary.json`` and ``summary.csv`` into ``outdir``.

    Parameters
    ----------
    result : CalibrationResult
    outdir : str or pathlib.Path
        Created when absent.

    Returns
    -------
    dict
        File kind -> path.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"posterior": out / "posterior.nc", "summary_json": out / "summary.json",
             "summary_csv": out / "summary.csv"}
    idata = inference_data(result.headline, config=result.config.to_dict(),
                           seed=result.config.seed)
    tmp = paths["posterior"].with_name(f"posterior.nc.tmp-{os.getpid()}")
    try:
        idata.to_netcdf(str(tmp), engine="h5netcdf")
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, paths["posterior"])
    finally:
        tmp.unlink(missing_ok=True)
    write_summary_json(result, paths["summary_json"])
    write_summary_csv(result, paths["summary_csv"])
    return paths
