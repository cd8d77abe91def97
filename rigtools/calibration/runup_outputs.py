r"""The result of a run-up calibration and its files.

:class:`RunUpResult` (what :func:`~rigtools.calibration.runup_api.calibrate_runups`
returns) holds one :class:`RunUpFit` per SDOF model and the PSIS-LOO comparison; every
number the figure (:mod:`rigtools.plots.runup`) and the report need is a plain array or dict
on it. :meth:`RunUpResult.to_dict` is the JSON content:
``to_dict()["models"][<model>]`` is ``runup/<model>/summary.json`` (valid against
``data_schemas/runup_summary.schema.json``), ``to_dict()["comparison"]`` is
``runup/comparison.json``.

Files (:func:`write_runup_outputs`, under ``<calibration dir>/runup/``, the pipeline's
``OUTDIR/calibration/runup/``):

``<model>/posterior.nc``
    arviz InferenceData (h5netcdf). ``posterior``: the free parameters (chains are the emcee
    walkers, draws thinned to at most :data:`MAX_STORED_DRAWS` in all),
    ``mesh_natural_frequency_Hz``, ``model_natural_frequency_Hz`` over ``run``, ``log_gain``
    over ``run_channel`` (drawn from its exact conditional). ``log_likelihood``:
    ``arms_point`` over ``point``, the leave-one-out log density of each observed (run, point),
    its channels together (they share the model error; the model is not factorised, so these
    are the exact Gaussian conditionals given the rest of the run:
    :mod:`rigtools.calibration.runup_likelihood`); what arviz's ``loo`` takes.
    ``posterior_predictive``: ``arms`` over ``obs`` (model, gain, the shared model error drawn
    along the run, the channel's error; log-normal). ``observed_data``: ``arms``.
    ``constant_data``: per ``obs`` its ``run``, ``channel``, ``point``, mesh frequency,
    direction and torque; per ``point`` its ``point_run`` and ``point_index``.
    ``sample_stats``: ``lp``. Attributes: the configuration (JSON), the model, convergence,
    sampler settings, rigtools version.
``<model>/summary.json``
    Parameters (mean, sd, q05, q50, q95, ess_bulk, r_hat, identified, prior; the interval
    left null with a statement when the data do not identify the parameter), derived
    ``mesh_natural_frequency_Hz`` and ``mesh_natural_frequency_Hz@<run>``, the gains, the
    backlash statement, jump frequencies per run, ``conventions``, sampler, warnings.
``comparison.json`` / ``comparison.csv``
    PSIS-LOO per model over points (``pointwise``) and over blocks of neighbouring points
    (``blocked``), elpd differences with their standard errors, Pareto k, the statement.
"""

from __future__ import annotations

import csv
import io
import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import arviz as az
import numpy as np

from rigtools.calibration.comparison import ModelComparison
from rigtools.calibration.outputs import csv_cell, replace_atomically, rigtools_version
from rigtools.calibration.runup_model import RunUpPosterior
from rigtools.calibration.sampler import SamplerRun

__all__ = [
    "COMPARISON_COLUMNS",
    "MAX_STORED_DRAWS",
    "RUNUP_DIR",
    "RunPredictive",
    "RunUpFit",
    "RunUpResult",
    "runup_inference_data",
    "write_runup_outputs",
]

#: Sub-directory of the calibration directory for the run-up calibration.
RUNUP_DIR: Final = "runup"
#: Posterior draws kept (all walkers together) for the predictive, the pointwise
#: log-likelihood and ``posterior.nc`` (the walkers' chains are thinned further to this).
MAX_STORED_DRAWS: Final = 1000
#: Columns of ``comparison.csv``.
COMPARISON_COLUMNS: Final = (
    "model", "elpd_loo", "se", "p_loo", "elpd_diff", "dse", "weight", "rank", "pareto_k_max",
    "n_pareto_k_bad", "blocked_elpd_loo", "blocked_se", "blocked_elpd_diff", "blocked_dse",
    "blocked_pareto_k_max",
)


@dataclass(frozen=True, eq=False)
class RunPredictive:
    """Measured and modelled run-up of one run under one model (for the figure and report).

    Arrays run along the run's time-ordered mesh-frequency path (``N`` points; bridging
    points carry NaN observations), channels along the first axis.

    Attributes
    ----------
    run_id : str
    gear_set : str
    torque_Nm : float
    channels : tuple of str
    mesh_frequency_Hz : numpy.ndarray
        ``(N,)`` (Hz), time order (up, then down).
    direction : numpy.ndarray
        ``(N,)`` ``"up"``, ``"down"`` or ``"hold"``.
    observed : numpy.ndarray
        ``(C, N)`` measured Arms (m/s^2), NaN where not observed.
    arms_q05, arms_q50, arms_q95 : numpy.ndarray
        ``(C, N)`` posterior predictive quantiles of Arms (m/s^2): model x gain x log-normal
        model error, over the posterior draws.
    jump_measured_Hz : dict
        ``"up"``/``"down"`` -> mesh frequency of the direction's jump between neighbouring
        observed points (its step out of the hysteresis band:
        :func:`~rigtools.calibration.runup_forward.jump_frequencies`; the geometric mean of
        the two points), None when there is none.
    jump_model_Hz : dict
        ``"up"``/``"down"`` -> ``{"q05", "q50", "q95"}`` of the same for the model (gain-free,
        at the points), over the posterior draws: the median of the geometric means, the
        interval from the 5 % quantile of the lower neighbours to the 95 % quantile of the
        upper ones (the points place a jump only between two of them); None when no draw
        jumps.
    backside_impact_probability : float
        Posterior probability of a back-side impact anywhere along this run.
    contact_loss_probability : float
        Posterior probability of contact loss anywhere along this run.
    """

    run_id: str
    gear_set: str
    torque_Nm: float
    channels: tuple[str, ...]
    mesh_frequency_Hz: np.ndarray
    direction: np.ndarray
    observed: np.ndarray
    arms_q05: np.ndarray
    arms_q50: np.ndarray
    arms_q95: np.ndarray
    jump_measured_Hz: dict[str, float | None]
    jump_model_Hz: dict[str, dict[str, float] | None]
    backside_impact_probability: float
    contact_loss_probability: float

    def to_dict(self) -> dict[str, Any]:
        """The run's numbers for ``summary.json`` (no arrays: jumps and probabilities)."""
        return {"gear_set": self.gear_set, "torque_Nm": self.torque_Nm,
                "channels": list(self.channels),
                "mesh_frequency_range_Hz": [float(np.min(self.mesh_frequency_Hz)),
                                            float(np.max(self.mesh_frequency_Hz))],
                "points": int(self.mesh_frequency_Hz.size),
                "jump_measured_Hz": self.jump_measured_Hz,
                "jump_model_Hz": self.jump_model_Hz,
                "backside_impact_probability": self.backside_impact_probability,
                "contact_loss_probability": self.contact_loss_probability}


@dataclass(frozen=True, eq=False)
class RunUpFit:
    """One SDOF model calibrated against every run-up.

    Attributes
    ----------
    model : {"fvms", "vvms", "lste"}
    posterior : RunUpPosterior
        The log posterior (forward model, priors, data).
    run : SamplerRun
        The emcee run (whole chain, tau, convergence).
    samples : numpy.ndarray
        Kept draws ``(W, n, D)`` (burn-in dropped, thinned to at most
        :data:`MAX_STORED_DRAWS`).
    log_prob : numpy.ndarray
        ``(W, n)``.
    log_likelihood : numpy.ndarray
        ``(W, n, U)`` leave-one-out log density, one per observed (run, point), all its
        channels together.
    log_gain : numpy.ndarray
        ``(W, n, G)`` drawn from the exact conditional, ``G`` = (run, channel) pairs.
    arms_predictive : numpy.ndarray
        ``(W, n, O)`` posterior predictive Arms at the observed points (m/s^2).
    obs_run, obs_channel, obs_point : numpy.ndarray
        ``(O,)`` index of the run (into ``posterior.forward.curves``), channel and point.
    loo_run, loo_point : numpy.ndarray
        ``(U,)`` index of the run and point of each ``log_likelihood`` term.
    block_log_likelihood : numpy.ndarray
        ``(W, n, B)`` leave-one-out log density of each observed block of neighbouring points
        (:func:`~rigtools.calibration.runup_api.loo_blocks`).
    gain_labels : tuple of str
        ``"<run>/<channel>"`` for the ``G`` gains.
    predictive : tuple of RunPredictive
        One per run.
    summary : dict
        ``summary.json``'s content.
    warnings : tuple of str
    seconds : float
        Wall time of the model's MAP, sampling and predictive (s).
    """

    model: str
    posterior: RunUpPosterior
    run: SamplerRun
    samples: np.ndarray
    log_prob: np.ndarray
    log_likelihood: np.ndarray
    log_gain: np.ndarray
    arms_predictive: np.ndarray
    obs_run: np.ndarray
    obs_channel: np.ndarray
    obs_point: np.ndarray
    loo_run: np.ndarray
    loo_point: np.ndarray
    block_log_likelihood: np.ndarray
    gain_labels: tuple[str, ...]
    predictive: tuple[RunPredictive, ...]
    summary: dict[str, Any]
    warnings: tuple[str, ...]
    seconds: float

    @property
    def converged(self) -> bool:
        """The autocorrelation rule passed."""
        return bool(self.run.converged)

    def predictive_for(self, run_id: str) -> RunPredictive:
        """The :class:`RunPredictive` of ``run_id``."""
        for p in self.predictive:
            if p.run_id == run_id:
                return p
        raise KeyError(run_id)


@dataclass(frozen=True, eq=False)
class RunUpResult:
    """Every SDOF model calibrated against the campaign's run-ups, and their comparison.

    Attributes
    ----------
    models : tuple of str
        The models fitted, in the configuration's order.
    fits : dict
        Model -> :class:`RunUpFit`.
    comparison : ModelComparison or None
        PSIS-LOO over the observed points (None with fewer than one model).
    blocked_comparison : ModelComparison or None
        PSIS-LOO over blocks of :data:`~rigtools.calibration.runup_api.BLOCK_POINTS`
        neighbouring points of one run and direction (all channels): the check that
        correlated neighbours do not make the pointwise se too small.
    statement : str
        The comparison in words, with the caveats.
    runs : tuple of str
        The runs calibrated against.
    refused : dict
        Run id -> why it was left out (item 7).
    warnings : tuple of str
        Everything the user must read (per model prefixed by the model's name).
    notes : tuple of str
        What was done (data preparation, checkpoint events).
    config : dict
        The resolved ``[calibration]`` configuration.
    seed : int
    """

    models: tuple[str, ...]
    fits: dict[str, RunUpFit]
    comparison: ModelComparison | None
    blocked_comparison: ModelComparison | None
    statement: str
    runs: tuple[str, ...]
    refused: dict[str, str]
    warnings: tuple[str, ...]
    notes: tuple[str, ...]
    config: dict[str, Any]
    seed: int

    def comparison_dict(self) -> dict[str, Any]:
        """``comparison.json``'s content."""
        return {
            "criterion": "psis-loo",
            "models": list(self.models),
            "pointwise": None if self.comparison is None else self.comparison.to_dict(),
            "blocked": (None if self.blocked_comparison is None
                        else self.blocked_comparison.to_dict()),
            "favoured": None if self.comparison is None else self.comparison.favoured,
            "statement": self.statement,
            "runs": list(self.runs),
            "refused": dict(self.refused),
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``{"models": {model: summary}, "comparison": ..., "refused", ...}``."""
        return {"models": {m: f.summary for m, f in self.fits.items()},
                "comparison": self.comparison_dict(),
                "runs": list(self.runs), "refused": dict(self.refused),
                "warnings": list(self.warnings), "notes": list(self.notes),
                "seed": self.seed}


def runup_inference_data(fit: RunUpFit, *, config: dict[str, Any],
                         seed: int) -> az.InferenceData:
    """InferenceData of one fitted model (module notes).

    Parameters
    ----------
    fit : RunUpFit
    config : dict
        The resolved configuration (JSON in the attributes).
    seed : int

    Returns
    -------
    arviz.InferenceData
    """
    post = fit.posterior
    fwd = post.forward
    runs = [c.run_id for c in fwd.curves]
    posterior: dict[str, np.ndarray] = {n: fit.samples[..., i] for i, n in enumerate(post.names)}
    s = post.unpack(fit.samples)["mesh_stiffness_scale"]
    posterior["mesh_natural_frequency_Hz"] = fwd.natural_frequency_Hz(s)
    posterior["model_natural_frequency_Hz"] = np.moveaxis(fwd.model_natural_frequency_Hz(s),
                                                          0, -1)
    posterior["log_gain"] = fit.log_gain
    obs_f = np.array([fwd.curves[r].mesh_frequency_Hz[i]
                      for r, i in zip(fit.obs_run, fit.obs_point, strict=True)])
    obs_dir = np.array([str(fwd.curves[r].direction[i])
                        for r, i in zip(fit.obs_run, fit.obs_point, strict=True)])
    observed = np.array([fwd.curves[r].observed[c, i] for r, c, i in
                         zip(fit.obs_run, fit.obs_channel, fit.obs_point, strict=True)])
    chan = np.array([fwd.curves[r].channels[c]
                     for r, c in zip(fit.obs_run, fit.obs_channel, strict=True)])
    torque = np.array([fwd.curves[r].torque_Nm for r in fit.obs_run], dtype=float)
    attrs = {"calibration_config": json.dumps(config), "model": fit.model,
             "converged": int(fit.converged), "n_steps": fit.run.n_steps,
             "burn_in": fit.run.burn_in, "thin": fit.run.thin,
             "tau": json.dumps([float(t) for t in fit.run.tau]),
             "walkers": int(fit.samples.shape[0]), "seed": int(seed),
             "fixed": json.dumps(post.fixed), "rigtools_version": rigtools_version()}
    with warnings.catch_warnings():
        # "more chains than draws": emcee has many walkers and few thinned draws each
        warnings.filterwarnings("ignore", message="More chains")
        return _from_dict(fit, posterior, observed, chan, torque, obs_f, obs_dir, runs, attrs)


def _from_dict(fit: RunUpFit, posterior: dict[str, np.ndarray], observed: np.ndarray,
               chan: np.ndarray, torque: np.ndarray, obs_f: np.ndarray, obs_dir: np.ndarray,
               runs: list[str], attrs: dict[str, Any]) -> az.InferenceData:
    return az.from_dict(
        posterior=posterior,
        posterior_predictive={"arms": fit.arms_predictive},
        log_likelihood={"arms_point": fit.log_likelihood},
        observed_data={"arms": observed},
        constant_data={"obs_run": np.array([runs[r] for r in fit.obs_run]),
                       "obs_channel": chan, "obs_point": fit.obs_point.astype(np.int64),
                       "mesh_frequency_Hz": obs_f, "direction": obs_dir, "torque_Nm": torque,
                       "point_run": np.array([runs[r] for r in fit.loo_run]),
                       "point_index": fit.loo_point.astype(np.int64)},
        sample_stats={"lp": fit.log_prob},
        coords={"obs": list(range(fit.obs_run.size)), "point": list(range(fit.loo_run.size)),
                "run": runs,
                "run_channel": list(fit.gain_labels)},
        dims={"arms": ["obs"], "model_natural_frequency_Hz": ["run"],
              "log_gain": ["run_channel"], "obs_run": ["obs"], "obs_channel": ["obs"],
              "obs_point": ["obs"], "mesh_frequency_Hz": ["obs"], "direction": ["obs"],
              "torque_Nm": ["obs"], "arms_point": ["point"], "point_run": ["point"],
              "point_index": ["point"]},
        attrs=attrs,
    )


def _comparison_csv(result: RunUpResult) -> str:
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(COMPARISON_COLUMNS)
    point = {} if result.comparison is None else result.comparison.variants
    block = {} if result.blocked_comparison is None else result.blocked_comparison.variants
    for m in result.models:
        p, b = point.get(m, {}), block.get(m, {})
        w.writerow([m, *(csv_cell(p.get(k)) for k in COMPARISON_COLUMNS[1:10]),
                    *(csv_cell(b.get(k)) for k in ("elpd_loo", "se", "elpd_diff", "dse",
                                                "pareto_k_max"))])
    return buf.getvalue()


def write_runup_outputs(result: RunUpResult, outdir: str | Path) -> dict[str, Path]:
    """Write the run-up files into ``outdir/runup/`` (module notes).

    Parameters
    ----------
    result : RunUpResult
    outdir : str or pathlib.Path
        The calibration directory (``OUTDIR/calibration`` in the pipeline); created when
        absent.

    Returns
    -------
    dict
        ``"<model>/posterior"``, ``"<model>/summary"``, ``"comparison_json"``,
        ``"comparison_csv"`` -> path.
    """
    root = Path(outdir) / RUNUP_DIR
    root.mkdir(parents=True, exist_ok=True)
    paths: dict[str, Path] = {}
    for m, fit in result.fits.items():
        d = root / m
        d.mkdir(parents=True, exist_ok=True)
        nc = d / "posterior.nc"
        tmp = nc.with_name(f"posterior.nc.tmp-{os.getpid()}")
        try:
            runup_inference_data(fit, config=result.config, seed=result.seed).to_netcdf(
                str(tmp), engine="h5netcdf")
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(tmp, nc)
        finally:
            tmp.unlink(missing_ok=True)
        sj = d / "summary.json"
        replace_atomically(sj, json.dumps(fit.summary, indent=2, allow_nan=False) + "\n")
        paths[f"{m}/posterior"], paths[f"{m}/summary"] = nc, sj
    cj, cc = root / "comparison.json", root / "comparison.csv"
    replace_atomically(cj, json.dumps(result.comparison_dict(), indent=2, allow_nan=False) + "\n")
    replace_atomically(cc, _comparison_csv(result))
    paths["comparison_json"], paths["comparison_csv"] = cj, cc
    return paths
