r"""The summary of a run-up model fit: parameters, identifiability, derived frequencies.

Per model, every parameter with mean, sd, 5/50/95 % quantiles, bulk ESS and split-walker R-hat,
and ``identified`` (posterior sd under the prior sd divided by ``[calibration.tolerances]
min_narrowing``, 2 by default). A parameter the data do not identify keeps its sd but has its
mean and interval null, a statement and a warning: the prior is never reported as a result.
The backlash in particular is identified only through back-side impacts: with a posterior
probability of an impact anywhere (the sweep flags) under :data:`BACKSIDE_PROBABILITY` the
summary says :data:`NO_BACKSIDE_STATEMENT`. Derived: ``mesh_natural_frequency_Hz = sqrt(s
kbar_F0 / m_e) / 2 pi`` and, per run, ``mesh_natural_frequency_Hz@<run>`` with the model's own
mean stiffness at ``T / s``. A run whose posterior natural frequency lies outside its measured
mesh-frequency range did not reach the resonance: a warning naming it. The conventions
(``k_ref``, ``m_e``, the observation model) are written beside the numbers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

import numpy as np

from models.geometry import EQUIVALENT_MASS_CONVENTION
from rigtools.calibration.config import Tolerances
from rigtools.calibration.diagnostics import sampler_warnings, summarize
from rigtools.calibration.runup_config import RUNUP_PARAMETERS
from rigtools.calibration.runup_forward import RunUpForward
from rigtools.calibration.runup_model import RunUpPosterior
from rigtools.calibration.runup_outputs import RunPredictive
from rigtools.calibration.sampler import SamplerRun

__all__ = ["BACKSIDE_PROBABILITY", "NO_BACKSIDE_STATEMENT", "runup_summary"]

#: Below this posterior probability of a back-side impact the backlash is not identified.
BACKSIDE_PROBABILITY: Final = 0.05
#: What the summary says then.
NO_BACKSIDE_STATEMENT: Final = ("no back-side contact in any posterior draw: the run-up does "
                                "not identify the backlash")
_PRIOR_DRAWS: Final = 20000
#: Notes of :func:`~rigtools.calibration.sampler.run_sampler` that are not warnings.
_SAMPLER_NOTES: Final = ("walkers stranded", "delayed acceptance:", "mixture move:")


def _fit_warnings(names: tuple[str, ...], run: SamplerRun, summaries: Mapping[str, Any],
                  tolerances: Tolerances) -> list[str]:
    """Convergence, R-hat, ESS and acceptance (as the natural-frequency calibration)."""
    # the sampler's account of itself, in summary.json's notes, not a warning
    notes = [n for n in run.notes if not n.startswith(_SAMPLER_NOTES)]
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
                             "DTE amplitude of mesh harmonic h (m), power-averaged over the "
                             "window's nodes (Hann^2 weights); log Arms error = a term shared "
                             "by the channels at a point (sd model_error; correlated "
                             "exp(-|d ln f_m| / model_error_length) between neighbouring "
                             "points of one direction) + each channel's own (sd "
                             "channel_error); log G_c marginalised (prior: gain)",
        "stiffness_scale": "exact: the model with compliance C/s is the mesh cycle at T/s "
                           "with k_ref = s kbar_F0",
    }


def runup_summary(post: RunUpPosterior, run: SamplerRun, samples: np.ndarray,
                  log_gain: np.ndarray, labels: tuple[str, ...],
                  predictive: list[RunPredictive], p_impact: float, tolerances: Tolerances,
                  warnings_out: list[str]) -> dict[str, Any]:
    """The ``summary.json`` of one run-up model fit (module notes).

    Parameters
    ----------
    post : RunUpPosterior
        The model's log posterior (names, priors, fixed values, forward model).
    run : SamplerRun
        The sampler's run: ESS and R-hat come from every kept draw.
    samples : numpy.ndarray
        The stored draws, ``(walkers, draws, ndim)`` (their count is recorded).
    log_gain : numpy.ndarray
        Log channel gains drawn with them, ``(walkers, draws, len(labels))``.
    labels : tuple of str
        ``<run>/<channel>`` of each gain.
    predictive : list of RunPredictive
        The posterior predictive of every run.
    p_impact : float
        Posterior probability of a back-side impact anywhere.
    tolerances : Tolerances
        ``min_narrowing`` decides identifiability; the sampler checks use the rest.
    warnings_out : list of str
        The warnings are appended to it.

    Returns
    -------
    dict
        JSON-ready: ``parameters``, ``identified``, ``derived``, ``gains``, ``backlash``,
        ``runs``, ``conventions``, ``sampler``, ``warnings``, ``notes``.
    """
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
