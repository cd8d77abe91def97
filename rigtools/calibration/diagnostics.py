r"""Posterior summaries and the checks a result must pass before anyone trusts it.

:func:`summarize` gives every quantity ``mean, sd, q05, q50, q95`` and arviz's bulk effective
sample size and split R-hat, treating each emcee walker as a chain (walkers of an ensemble
are not independent, so these are optimistic; the autocorrelation-time rule of the sampler is
the primary convergence test). Draws that are not finite (a flip temperature that does not
exist) are left out of the mean and sd, kept as +-inf in the quantiles, and counted in
``finite_fraction``.

:func:`check_fit` turns the tolerances into warnings, each naming what failed:

* the chain did not converge (autocorrelation rule), an R-hat above ``max_r_hat``, a bulk ESS
  below ``min_ess_bulk``;
* a mean acceptance fraction outside ``acceptance_range``, or walkers that hardly move
  (acceptance below 0.05: stuck in a corner of the support);
* **identifiability**: a free parameter whose posterior sd is not at least ``min_narrowing``
  (default 2) times smaller than its prior's (the data barely inform it); the per-run
  temperature offsets are nuisance parameters and are not checked;
* **degeneracy** of the backlash and the thermal coefficient: all runs at one temperature
  (then only ``c - c*`` is identified, so ``c`` and ``kappa`` trade off along a line), or a
  posterior correlation of the two beyond 0.95.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Final

import arviz as az
import numpy as np

from rigtools.calibration.config import Tolerances
from rigtools.calibration.model import TEMPERATURE_OFFSET, CalibrationModel
from rigtools.calibration.sampler import SamplerRun

__all__ = ["DEGENERATE_CORRELATION", "STUCK_ACCEPTANCE", "check_fit", "sampler_warnings",
           "summarize"]

#: |corr(backlash, closure_coefficient)| above this is reported as a degeneracy.
DEGENERATE_CORRELATION: Final = 0.95
#: Walkers accepting less than this fraction of proposals are reported as stuck.
STUCK_ACCEPTANCE: Final = 0.05


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def summarize(draws: np.ndarray, unit: str) -> dict[str, Any]:
    """Summary of one quantity's draws ``(W, N)`` (module notes).

    Returns
    -------
    dict
        ``mean, sd, q05, q50, q95, ess_bulk, r_hat, unit`` (None where not finite) and
        ``finite_fraction`` when some draws are not finite.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> s = summarize(rng.normal(10.0, 2.0, (8, 500)), "um")
    >>> round(s["mean"]), round(s["sd"]), s["unit"], s["r_hat"] < 1.01
    (10, 2, 'um', True)
    """
    x = np.asarray(draws, dtype=float)
    finite = np.isfinite(x)
    frac = float(finite.mean())
    xf = x[finite]
    q = np.quantile(np.where(np.isnan(x), np.inf, x), [0.05, 0.5, 0.95],
                    method="inverted_cdf")
    if xf.size and np.ptp(xf) > 0:
        big = float(np.max(np.abs(xf))) * 10.0 + 1.0
        xr = np.where(finite, x, np.sign(np.nan_to_num(x, nan=1.0)) * big)
        ess = float(az.ess(xr, method="bulk"))
        rhat = float(az.rhat(xr))
    else:
        ess, rhat = math.nan, math.nan
    out: dict[str, Any] = {
        "mean": _num(float(xf.mean())) if xf.size else None,
        "sd": _num(float(xf.std(ddof=1))) if xf.size > 1 else None,
        "q05": _num(float(q[0])), "q50": _num(float(q[1])), "q95": _num(float(q[2])),
        "ess_bulk": _num(ess), "r_hat": _num(rhat), "unit": unit,
    }
    if frac < 1.0:
        out["finite_fraction"] = frac
    return out


def sampler_warnings(names: Sequence[str], run: SamplerRun, summaries: Mapping[str, Any],
                     tolerances: Tolerances) -> list[str]:
    """R-hat, bulk ESS, acceptance and stuck walkers of a run, against ``tolerances``.

    Parameters
    ----------
    names : sequence of str
        The sampled parameters.
    run : SamplerRun
    summaries : mapping
        Name -> :func:`summarize` output, for ``names`` at least.
    tolerances : Tolerances

    Returns
    -------
    list of str
        One warning per failed check; empty when everything passes.
    """
    w: list[str] = []
    for n in names:
        s = summaries[n]
        if s["r_hat"] is not None and s["r_hat"] > tolerances.max_r_hat:
            w.append(f"{n}: split-walker R-hat {s['r_hat']:.4f} above {tolerances.max_r_hat:g}")
        if s["ess_bulk"] is not None and s["ess_bulk"] < tolerances.min_ess_bulk:
            w.append(f"{n}: bulk ESS {s['ess_bulk']:.0f} below {tolerances.min_ess_bulk:g}")
    acc = float(np.mean(run.acceptance_fraction))
    lo, hi = tolerances.acceptance_range
    if not lo <= acc <= hi:
        w.append(f"mean acceptance fraction {acc:.3f} outside [{lo:g}, {hi:g}]")
    stuck = int(np.sum(run.acceptance_fraction < STUCK_ACCEPTANCE))
    if stuck:
        w.append(f"{stuck} walker(s) accepted under {STUCK_ACCEPTANCE:g} of their proposals")
    return w


def check_fit(model: CalibrationModel, run: SamplerRun, summaries: dict[str, dict[str, Any]],
              tolerances: Tolerances) -> list[str]:
    """Warnings for a fitted variant (module notes); empty when everything passes.

    Parameters
    ----------
    model : CalibrationModel
    run : SamplerRun
    summaries : dict
        Name -> :func:`summarize` output, for the parameters at least.
    tolerances : Tolerances

    Returns
    -------
    list of str
    """
    w: list[str] = list(run.notes)   # not converged, bimodality, checkpoint events
    w += sampler_warnings(model.names, run, summaries, tolerances)
    for n, prior in zip(model.names, model.priors, strict=True):
        if n.startswith(TEMPERATURE_OFFSET):   # nuisance: expected to follow its prior
            continue
        s = summaries[n]
        prior_sd = prior.moments()[1]
        if s["sd"] is not None and s["sd"] * tolerances.min_narrowing > prior_sd:
            w.append(f"{n}: the posterior (sd {s['sd']:.3g} {s['unit']}) is not "
                     f"{tolerances.min_narrowing:g} times narrower than its prior "
                     f"{prior.describe()} (sd {prior_sd:.3g}): the data barely inform it")
    temps = np.unique(model.forward.temperature_C)
    free = set(model.names)
    if {"backlash", "closure_coefficient"} <= free:
        if temps.size == 1:
            w.append(f"all runs at one bulk temperature ({temps[0]:g} degC): the backlash and "
                     "the closure coefficient are degenerate (only c - c* is identified); "
                     "add runs at another temperature (rigtools plan)")
        else:
            flat = run.samples().reshape(-1, model.ndim)
            i, j = model.names.index("backlash"), model.names.index("closure_coefficient")
            if np.std(flat[:, i]) > 0 and np.std(flat[:, j]) > 0:
                rho = float(np.corrcoef(flat[:, i], flat[:, j])[0, 1])
                if abs(rho) > DEGENERATE_CORRELATION:
                    w.append(f"backlash and closure_coefficient are degenerate (posterior "
                             f"correlation {rho:.3f}): the temperatures do not separate them")
    return w
