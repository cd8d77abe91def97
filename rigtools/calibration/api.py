r"""``calibrate_observations``: from an observations table to a posterior, everything derived.

(:func:`rigtools.calibration.calibrate` takes a campaign and reads the pair, the
``[calibration]`` block and the ``[thermal]`` reference from it, then comes here.)

::

    from models.geometry import load_gear_set
    from rigtools.calibration import calibrate_observations, write_outputs

    result = calibrate_observations(observations, load_gear_set("fzg-c").pair, config,
                                    outdir="cal")
    result.summary["derived"]["critical_gap@90C"]      # mean, sd, q05, q50, q95, ess, r_hat
    result.summary["runs"]["LS9-90C"]["regime"]        # 'rises' | 'falls' | 'unchanged'

Steps: the table becomes runs, conditions and candidate peaks
(:mod:`~rigtools.calibration.data`); each variant in ``compare_variants`` (headline first)
gets its log posterior (:mod:`~rigtools.calibration.model`), a MAP and an emcee run
(:mod:`~rigtools.calibration.sampler`, resumable through ``OUTDIR/chains.h5``); the headline
variant's MAP is checked against the data first (priors that exclude every run's peaks, or
that jam every run, stop here with a :class:`~rigtools.calibration.errors.CalibrationError`
naming the key); then derived quantities and run summaries
(:mod:`~rigtools.calibration.derived`), diagnostics and warnings
(:mod:`~rigtools.calibration.diagnostics`), the PSIS-LOO comparison
(:mod:`~rigtools.calibration.comparison`) and ``summary.json``'s content. With ``outdir`` the
files of :mod:`~rigtools.calibration.outputs` are written. Figures are drawn by
:mod:`rigtools.plots.calibration` from the result.

A result that did not converge is returned all the same, flagged (``converged`` false, a
warning): the caller decides (the command line exits 0 with a warning line).

Randomness: one integer ``seed`` (``config.seed`` unless given) drives the MAP starts, the
walker ball, the sampler and the posterior-predictive noise, and is recorded in the outputs.
It is an integer rather than a ``numpy.random.Generator`` because a killed run must be able
to restart the same stream from the file alone.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import arviz as az
import numpy as np
import pandas as pd

from models.geometry import EQUIVALENT_MASS_CONVENTION, GearPair, load_gear_set
from models.thermal import ThermalReference
from rigtools.calibration.comparison import ModelComparison, compare_variants
from rigtools.calibration.config import PARAMETERS, CalibrationConfig, Variant, default_config
from rigtools.calibration.data import CalibrationData, prepare_data
from rigtools.calibration.derived import (
    ROBUSTNESS,
    derived_quantities,
    run_margins_um,
    run_summaries,
)
from rigtools.calibration.diagnostics import check_fit, summarize
from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.model import CalibrationModel, build_model
from rigtools.calibration.outputs import write_outputs
from rigtools.calibration.result import CalibrationResult, VariantFit
from rigtools.calibration.sampler import (
    BIMODAL_LOG_PROB,
    MapEstimate,
    Progress,
    SamplerSettings,
    find_map,
    run_sampler,
)

__all__ = ["CHECKPOINT_FILE", "INFORMATIVE_NOTES", "calibrate_observations", "resolve_reference"]

#: The chains' checkpoint file in OUTDIR.
CHECKPOINT_FILE = "chains.h5"
#: Notes that describe what was done rather than what is wrong: kept in ``summary.json``'s
#: ``data.notes`` and ``sampler.notes``, not repeated as warnings.
INFORMATIVE_NOTES = ("recurring peaks", "walkers stranded")


def resolve_reference(config: CalibrationConfig,
                      thermal_reference: ThermalReference | None) -> ThermalReference:
    """The thermal reference state: the campaign's, with ``reference_temperature_C`` applied.

    Without either, ``ThermalReference(20.0)`` (assembly at 20 degC, fixed centre distance).
    """
    if thermal_reference is None:
        t = 20.0 if config.reference_temperature_C is None else config.reference_temperature_C
        return ThermalReference(t)
    if config.reference_temperature_C is None:
        return thermal_reference
    return replace(thermal_reference, reference_temperature_C=config.reference_temperature_C)


def _fingerprint(config: CalibrationConfig, data: CalibrationData, pair: GearPair,
                 reference: ThermalReference, variant: str) -> str:
    h = hashlib.sha256()
    cfg = config.to_dict()
    h.update(json.dumps(cfg, sort_keys=True).encode())
    h.update(variant.encode())
    h.update(repr(pair).encode())
    h.update(repr(reference).encode())
    for a in (data.runs.torque_Nm, data.runs.bulk_temperature_C, data.runs.oil_temperature_C,
              data.candidates.f_Hz, data.candidates.sd_Hz, data.candidates.mask):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update("\0".join(data.runs.run_id).encode())
    return h.hexdigest()


def _check_map_against_data(model: CalibrationModel, map_est: MapEstimate) -> None:
    """Stop when the best fit the priors allow explains no run's peaks (issue 18 item 12)."""
    theta = map_est.theta[None, :]
    _, _, f = model.evaluate(theta)
    me = model.unpack(theta)["model_error"]
    assign = model.likelihood.assignment_probabilities(f, me)
    p_none = assign[0, :, -1]
    if np.any(p_none < 0.5):
        return
    runs = model.data.runs.run_id
    at_bound = []
    for n, p, x in zip(model.names, model.priors, map_est.theta, strict=True):
        dom = PARAMETERS[n].domain if n in PARAMETERS else (-np.inf, np.inf)
        tol = 1e-2 * p.moments()[1]
        if (p.lower > dom[0] and x - p.lower <= tol) or (p.upper < dom[1]
                                                         and p.upper - x <= tol):
            at_bound.append(n)
    jammed = np.isnan(f[0])
    if jammed.all() or (model.variant != "tangent" and model.predict(theta).jammed.all()):
        raise CalibrationError(
            f"every run ({', '.join(runs)}) is jammed by thermal growth at the best fit the "
            "priors allow (the thermal closure exceeds the backlash plus the elastic "
            "deflection): the natural frequencies cannot be fitted; widen the backlash prior or "
            "narrow the closure coefficient's", key="calibration.priors.backlash")
    cand = model.data.candidates
    f_lo, f_hi = float(np.nanmin(f)), float(np.nanmax(f))
    c_lo = float(np.min(cand.f_Hz[cand.mask]))
    c_hi = float(np.max(cand.f_Hz[cand.mask]))
    side = "above" if f_lo > c_hi else "below" if f_hi < c_lo else "around"
    # the stiffness scale moves every prediction at once: name it unless it is fixed
    first = "stiffness_scale" if "stiffness_scale" in model.names else (
        at_bound[0] if at_bound else None)
    key = f"calibration.priors.{first}" if first else "calibration.priors"
    hint = (f"; at the bound of its prior: {', '.join(at_bound)}" if at_bound else "")
    hint = f" (the predictions lie {side} the peaks){hint}"
    raise CalibrationError(
        f"the priors exclude the data: at the best fit they allow, the predicted mesh modes "
        f"({f_lo:.4g}-{f_hi:.4g} Hz) match none of the runs' peaks ({c_lo:.4g}-{c_hi:.4g} Hz)"
        f"{hint}; widen the priors (stiffness_scale, backlash) or check equivalent_mass_kg "
        "and band_Hz", key=key)


def _bimodality(model: CalibrationModel, map_est: MapEstimate) -> list[str]:
    """A second optimum close to the best that puts a run on the other side of c = c*."""
    if len(map_est.optima) < 2:
        return []
    m = run_margins_um(model, model.unpack(map_est.optima))
    out = []
    for k in range(1, len(map_est.optima)):
        gap = map_est.log_prob - float(map_est.optima_log_prob[k])
        flipped = [r for r, a, b in zip(model.data.runs.run_id, m[0], m[k], strict=True)
                   if np.sign(a) != np.sign(b)]
        if gap < BIMODAL_LOG_PROB and flipped:
            out.append(f"the posterior may be bimodal across c = c*: a local optimum "
                       f"{gap:.2g} below the best in log density puts run(s) "
                       f"{', '.join(flipped)} on the other side of the critical gap; the "
                       "walkers started at the best one, and an ensemble sampler does not "
                       "move mass between separated modes")
            break
    return out


def _fit_variant(model: CalibrationModel, config: CalibrationConfig, *, map_est: MapEstimate,
                 checkpoint: Path | None, fingerprint: str, progress: Progress | None,
                 operating_temperature_C: float) -> VariantFit:
    settings = SamplerSettings(walkers=config.walkers, max_steps=config.max_steps,
                               check_every=config.check_every, seed=config.seed,
                               map_starts=config.map_starts)
    walkers = settings.n_walkers(model.ndim)
    if walkers < 2 * model.ndim:
        raise CalibrationError(f"{walkers} walkers for {model.ndim} free parameters; emcee "
                               f"needs at least {2 * model.ndim}", key="calibration.walkers")
    run = run_sampler(model, model.priors, settings, checkpoint=checkpoint,
                      checkpoint_name=model.variant, fingerprint=fingerprint,
                      progress=progress, map_estimate=map_est)
    samples = run.samples()
    w, n, d = samples.shape
    flat = samples.reshape(-1, d)
    lp, ll, f = model.evaluate(flat)
    r = model.forward.n_runs
    jammed = (np.isnan(f) if config.jammed_model == "censored"
              else model.predict(flat).jammed)
    quantities = tuple(derived_quantities(model, samples,
                                          operating_temperature_C=operating_temperature_C))
    summaries = {q.name: summarize(q.draws, q.unit) for q in quantities}
    runs = run_summaries(model, samples, band_um=config.tolerances.unchanged_band_um)
    warns = _bimodality(model, map_est) + check_fit(model, run, summaries, config.tolerances)
    return VariantFit(
        variant=model.variant, model=model, run=run, samples=samples,
        log_prob=lp.reshape(w, n), log_likelihood=ll.reshape(w, n, r),
        f_pred_Hz=f.reshape(w, n, r), jammed=np.asarray(jammed).reshape(w, n, r),
        quantities=quantities, summaries=summaries, runs=runs, warnings=tuple(warns))


def _loo_data(fit: VariantFit) -> az.InferenceData:
    return az.from_dict(posterior={"lp": fit.log_prob},
                        log_likelihood={"f_n": fit.log_likelihood},
                        dims={"f_n": ["run"]}, coords={"run": list(fit.model.data.runs.run_id)})


def _variant_margins(fit: VariantFit) -> dict[str, Any]:
    out = {}
    for run_id, s in fit.runs.items():
        m = fit.summaries[f"margin@{run_id}"]
        out[run_id] = {"regime": s["regime"], "regime_probability": s["regime_probability"],
                       "margin_um": {k: m[k] for k in ("mean", "q05", "q95")}}
    return out


def _summary(config: CalibrationConfig, data: CalibrationData, fits: dict[str, VariantFit],
             headline: str, comparison: ModelComparison, reference: ThermalReference,
             operating_temperature_C: float, warnings: list[str],
             run_order: list[str]) -> dict[str, Any]:
    fit = fits[headline]
    model = fit.model
    names = set(model.names)
    runs: dict[str, Any] = {}
    for r in run_order:
        if r in fit.runs:
            runs[r] = fit.runs[r]
        elif r in data.left_out:
            runs[r] = {"regime": None, "regime_probability": None, "p_c_lt_cstar": None,
                       "mesh_mode_Hz": None, "mesh_mode_channel": None,
                       "mesh_mode_probability": None, "left_out": data.left_out[r]}
    chi = config.parameter("chi")
    comp = comparison.to_dict()
    for name, f in fits.items():
        comp["variants"][name]["converged"] = f.converged
        comp["variants"][name]["runs"] = _variant_margins(f)
    fwd = model.forward
    return {
        "schema_version": 1,
        "model_variant": headline,
        "converged": all(f.converged for f in fits.values()),
        "warnings": warnings,
        "parameters": {q.name: fit.summaries[q.name] for q in fit.quantities
                       if q.kind == "parameter" and q.name in names},
        "derived": {q.name: fit.summaries[q.name] for q in fit.quantities
                    if q.kind == "derived"},
        "runs": runs,
        "conventions": {
            "equivalent_mass_kg": fwd.equivalent_mass_kg,
            "equivalent_mass_basis": fwd.equivalent_mass_basis,
            "equivalent_mass_convention": EQUIVALENT_MASS_CONVENTION,
            "k_EP_N_per_m": fwd.k_mesh_N_per_m,
            "reference_temperature_C": reference.reference_temperature_C,
            "housing": reference.housing,
            "chi": chi.fixed,
            "chi_prior": None if chi.free is False or chi.prior is None else chi.prior.describe(),
            "thermal_model": config.thermal_model,
            "closure_per_unit_coefficient_um_per_K": fwd.closure.line_slope_m_per_K * 1e6,
            "model_variant": headline,
            "jammed_model": config.jammed_model,
            "likelihood": config.likelihood,
            "band_Hz": list(data.candidates.band_Hz),
            "detection_probability": config.detection_probability,
            "operating_temperature_C": operating_temperature_C,
            "unchanged_band_um": config.tolerances.unchanged_band_um,
        },
        "model_comparison": comp,
        "robustness": ROBUSTNESS,
        "sampler": {
            "walkers": int(fit.samples.shape[0]),
            "n_steps": fit.run.n_steps,
            "burn_in": fit.run.burn_in,
            "thin": fit.run.thin,
            "draws": int(fit.samples.shape[0] * fit.samples.shape[1]),
            "tau": {n: float(t) for n, t in zip(model.names, fit.run.tau, strict=True)},
            "acceptance_fraction": float(np.mean(fit.run.acceptance_fraction)),
            "converged": fit.converged,
            "resumed_from": fit.run.resumed_from,
            "notes": list(fit.run.notes),
            "seed": config.seed,
            "map": {n: float(x) for n, x in zip(model.names, fit.run.map_estimate.theta,
                                                strict=True)},
        },
        "data": {
            "runs_fitted": list(data.runs.run_id),
            "runs_left_out": dict(data.left_out),
            "candidates": int(data.candidates.mask.sum()),
            "notes": list(data.notes),
        },
        "config": config.to_dict(),
    }


def calibrate_observations(
    observations: pd.DataFrame,
    pair: GearPair | str,
    config: CalibrationConfig | None = None,
    *,
    thermal_reference: ThermalReference | None = None,
    outdir: str | Path | None = None,
    progress: Callable[[int, int, float | None], None] | None = None,
    seed: int | None = None,
) -> CalibrationResult:
    """Calibrate backlash, thermal closure and stiffness scale from a campaign's peaks.

    Parameters
    ----------
    observations : pandas.DataFrame
        The observations table (``data_schemas/observations.schema.json``).
    pair : GearPair or str
        The gear pair, or a shipped gear set's name.
    config : CalibrationConfig, optional
        The resolved ``[calibration]`` block (default: :func:`default_config`).
    thermal_reference : ThermalReference, optional
        The campaign's reference state (``[thermal]``).
    outdir : str or pathlib.Path, optional
        Where to write the outputs and the chains' checkpoint (a run killed and started
        again with the same arguments resumes from it).
    progress : callable, optional
        ``progress(step, max_steps, tau)`` after every convergence check, over all variants.
    seed : int, optional
        Overrides ``config.seed``.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    CalibrationError
        No usable run (each run's reason listed), priors that exclude the data or jam every
        run, too few walkers.
    """
    cfg = default_config() if config is None else config
    if seed is not None:
        cfg = replace(cfg, seed=int(seed))
    gear_pair = load_gear_set(pair).pair if isinstance(pair, str) else pair
    reference = resolve_reference(cfg, thermal_reference)
    data = prepare_data(observations, cfg)
    t_op = (float(np.max(data.runs.bulk_temperature_C)) if cfg.operating_temperature_C is None
            else cfg.operating_temperature_C)
    variants: list[Variant] = [cfg.model_variant]
    variants += [v for v in cfg.compare_variants if v != cfg.model_variant]
    out = None if outdir is None else Path(outdir)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    fits: dict[str, VariantFit] = {}
    warnings: list[str] = [f"run {r!r} left out: {why}" for r, why in data.left_out.items()]
    warnings += [n for n in data.notes if not n.startswith(INFORMATIVE_NOTES)]
    for i, variant in enumerate(variants):
        model = build_model(data, gear_pair, cfg, reference=reference, variant=variant)
        map_est = find_map(model, model.priors, starts=cfg.map_starts, seed=cfg.seed)
        if i == 0:
            _check_map_against_data(model, map_est)

        def step(s: int, m: int, tau: float | None, i: int = i) -> None:
            if progress is not None:
                progress(i * m + s, m * len(variants), tau)

        fit = _fit_variant(
            model, cfg, map_est=map_est,
            checkpoint=None if out is None else out / CHECKPOINT_FILE,
            fingerprint=_fingerprint(cfg, data, gear_pair, reference, variant),
            progress=step, operating_temperature_C=t_op)
        fits[variant] = fit
        prefix = "" if i == 0 else f"variant {variant}: "
        warnings += [prefix + w for w in fit.warnings if not w.startswith(INFORMATIVE_NOTES)
                     and (i == 0 or w.startswith(("not converged", "mean acceptance")))]
    comparison = compare_variants({v: _loo_data(f) for v, f in fits.items()})
    if len(fits) > 1:
        warnings.append(f"model comparison: {comparison.statement}")
    run_order = list(dict.fromkeys(str(r) for r in observations["run_id"]))
    summary = _summary(cfg, data, fits, cfg.model_variant, comparison, reference, t_op,
                       warnings, run_order)
    result = CalibrationResult(config=cfg, data=data, variant=cfg.model_variant, fits=fits,
                               comparison=comparison if len(fits) > 1 else None,
                               summary=summary, warnings=tuple(warnings))
    if out is not None:
        write_outputs(result, out)
    return result
