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
   differential evolution (:func:`~rigtools.calibration.runup_map.find_runup_map`) and emcee
   to the autocorrelation rule with :func:`~rigtools.calibration.sampler.run_sampler`, the
   positive parameters moved in log coordinates
   (:attr:`~rigtools.calibration.runup_model.RunUpPosterior.log_scale`), the proposals
   screened by a surrogate (delayed acceptance) and a fifth of the steps independence
   proposals from a mixture fitted to the chain, both exact and both switchable in
   ``[calibration.runup]`` (module notes 7 and 8 of :mod:`~rigtools.calibration.sampler`),
   resumable from
   ``<outdir>/runup/chains.h5`` (group ``runup-<model>``); :data:`RUNUP_WALKERS` walkers
   unless configured.
3. From at most :data:`~rigtools.calibration.runup_outputs.MAX_STORED_DRAWS` posterior draws:
   the gains drawn from their exact conditional, the leave-one-out log density per (run,
   point) with its channels together (they share the model error; the exact Gaussian
   conditional given the rest of the run, the model being non-factorised:
   :func:`~rigtools.calibration.runup_likelihood.pointwise_log_likelihood`) and per block
   (:func:`loo_blocks`), the posterior predictive Arms bands (the model error drawn along the
   run as it is modelled) and the jump frequencies.
4. Summary per model (:func:`~rigtools.calibration.runup_summary.runup_summary`): every
   parameter with its quantiles, ESS, R-hat and ``identified`` (posterior sd under the prior
   sd divided by ``[calibration.tolerances] min_narrowing``); a parameter the data do not
   identify has its mean and interval null, a statement and a warning: the prior is never
   reported as a result (the backlash: only through back-side impacts). Derived: the mesh
   natural frequency, overall and per run, with a warning for a run whose ramp does not
   reach it.
5. The models are compared by PSIS-LOO (:func:`~rigtools.calibration.comparison.
   compare_variants`: elpd differences with their standard errors, Pareto k). The se of a
   difference sums pointwise terms as if independent, and neighbouring points are not (a jump
   one point off moves two residuals); the same comparison leaving out blocks of
   :data:`BLOCK_POINTS` neighbouring points of one stretch (all channels, the block's exact
   left-out density) is reported beside it, and the statement gives both.

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
from typing import Final

import arviz as az
import numpy as np
import pandas as pd

from models.errors import ModelError
from models.geometry import GearPair, pair_equivalent_mass
from rigtools.calibration.campaign_inputs import (
    ObservationsInput,
    campaign_config,
    campaign_observations,
)
from rigtools.calibration.comparison import ModelComparison, compare_variants
from rigtools.calibration.config import CalibrationConfig
from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.runup_data import (
    RunUpData,
    direction_stretches,
    has_interior_maximum,
    prepare_runups,
)
from rigtools.calibration.runup_forward import (
    DIRECTIONS,
    RunUpForward,
    build_forward,
    jump_frequencies,
)
from rigtools.calibration.runup_likelihood import (
    gain_conditional,
    pointwise_log_likelihood,
    sample_model_error,
)
from rigtools.calibration.runup_map import SmoothedStart, find_runup_map
from rigtools.calibration.runup_model import RunUpPosterior, build_posterior
from rigtools.calibration.runup_outputs import (
    MAX_STORED_DRAWS,
    RUNUP_DIR,
    RunPredictive,
    RunUpFit,
    RunUpResult,
    write_runup_outputs,
)
from rigtools.calibration.runup_summary import runup_summary
from rigtools.calibration.sampler import Progress, SamplerRun, SamplerSettings, run_sampler
from rigtools.campaign.manifest import Campaign, load_campaign

__all__ = [
    "BLOCK_POINTS",
    "CHECKPOINT_FILE",
    "RUNUP_WALKERS",
    "calibrate_runup_data",
    "calibrate_runups",
    "loo_blocks",
    "runup_loo_data",
]

#: The chains' checkpoint file in ``<outdir>/runup/``.
CHECKPOINT_FILE: Final = "chains.h5"
#: Neighbouring points per block of the blocked PSIS-LOO check.
BLOCK_POINTS: Final = 10
#: Walkers of a run-up calibration unless ``[calibration.runup]`` or ``[calibration]`` sets
#: them (at least ``2 D + 2``, even). A step costs a sweep per walker, so the wall time to
#: the autocorrelation rule is linear in the walkers while ``tau`` in steps hardly falls
#: with more of them; with 16 the demo's VVMS run-up (6 parameters) converged in 2700 steps,
#: 570 s on 2 cores (issue 20, must-hold 4).
RUNUP_WALKERS: Final = 16


def _q(x: np.ndarray) -> dict[str, float] | None:
    v = np.asarray(x, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return None
    q = np.quantile(v, [0.05, 0.5, 0.95])
    return {"q05": float(q[0]), "q50": float(q[1]), "q95": float(q[2])}


def _q_bracket(b: np.ndarray) -> dict[str, float] | None:
    """Quantiles of a jump that the points place between two neighbours, ``(W, 2)`` (Hz).

    The median of the two neighbours' geometric mean; the 90 % interval from the 5 % quantile
    of the lower neighbours to the 95 % quantile of the upper ones (a jump is known only to
    lie between two points, and a zero-width interval would claim more).
    """
    v = np.asarray(b, dtype=float).reshape(-1, 2)
    v = v[np.isfinite(v).all(axis=1)]
    if not v.size:
        return None
    return {"q05": float(np.quantile(v[:, 0], 0.05)),
            "q50": float(np.quantile(np.sqrt(v[:, 0] * v[:, 1]), 0.5)),
            "q95": float(np.quantile(v[:, 1], 0.95))}


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
    walkers = ru.walkers if ru.walkers is not None else config.walkers
    if walkers is None:
        walkers = max(RUNUP_WALKERS, 2 * post.ndim + 2)
        walkers += walkers % 2
    settings = SamplerSettings(
        walkers=walkers,
        max_steps=ru.max_steps if ru.max_steps is not None else config.max_steps,
        check_every=config.check_every, seed=seed, map_starts=config.map_starts,
        delayed_acceptance=ru.delayed_acceptance, mixture_move=ru.mixture_move)
    walkers = settings.n_walkers(post.ndim)
    if walkers < 2 * post.ndim:
        raise CalibrationError(f"{walkers} walkers for {post.ndim} free parameters; emcee "
                               f"needs at least {2 * post.ndim}", key="calibration.runup.walkers")
    map_est = find_runup_map(post, post.priors, population=walkers, seed=seed,
                             smoothed=SmoothedStart(post.smoothed_start(), post.profile_errors))
    run = run_sampler(post, post.priors, settings, checkpoint=checkpoint,
                      checkpoint_name=f"runup-{post.kind}",
                      fingerprint=_fingerprint(config, fwd), progress=progress,
                      map_estimate=map_est, log_scale=post.log_scale)
    samples, lp = _draws(run)
    w, n, d = samples.shape
    m = w * n
    flat = samples.reshape(m, d)
    p = post.unpack(flat)
    tau, sigma = p["model_error"], p["channel_error"]
    sweeps = post.sweeps(flat)
    rng = np.random.default_rng([seed, 20, index])
    ll_parts, pred_parts, gains, labels = [], [], [], []
    o_run, o_chan, o_pt, l_run, l_pt = [], [], [], [], []
    predictive = []
    any_impact = np.zeros(m, dtype=bool)
    ell = p["model_error_length"]
    blk_parts = []
    for r, (curve, y, gaps, sw) in enumerate(zip(fwd.curves, post.log_observed, post.gaps,
                                                 sweeps, strict=True)):
        mean, cov = gain_conditional(y, sw.log_mu, tau, sigma, post.gain_prior,
                                     error_length=ell, gaps=gaps)
        chol = np.linalg.cholesky(cov)
        g = mean + np.einsum("mcd,md->mc", chol, rng.standard_normal(mean.shape))  # (M, C)
        gains.append(g)
        labels += [f"{curve.run_id}/{c}" for c in curve.channels]
        pw = pointwise_log_likelihood(y, sw.log_mu, tau, sigma, post.gain_prior,
                                      error_length=ell, gaps=gaps)
        seen = np.flatnonzero(np.isfinite(y).any(axis=0))
        ll_parts.append(pw[:, seen])
        l_run.append(np.full(seen.size, r))
        l_pt.append(seen)
        blocks = loo_blocks(curve.direction)
        pb = pointwise_log_likelihood(y, sw.log_mu, tau, sigma, post.gain_prior,
                                      error_length=ell, gaps=gaps, groups=blocks)
        blk_parts.append(pb[:, ~np.isnan(pb).all(axis=0)])
        cc, ii = np.nonzero(np.isfinite(y))
        noise = (sample_model_error(tau, ell, gaps, rng)[:, None, :]
                 + sigma[:, None, None] * rng.standard_normal((m, *y.shape)))
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
        jmod = jump_frequencies(sw.log_mu, curve.mesh_frequency_Hz, curve.direction,
                                brackets=True)
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
            jump_model_Hz={k: _q_bracket(jmod[k]) for k in DIRECTIONS},
            backside_impact_probability=float(impact.mean()),
            contact_loss_probability=float(sw.contact_loss.any(axis=1).mean())))
    log_lik = np.concatenate(ll_parts, axis=1).reshape(w, n, -1)
    block_lik = np.concatenate(blk_parts, axis=1).reshape(w, n, -1)
    arms_pred = np.concatenate(pred_parts, axis=1).reshape(w, n, -1)
    log_gain = np.concatenate(gains, axis=1).reshape(w, n, -1)
    fit_warn: list[str] = []
    summary = runup_summary(post, run, samples, log_gain, tuple(labels), predictive,
                            float(any_impact.mean()), config.tolerances, fit_warn)
    seconds = time.perf_counter() - t0
    summary["seconds"] = seconds
    return RunUpFit(
        model=post.kind, posterior=post, run=run, samples=samples, log_prob=lp,
        log_likelihood=log_lik, log_gain=log_gain, arms_predictive=arms_pred,
        obs_run=np.concatenate(o_run), obs_channel=np.concatenate(o_chan),
        obs_point=np.concatenate(o_pt), loo_run=np.concatenate(l_run),
        loo_point=np.concatenate(l_pt), block_log_likelihood=block_lik,
        gain_labels=tuple(labels),
        predictive=tuple(predictive), summary=summary, warnings=tuple(fit_warn),
        seconds=seconds)


def loo_blocks(direction: np.ndarray) -> np.ndarray:
    """Block label of each point: :data:`BLOCK_POINTS` neighbours of one stretch of one direction.

    Parameters
    ----------
    direction : numpy.ndarray
        ``(N,)`` in time order.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` labels ``0..B-1`` in time order.

    Examples
    --------
    >>> loo_blocks(np.array(["up"] * 12 + ["down"] * 3)).tolist()
    [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 2, 2, 2]
    """
    out = np.empty(len(direction), dtype=np.int64)
    first = 0
    for a, b in direction_stretches(np.asarray(direction, dtype=object)):
        out[a:b] = first + np.arange(b - a) // BLOCK_POINTS
        first = int(out[b - 1]) + 1
    return out


def runup_loo_data(fit: RunUpFit, *, blocked: bool = False) -> az.InferenceData:
    """What PSIS-LOO compares of a fit: its log posterior and pointwise log-likelihood.

    ``blocked``: the left-out densities of :func:`loo_blocks`' blocks instead of one per
    (run, point); for :func:`~rigtools.calibration.comparison.compare_variants` (module
    notes, step 5), also across fits of separate calls.
    """
    ll = fit.block_log_likelihood if blocked else fit.log_likelihood
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
    text = ("Pointwise PSIS-LOO (one term per run and point, its channels together): "
            f"{point.statement}")
    if block is not None:
        text += (f" Blocked check (blocks of {BLOCK_POINTS} neighbouring points of one run and "
                 "direction left out together, all channels; the se of a pointwise difference "
                 f"treats neighbours as independent and can be too small): {block.statement}")
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
    point = compare_variants({m: runup_loo_data(f) for m, f in fits.items()})
    block = (compare_variants({m: runup_loo_data(f, blocked=True) for m, f in fits.items()})
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
