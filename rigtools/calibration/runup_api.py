r"""``calibrate_runups``: the SDOF models against a campaign's measured Arms run-up curves.

::

    from rigtools.calibration import calibrate_runups, write_runup_outputs

    result = calibrate_runups("campaign.toml", "observations.parquet", outdir="out/calibration")
    result.fits["vvms"].summary["derived"]["mesh_natural_frequency_Hz"]   # q05, q50, q95, ...
    result.statement                                   # which model the data support, by elpd
    write_runup_outputs(result, "out/calibration")     # out/calibration/runup/...

Steps (issue 20):

1. ``[calibration] models`` names the SDOF models (``fvms``, ``vvms``, ``lste``; empty: nothing
   to do, an empty result). The observations table's ``arms`` rows become one time-ordered
   curve per run (:func:`rigtools.calibration.runup_data.prepare_runups`, with the
   ``[calibration.runup]`` settings); runs it refuses (no usable speed, too few points, too
   small a span, gaps) go to :attr:`RunUpResult.refused` with a warning naming the run, and
   the rest goes on. Only when no run-up is usable at all is it a
   :class:`~rigtools.calibration.errors.CalibrationError`.
2. Per model: the cycle banks of every run's pair and torque
   (:mod:`~rigtools.calibration.runup_forward`), the log posterior with the gains
   marginalised (:mod:`~rigtools.calibration.runup_model`), the MAP by vectorised
   differential evolution (:func:`find_runup_map`) and emcee to the
   autocorrelation rule with the unchanged :func:`~rigtools.calibration.sampler.run_sampler`,
   resumable from ``<outdir>/runup/chains.h5`` (group ``runup-<model>``).
3. From at most :data:`~rigtools.calibration.runup_outputs.MAX_STORED_DRAWS` posterior draws:
   the gains drawn from their exact conditional, the pointwise log-likelihood per (run,
   channel, point), the posterior predictive Arms bands and the jump frequencies.
4. Summary per model: every parameter with mean, sd, 5/50/95 % quantiles, bulk ESS and
   split-walker R-hat, and ``identified`` (posterior sd under the prior sd divided by
   ``[calibration.tolerances] min_narrowing``, 2 by default). A parameter the data do not
   identify keeps its sd but has its mean and interval null, a statement and a warning: the
   prior is never reported as a result. The backlash in particular is identified only
   through back-side impacts: with a posterior probability of an impact anywhere (the sweep
   flags) under :data:`BACKSIDE_PROBABILITY` the summary says :data:`NO_BACKSIDE_STATEMENT`.
   Derived: ``mesh_natural_frequency_Hz = sqrt(s kbar_F0 / m_e) / 2 pi`` and, per run,
   ``mesh_natural_frequency_Hz@<run>`` with the model's own mean stiffness at ``T / s``. A run
   whose posterior natural frequency lies outside its measured mesh-frequency range did not
   reach the resonance: a warning naming it.
5. The models are compared by PSIS-LOO (:func:`~rigtools.calibration.comparison.
   compare_variants`: elpd differences with their standard errors, Pareto k). Neighbouring
   points of a curve are correlated (a jump one point off moves two residuals), which makes
   the pointwise se of the differences optimistic; the same comparison over blocks of
   :data:`BLOCK_POINTS` neighbouring points of one run and direction (all channels) is
   reported beside it, and the statement gives both.

Randomness: one integer ``seed`` (``[calibration] seed`` unless given) drives the MAP, the
walkers, the sampler, the gain draws and the predictive noise.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Final

import arviz as az
import numpy as np
import pandas as pd

from models.errors import ModelError
from models.geometry import EQUIVALENT_MASS_CONVENTION, GearPair, pair_equivalent_mass
from rigtools.calibration.campaign_inputs import (
    ObservationsInput,
    campaign_config,
    campaign_observations,
)
from rigtools.calibration.comparison import ModelComparison, compare_variants
from rigtools.calibration.config import RUNUP_PARAMETERS, CalibrationConfig, Tolerances
from rigtools.calibration.diagnostics import sampler_warnings, summarize
from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.priors import Prior
from rigtools.calibration.runup_data import RunUpData, has_interior_maximum, prepare_runups
from rigtools.calibration.runup_forward import (
    DIRECTIONS,
    RunUpForward,
    build_forward,
    jump_frequencies,
)
from rigtools.calibration.runup_likelihood import gain_conditional, pointwise_log_likelihood
from rigtools.calibration.runup_model import RunUpPosterior, build_posterior
from rigtools.calibration.runup_outputs import (
    MAX_STORED_DRAWS,
    RUNUP_DIR,
    RunPredictive,
    RunUpFit,
    RunUpResult,
    write_runup_outputs,
)
from rigtools.calibration.sampler import (
    MapEstimate,
    Progress,
    SamplerRun,
    SamplerSettings,
    run_sampler,
)
from rigtools.campaign.manifest import Campaign, load_campaign

__all__ = [
    "BACKSIDE_PROBABILITY",
    "BLOCK_POINTS",
    "CHECKPOINT_FILE",
    "MAP_GENERATIONS",
    "NO_BACKSIDE_STATEMENT",
    "calibrate_runup_data",
    "calibrate_runups",
    "find_runup_map",
]

#: The chains' checkpoint file in ``<outdir>/runup/``.
CHECKPOINT_FILE: Final = "chains.h5"
#: Below this posterior probability of a back-side impact the backlash is not identified.
BACKSIDE_PROBABILITY: Final = 0.05
#: What the summary says then.
NO_BACKSIDE_STATEMENT: Final = ("no back-side contact in any posterior draw: the run-up does "
                                "not identify the backlash")
#: Neighbouring points per block of the blocked PSIS-LOO check.
BLOCK_POINTS: Final = 10
_PRIOR_DRAWS: Final = 20000
#: Largest number of differential-evolution generations of :func:`find_runup_map`.
MAP_GENERATIONS: Final = 60


def _q(x: np.ndarray) -> dict[str, float] | None:
    v = np.asarray(x, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return None
    q = np.quantile(v, [0.05, 0.5, 0.95])
    return {"q05": float(q[0]), "q50": float(q[1]), "q95": float(q[2])}


def _fingerprint(config: CalibrationConfig, forward: RunUpForward) -> str:
    h = hashlib.sha256()
    h.update(json.dumps(config.to_dict(), sort_keys=True).encode())
    h.update(forward.kind.encode())
    h.update(str(forward.steps_per_period).encode())
    for c, b in zip(forward.curves, forward.banks, strict=True):
        h.update(c.run_id.encode() + b"\0" + c.gear_set.encode())
        h.update(repr((b.torque_Nm, b.equivalent_mass_kg, b.reference_stiffness_N_m)).encode())
        for a in (c.mesh_frequency_Hz, c.observed):
            h.update(np.ascontiguousarray(a, dtype=float).tobytes())
        h.update("\0".join(str(d) for d in c.direction).encode())
    return h.hexdigest()


def _fit_warnings(names: tuple[str, ...], run: SamplerRun, summaries: Mapping[str, Any],
                  tolerances: Tolerances) -> list[str]:
    """Convergence, R-hat, ESS and acceptance (as the natural-frequency calibration)."""
    notes = [n for n in run.notes if not n.startswith("walkers stranded")]
    return notes + sampler_warnings(names, run, summaries, tolerances)


def _not_identified(entry: dict[str, Any], statement: str) -> dict[str, Any]:
    """Null the result fields of a parameter the data do not identify, add the statement."""
    out = dict(entry)
    for k in ("mean", "q05", "q50", "q95"):
        out[k] = None
    out["identified"] = False
    out["statement"] = statement
    return out


def _conventions(forward: RunUpForward) -> dict[str, Any]:
    banks = {c.run_id: b for c, b in zip(forward.curves, forward.banks, strict=True)}
    first = forward.curves[0].run_id
    return {
        "k_ref": "k_ref = s kbar_F0: kbar_F0 is the mean of the error-free FVMS mesh stiffness "
                 "of the run's pair (load independent), s = mesh_stiffness_scale",
        "kbar_F0_N_per_m": {r: b.reference_stiffness_N_m for r, b in banks.items()},
        "m_e": "equivalent mass of the pair on the line of action, m_e = 1 / (r_b1^2/J_1 + "
               "r_b2^2/J_2), models.geometry.inertia (or the [calibration] override for "
               "runs on the campaign's gear set)",
        "equivalent_mass_kg": {r: b.equivalent_mass_kg for r, b in banks.items()},
        "equivalent_mass_convention": EQUIVALENT_MASS_CONVENTION,
        "mesh_natural_frequency_Hz": f"sqrt(k_ref / m_e) / 2 pi with run {first}'s pair",
        "mesh_natural_frequency_Hz@<run>": "sqrt(s k_model(T/s) / m_e) / 2 pi: the model's "
                                           "own mean stiffness at the run's torque",
        "zeta": "damping ratio relative to k_ref: c = 2 zeta sqrt(k_ref m_e)",
        "backlash": "total backlash 2b on the line of action (um)",
        "observation_model": "Arms_c = G_c (2 pi f_m)^2 sqrt(sum_h h^4 D_h^2), D_h the peak "
                             "DTE amplitude of mesh harmonic h (m), log-normal error sigma = "
                             "model_error, log G_c marginalised (prior: gain)",
        "stiffness_scale": "exact: the model with compliance C/s is the mesh cycle at T/s "
                           "with k_ref = s kbar_F0",
    }


def find_runup_map(log_prob: Callable[[np.ndarray], np.ndarray], priors: tuple[Prior, ...],
                   *, population: int, seed: int, generations: int = MAP_GENERATIONS,
                   keep: int = 4) -> MapEstimate:
    """MAP by differential evolution, every generation one vectorised call.

    :func:`rigtools.calibration.sampler.find_map` screens 2048 prior draws and runs
    Nelder-Mead one parameter vector at a time; with a model sweep per evaluation that costs
    more than the sampling (measured: 60-80 % of a VVMS fit), and prior draws with a small
    damping ratio settle slowly. Here ``4 population`` prior draws are screened in one call,
    the best ``population`` evolve by DE/rand/1/bin (``F = 0.7``, ``CR = 0.9``, greedy
    selection, candidates outside the support rejected) until the population's log posterior
    spreads less than 0.05 or ``generations`` pass. The best members that are distinct
    (more than 0.05 prior sd apart) are the optima.

    Parameters
    ----------
    log_prob : callable
        ``(W, D) -> (W,)``.
    priors : tuple of Prior
    population : int
        Members (the sampler's walkers: one generation costs one sampler step).
    seed : int
    generations : int
    keep : int
        Distinct optima reported.

    Returns
    -------
    MapEstimate
    """
    rng = np.random.default_rng([seed, 0])
    d = len(priors)
    lo = np.array([p.lower for p in priors])
    hi = np.array([p.upper for p in priors])
    sd = np.array([max(p.moments()[1], 1e-12) for p in priors])
    screen = np.column_stack([p.sample(rng, 4 * population) for p in priors])
    lp = log_prob(screen)
    order = np.argsort(-np.where(np.isfinite(lp), lp, -np.inf), kind="stable")[:population]
    pop, plp = screen[order].copy(), lp[order].copy()
    n = pop.shape[0]
    for _ in range(generations):
        if np.all(np.isfinite(plp)) and np.ptp(plp) < 0.05:
            break
        idx = np.array([rng.choice(n, 3, replace=False) for _ in range(n)])
        mutant = pop[idx[:, 0]] + 0.7 * (pop[idx[:, 1]] - pop[idx[:, 2]])
        cross = rng.random((n, d)) < 0.9
        cross[np.arange(n), rng.integers(0, d, n)] = True
        trial = np.where(cross, mutant, pop)
        inside = np.all((trial >= lo) & (trial <= hi), axis=1)
        tlp = np.full(n, -np.inf)
        if inside.any():
            tlp[inside] = log_prob(trial[inside])
        better = np.nan_to_num(tlp, nan=-np.inf) > np.nan_to_num(plp, nan=-np.inf)
        pop[better], plp[better] = trial[better], tlp[better]
    rank = np.argsort(-np.where(np.isfinite(plp), plp, -np.inf), kind="stable")
    optima: list[np.ndarray] = []
    values: list[float] = []
    for i in rank:
        if len(optima) >= keep:
            break
        if all(np.max(np.abs(pop[i] - o) / sd) > 0.05 for o in optima):
            optima.append(pop[i])
            values.append(float(plp[i]))
    return MapEstimate(theta=optima[0], log_prob=values[0], optima=np.array(optima),
                       optima_log_prob=np.array(values))


def _draws(run: SamplerRun) -> tuple[np.ndarray, np.ndarray]:
    """Kept draws and their log posterior, thinned to at most MAX_STORED_DRAWS."""
    samples, lp = run.samples(), run.sample_log_prob()
    w, n, _ = samples.shape
    k = max(1, math.ceil(w * n / MAX_STORED_DRAWS))
    return samples[:, ::k], lp[:, ::k]


def _fit_model(post: RunUpPosterior, config: CalibrationConfig, *, seed: int, index: int,
               checkpoint: Path | None, progress: Progress | None) -> RunUpFit:
    t0 = time.perf_counter()
    fwd = post.forward
    ru = config.runup
    settings = SamplerSettings(
        walkers=ru.walkers if ru.walkers is not None else config.walkers,
        max_steps=ru.max_steps if ru.max_steps is not None else config.max_steps,
        check_every=config.check_every, seed=seed, map_starts=config.map_starts)
    walkers = settings.n_walkers(post.ndim)
    if walkers < 2 * post.ndim:
        raise CalibrationError(f"{walkers} walkers for {post.ndim} free parameters; emcee "
                               f"needs at least {2 * post.ndim}", key="calibration.runup.walkers")
    map_est = find_runup_map(post, post.priors, population=walkers, seed=seed)
    run = run_sampler(post, post.priors, settings, checkpoint=checkpoint,
                      checkpoint_name=f"runup-{post.kind}",
                      fingerprint=_fingerprint(config, fwd), progress=progress,
                      map_estimate=map_est)
    samples, lp = _draws(run)
    w, n, d = samples.shape
    m = w * n
    flat = samples.reshape(m, d)
    p = post.unpack(flat)
    sigma = p["model_error"]
    sweeps = post.sweeps(flat)
    rng = np.random.default_rng([seed, 20, index])
    ll_parts, pred_parts, gains, labels = [], [], [], []
    o_run, o_chan, o_pt = [], [], []
    predictive = []
    any_impact = np.zeros(m, dtype=bool)
    for r, (curve, y, sw) in enumerate(zip(fwd.curves, post.log_observed, sweeps, strict=True)):
        mean, sd = gain_conditional(y, sw.log_mu, sigma, post.gain_prior)
        g = mean + sd * rng.standard_normal(mean.shape)                      # (M, C)
        gains.append(g)
        labels += [f"{curve.run_id}/{c}" for c in curve.channels]
        pw = pointwise_log_likelihood(y, sw.log_mu, sigma, g)                # (M, C, N)
        cc, ii = np.nonzero(np.isfinite(y))
        ll_parts.append(pw[:, cc, ii])
        noise = sigma[:, None, None] * rng.standard_normal((m, *y.shape))
        with np.errstate(over="ignore", invalid="ignore"):
            arms = np.exp(g[:, :, None] + sw.log_mu[:, None, :] + noise)    # (M, C, N)
        pred_parts.append(arms[:, cc, ii])
        o_run.append(np.full(cc.size, r))
        o_chan.append(cc)
        o_pt.append(ii)
        q = np.nanquantile(np.where(np.isfinite(arms), arms, np.nan), [0.05, 0.5, 0.95],
                           axis=0)
        jm = jump_frequencies(y, curve.mesh_frequency_Hz, curve.direction,
                              channels_first=True)
        jmod = jump_frequencies(sw.log_mu, curve.mesh_frequency_Hz, curve.direction)
        impact = sw.backside_impact.any(axis=1)
        any_impact |= impact
        predictive.append(RunPredictive(
            run_id=curve.run_id, gear_set=curve.gear_set, torque_Nm=float(curve.torque_Nm),
            channels=tuple(curve.channels),
            mesh_frequency_Hz=np.asarray(curve.mesh_frequency_Hz, dtype=float),
            direction=np.asarray(curve.direction), observed=np.asarray(curve.observed,
                                                                       dtype=float),
            arms_q05=q[0], arms_q50=q[1], arms_q95=q[2],
            jump_measured_Hz={k: (float(v) if np.isfinite(v) else None)
                              for k, v in jm.items()},
            jump_model_Hz={k: _q(jmod[k]) for k in DIRECTIONS},
            backside_impact_probability=float(impact.mean()),
            contact_loss_probability=float(sw.contact_loss.any(axis=1).mean())))
    log_lik = np.concatenate(ll_parts, axis=1).reshape(w, n, -1)
    arms_pred = np.concatenate(pred_parts, axis=1).reshape(w, n, -1)
    log_gain = np.concatenate(gains, axis=1).reshape(w, n, -1)
    fit_warn: list[str] = []
    summary = _summary(post, run, samples, log_gain, tuple(labels), predictive,
                       float(any_impact.mean()), config.tolerances, fit_warn)
    seconds = time.perf_counter() - t0
    summary["seconds"] = seconds
    return RunUpFit(
        model=post.kind, posterior=post, run=run, samples=samples, log_prob=lp,
        log_likelihood=log_lik, log_gain=log_gain, arms_predictive=arms_pred,
        obs_run=np.concatenate(o_run), obs_channel=np.concatenate(o_chan),
        obs_point=np.concatenate(o_pt), gain_labels=tuple(labels),
        predictive=tuple(predictive), summary=summary, warnings=tuple(fit_warn),
        seconds=seconds)


def _summary(post: RunUpPosterior, run: SamplerRun, samples: np.ndarray, log_gain: np.ndarray,
             labels: tuple[str, ...], predictive: list[RunPredictive], p_impact: float,
             tolerances: Tolerances, warnings_out: list[str]) -> dict[str, Any]:
    fwd = post.forward
    full = run.samples()            # ESS and R-hat from every kept draw
    summaries = {n: summarize(full[..., i], RUNUP_PARAMETERS[n].unit)
                 for i, n in enumerate(post.names)}
    warnings_out += _fit_warnings(post.names, run, summaries, tolerances)
    params: dict[str, Any] = {}
    identified: dict[str, bool] = {}
    for n, prior in zip(post.names, post.priors, strict=True):
        s = summaries[n]
        prior_sd = prior.moments()[1]
        ok = s["sd"] is not None and s["sd"] * tolerances.min_narrowing < prior_sd
        entry = dict(s, identified=bool(ok), prior=prior.describe(), prior_sd=prior_sd,
                     statement=None)
        if n == "backlash" and p_impact < BACKSIDE_PROBABILITY:
            ok = False
            entry = _not_identified(entry, f"{NO_BACKSIDE_STATEMENT} (posterior probability "
                                           f"of a back-side impact {p_impact:.3f})")
            warnings_out.append(f"backlash: {entry['statement']}; its prior "
                                f"{prior.describe()} um is not a result")
        elif not ok:
            entry = _not_identified(entry, (
                f"the data do not identify {n}: posterior sd {s['sd']:.3g} is not "
                f"{tolerances.min_narrowing:g} times under the prior's {prior_sd:.3g} "
                f"({prior.describe()}); the prior is not a result"))
            warnings_out.append(f"{n}: {entry['statement']}")
        identified[n] = bool(ok)
        params[n] = entry
    for n, v in post.fixed.items():
        params[n] = {"fixed": v, "unit": RUNUP_PARAMETERS[n].unit, "identified": None,
                     "statement": f"fixed at {v:g} ([calibration.runup.fixed])"}
    # derived natural frequencies; identified as the stiffness scale is
    s_draws = post.unpack(full)["mesh_stiffness_scale"]
    rng = np.random.default_rng(0)
    if "mesh_stiffness_scale" in post.names:
        prior_s = post.priors[post.names.index("mesh_stiffness_scale")].sample(rng, _PRIOR_DRAWS)
        lo, hi = fwd.scale_range
        prior_s = prior_s[(prior_s >= lo) & (prior_s <= hi)]
    else:
        prior_s = np.full(2, float(post.fixed["mesh_stiffness_scale"]))
    derived: dict[str, Any] = {}
    fn = summarize(fwd.natural_frequency_Hz(s_draws), "Hz")
    fn_prior_sd = float(np.std(fwd.natural_frequency_Hz(prior_s)))
    s_ok = identified.get("mesh_stiffness_scale", True)
    fn_ok = s_ok and fn["sd"] is not None and (
        fn["sd"] * tolerances.min_narrowing < fn_prior_sd or fn_prior_sd == 0.0)
    derived["mesh_natural_frequency_Hz"] = dict(fn, identified=bool(fn_ok),
                                                prior_sd=fn_prior_sd)
    if not fn_ok:
        derived["mesh_natural_frequency_Hz"] = _not_identified(
            derived["mesh_natural_frequency_Hz"],
            "the data do not identify the mesh natural frequency (the stiffness scale)")
    model_fn = fwd.model_natural_frequency_Hz(s_draws)            # (R, W, n)
    for r, curve in enumerate(fwd.curves):
        e = summarize(model_fn[r], "Hz")
        e = dict(e, identified=bool(fn_ok))
        name = f"mesh_natural_frequency_Hz@{curve.run_id}"
        derived[name] = e if fn_ok else _not_identified(e, "not identified (see "
                                                           "mesh_natural_frequency_Hz)")
        f_obs = np.asarray(curve.mesh_frequency_Hz)[np.isfinite(curve.observed).any(axis=0)]
        med = e["q50"]
        if fn_ok and med is not None and f_obs.size and not (
                float(f_obs.min()) <= med <= float(f_obs.max())):
            warnings_out.append(
                f"run {curve.run_id}: the posterior mesh natural frequency ({med:.0f} Hz) lies "
                f"outside the measured mesh frequencies [{f_obs.min():.0f}, "
                f"{f_obs.max():.0f}] Hz: the ramp does not reach the resonance, the fit "
                "rests on the flank of the curve")
    gains = {lab: summarize(np.exp(log_gain[..., j]), "1") for j, lab in enumerate(labels)}
    acc = float(np.mean(run.acceptance_fraction))
    me = run.map_estimate
    return {
        "schema_version": 1,
        "model": fwd.kind,
        "converged": bool(run.converged),
        "parameters": params,
        "identified": identified,
        "derived": derived,
        "gains": gains,
        "backlash": {
            "backside_impact_probability": p_impact,
            "identified": identified.get("backlash"),
            "statement": (params["backlash"].get("statement")
                          if "backlash" in params else None),
        },
        "runs": {p.run_id: p.to_dict() for p in predictive},
        "conventions": _conventions(fwd),
        "sampler": {
            "walkers": int(run.chain.shape[1]), "n_steps": run.n_steps,
            "burn_in": run.burn_in, "thin": run.thin,
            "tau": [float(t) if math.isfinite(t) else None for t in run.tau],
            "acceptance_fraction": acc,
            "log_prob_evaluations": run.log_prob_evaluations,
            "seconds_sampling": run.seconds_sampling, "resumed_from": run.resumed_from,
            "draws_stored": int(samples.shape[0] * samples.shape[1]),
            "map": {"theta": {n: float(v) for n, v in zip(post.names, me.theta, strict=True)},
                    "log_prob": float(me.log_prob)},
            "notes": list(run.notes),
        },
        "warnings": list(warnings_out),
        "notes": list(post.notes),
    }


def _loo_data(fit: RunUpFit, *, blocked: bool) -> az.InferenceData:
    ll = fit.log_likelihood
    if blocked:
        curves = fit.posterior.forward.curves
        keys = []
        for r, i in zip(fit.obs_run, fit.obs_point, strict=True):
            d = np.asarray(curves[r].direction)
            same = np.flatnonzero(d == d[i])
            keys.append((int(r), str(d[i]), int(np.searchsorted(same, i)) // BLOCK_POINTS))
        uniq = sorted(set(keys))
        idx = np.array([uniq.index(k) for k in keys])
        ll = np.stack([ll[..., idx == b].sum(axis=-1) for b in range(len(uniq))], axis=-1)
    with warnings.catch_warnings():
        # "more chains than draws": emcee has many walkers and few thinned draws each
        warnings.filterwarnings("ignore", message="More chains")
        return az.from_dict(posterior={"lp": fit.log_prob}, log_likelihood={"arms": ll},
                            dims={"arms": ["obs"]}, coords={"obs": list(range(ll.shape[-1]))})


def _statement(fits: Mapping[str, RunUpFit], point: ModelComparison | None,
               block: ModelComparison | None) -> str:
    if point is None:
        return "no model fitted."
    if len(fits) < 2:
        return f"only {next(iter(fits))} fitted; nothing to compare."
    text = f"Pointwise PSIS-LOO (one observation per run, channel and point): {point.statement}"
    if block is not None:
        text += (f" Blocked check (blocks of {BLOCK_POINTS} neighbouring points of one run and "
                 "direction, all channels; pointwise LOO treats correlated neighbours as "
                 f"independent, so its se can be too small): {block.statement}")
        if point.favoured is not None and block.favoured != point.favoured:
            text += (" The blocked check does not confirm the pointwise preference: read the "
                     "difference as suggestive only.")
    return text


def calibrate_runup_data(
    data: RunUpData,
    pairs: Mapping[str, GearPair],
    config: CalibrationConfig,
    *,
    masses_kg: Mapping[str, float | None] | None = None,
    outdir: str | Path | None = None,
    progress: Callable[[int, int, float | None], None] | None = None,
    seed: int | None = None,
    write: bool = True,
) -> RunUpResult:
    """Calibrate ``config.models`` against prepared run-up curves (module notes, steps 2-5).

    Parameters
    ----------
    data : RunUpData
        :func:`~rigtools.calibration.runup_data.prepare_runups`'s result.
    pairs : mapping
        Run id -> the run's gear pair.
    config : CalibrationConfig
    masses_kg : mapping, optional
        Run id -> ``m_e`` (kg); a missing run or None: the package's convention.
    outdir : str or pathlib.Path, optional
        The calibration directory: the checkpoint is ``<outdir>/runup/chains.h5`` and, with
        ``write``, the files of :func:`~rigtools.calibration.runup_outputs.write_runup_outputs`.
    progress : callable, optional
        ``progress(step, max_steps, tau)`` over all models.
    seed : int, optional
        Default ``config.seed``.
    write : bool
        Write the output files when ``outdir`` is given.

    Returns
    -------
    RunUpResult

    Raises
    ------
    CalibrationError
        ``config.models`` is not empty and no run-up is usable (the refusals named), or no
        model could be fitted.
    """
    seed = config.seed if seed is None else int(seed)
    refused = dict(data.refused)
    warns = [f"run {r}: {msg}" for r, msg in refused.items()]
    notes = list(data.notes)
    if not config.models:
        return RunUpResult(models=(), fits={}, comparison=None, blocked_comparison=None,
                           statement="no SDOF models configured ([calibration] models = [])",
                           runs=(), refused=refused, warnings=tuple(warns),
                           notes=tuple(notes), config=config.to_dict(), seed=seed)
    curves = tuple(data.curves)
    for c in curves:
        if not has_interior_maximum(c):
            warns.append(f"run {c.run_id}: Arms / f_m^2 has no interior maximum: the ramp "
                         "may not reach the mesh resonance (the fit then rests on the flank)")
    if not curves:
        why = "; ".join(f"{r}: {m}" for r, m in refused.items()) or "no run-up rows"
        raise CalibrationError(f"no usable run-up for the SDOF calibration ({why})",
                               key="calibration.models")
    out = None if outdir is None else Path(outdir)
    checkpoint = None
    if out is not None:
        (out / RUNUP_DIR).mkdir(parents=True, exist_ok=True)
        checkpoint = out / RUNUP_DIR / CHECKPOINT_FILE
    masses = dict(masses_kg or {})
    fits: dict[str, RunUpFit] = {}
    n_models = len(config.models)
    for i, kind in enumerate(config.models):
        def step(s: int, mx: int, tau: float | None, i: int = i) -> None:
            if progress is not None:
                progress(i * mx + s, mx * n_models, tau)

        try:
            fwd = build_forward(kind, curves, pairs, masses,
                                steps_per_period=config.runup.steps_per_period)
        except (ModelError, ValueError) as exc:   # a pair the mesh-cycle model cannot take
            warns.append(f"{kind}: not fitted, its mesh cycles could not be built ({exc})")
            continue
        post = build_posterior(fwd, config.runup)
        fit = _fit_model(post, config, seed=seed, index=i, checkpoint=checkpoint,
                         progress=step)
        if not math.isfinite(fit.run.map_estimate.log_prob):
            warns.append(f"{kind}: not fitted, no parameter set the priors allow gives a "
                         "finite likelihood (every model sweep failed at an observed point)")
            continue
        fits[kind] = fit
        warns += [f"{kind}: {w}" for w in fit.warnings]
    if not fits:
        raise CalibrationError("no SDOF model could be fitted: " + "; ".join(warns),
                               key="calibration.models")
    point = compare_variants({m: _loo_data(f, blocked=False) for m, f in fits.items()})
    block = (compare_variants({m: _loo_data(f, blocked=True) for m, f in fits.items()})
             if len(fits) > 1 else None)
    result = RunUpResult(
        models=tuple(fits), fits=fits, comparison=point, blocked_comparison=block,
        statement=_statement(fits, point, block), runs=tuple(c.run_id for c in curves),
        refused=refused, warnings=tuple(warns), notes=tuple(notes), config=config.to_dict(),
        seed=seed)
    if out is not None and write:
        write_runup_outputs(result, out)
    return result


def _masses(camp: Campaign, config: CalibrationConfig,
            runs: list[str]) -> dict[str, float | None]:
    """``m_e`` per run: the ``[calibration]`` override on the campaign's gear set."""
    out: dict[str, float | None] = {}
    for r in runs:
        pair = camp.gear_for(r).pair
        if camp.on_campaign_gear(r) and config.equivalent_mass_kg is not None:
            out[r] = config.equivalent_mass_kg
        elif camp.on_campaign_gear(r):
            out[r] = pair_equivalent_mass(pair, inertia_kg_m2=config.inertia_kg_m2,
                                          disc_radius=config.disc_radius)
        else:
            out[r] = pair_equivalent_mass(pair, disc_radius=config.disc_radius)
    return out


def calibrate_runups(
    campaign: Campaign | str | Path,
    observations: ObservationsInput | pd.DataFrame = None,
    *,
    config: CalibrationConfig | None = None,
    outdir: str | Path | None = None,
    progress: Callable[[int, int, float | None], None] | None = None,
    seed: int | None = None,
) -> RunUpResult:
    """Calibrate the campaign's SDOF models against its Arms run-ups (module notes).

    Parameters
    ----------
    campaign : Campaign, str or pathlib.Path
        The loaded campaign or its manifest; each run's gear set is its ``[[run]]
        gear_set`` (else the campaign's).
    observations : DataFrame, Observations, str, pathlib.Path or None
        As :func:`rigtools.calibration.campaign_observations` (None: observe first).
    config : CalibrationConfig, optional
        Instead of the campaign's ``[calibration]`` block.
    outdir : str or pathlib.Path, optional
        The calibration directory (``OUTDIR/calibration``): checkpoint and files go to
        ``<outdir>/runup/``.
    progress : callable, optional
        ``progress(step, max_steps, tau)``.
    seed : int, optional

    Returns
    -------
    RunUpResult
        Empty (no models) when ``[calibration] models`` is empty. Refused runs are in
        ``refused`` and the warnings, never raised.

    Raises
    ------
    CampaignError
        The ``[calibration]`` block is wrong (file and line).
    CalibrationError
        ``models`` is not empty and no run-up is usable.
    """
    camp = campaign if isinstance(campaign, Campaign) else load_campaign(campaign)
    cfg = campaign_config(camp) if config is None else config
    if not cfg.models:
        return calibrate_runup_data(RunUpData(curves=(), refused={}, notes=()), {}, cfg,
                                    outdir=None, seed=seed)
    table = campaign_observations(camp, observations)
    data = prepare_runups(table, camp, cfg.runup)
    runs = [c.run_id for c in data.curves]
    pairs = {r: camp.gear_for(r).pair for r in runs}
    return calibrate_runup_data(data, pairs, cfg, masses_kg=_masses(camp, cfg, runs),
                                outdir=outdir, progress=progress, seed=seed)
