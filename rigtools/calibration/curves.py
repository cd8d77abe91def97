"""Posterior predictive curves on a grid of torques, for the figures and the report.

:func:`predictive_curves` evaluates the fitted forward model of a variant at ``n_draws``
posterior draws (evenly spaced) on a torque grid at each campaign temperature (the temperature
offsets, when sampled, are not applied: these are curves at the logged temperatures) and
returns quantiles: of the predicted mesh-mode frequency (the model, and a new measurement with
the model error), of the cycle-mean mesh stiffness, of the elastic ``s k_m``, of the critical
gap at each temperature and of the backlash; plus the share of draws jammed at each point and
the measured peaks (the chosen mesh mode of every run with its sd, and every candidate).
Plain arrays out; :mod:`rigtools.plots.calibration` draws them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rigtools.calibration.forward import ClosureBasis, predict
from rigtools.calibration.model import UM
from rigtools.calibration.result import VariantFit

__all__ = ["QUANTILES", "PredictiveCurves", "predictive_curves"]

#: Quantiles of every band (5 %, median, 95 %).
QUANTILES = (0.05, 0.5, 0.95)


@dataclass(frozen=True, eq=False)
class PredictiveCurves:
    """Quantiles of the posterior predictions on a grid (module notes).

    Attributes
    ----------
    variant : str
    torque_Nm : numpy.ndarray
        Grid, ``(T,)``.
    temperature_C : numpy.ndarray
        Campaign temperatures, ``(K,)``.
    f_n_Hz : numpy.ndarray
        Quantiles of the model's ``f_n``, ``(3, K, T)`` (over unjammed draws; NaN where all
        jammed).
    f_n_new_Hz : numpy.ndarray
        5 % and 95 % of a new measurement (model error and a typical fit sd), ``(2, K, T)``.
    k_mean_N_per_m : numpy.ndarray
        Quantiles of the cycle-mean mesh stiffness, ``(3, K, T)``.
    k_elastic_N_per_m : numpy.ndarray
        Quantiles of ``s k_m``, ``(3,)``.
    jammed_fraction : numpy.ndarray
        ``(K, T)``.
    critical_gap_um : numpy.ndarray
        Quantiles of ``c*`` at each temperature, ``(3, K)``.
    backlash_um : numpy.ndarray
        Quantiles of ``c``, ``(3,)``.
    run_torque_Nm, run_temperature_C : numpy.ndarray
        Fitted runs, ``(R,)``.
    run_f_n_Hz, run_f_n_std_Hz : numpy.ndarray
        The chosen mesh-mode peak of each run and its sd (NaN where none), ``(R,)``.
    run_ids : tuple of str
    candidate_torque_Nm, candidate_temperature_C, candidate_f_n_Hz : numpy.ndarray
        Every candidate peak, flattened.
    """

    variant: str
    torque_Nm: np.ndarray
    temperature_C: np.ndarray
    f_n_Hz: np.ndarray
    f_n_new_Hz: np.ndarray
    k_mean_N_per_m: np.ndarray
    k_elastic_N_per_m: np.ndarray
    jammed_fraction: np.ndarray
    critical_gap_um: np.ndarray
    backlash_um: np.ndarray
    run_torque_Nm: np.ndarray
    run_temperature_C: np.ndarray
    run_f_n_Hz: np.ndarray
    run_f_n_std_Hz: np.ndarray
    run_ids: tuple[str, ...]
    candidate_torque_Nm: np.ndarray
    candidate_temperature_C: np.ndarray
    candidate_f_n_Hz: np.ndarray


def _nanq(x: np.ndarray, q: tuple[float, ...]) -> np.ndarray:
    out = np.full((len(q), *x.shape[1:]), np.nan)
    ok = np.any(np.isfinite(x), axis=0)
    if ok.any():
        out[:, ok] = np.nanquantile(x[:, ok], q, axis=0)
    return out


def predictive_curves(fit: VariantFit, *, torque_Nm: ArrayLike | None = None,
                      n_draws: int = 400, seed: int = 0) -> PredictiveCurves:
    """Posterior predictive quantiles of a fitted variant on a torque grid.

    Parameters
    ----------
    fit : VariantFit
    torque_Nm : array_like, optional
        Grid (N m); default 60 points log-spaced from half the lowest to 1.2 times the highest
        campaign torque.
    n_draws : int
        Posterior draws used (evenly spaced over the kept ones).
    seed : int
        Seeds the noise of the new-measurement band.

    Returns
    -------
    PredictiveCurves
    """
    model = fit.model
    fm = model.forward
    runs = model.data.runs
    grid = (np.geomspace(0.5 * runs.torque_Nm.min(), 1.2 * runs.torque_Nm.max(), 60)
            if torque_Nm is None else np.asarray(torque_Nm, dtype=float))
    temps = np.unique(runs.bulk_temperature_C)
    flat = fit.samples.reshape(-1, fit.samples.shape[-1])
    pick = flat[np.unique(np.linspace(0, flat.shape[0] - 1, min(n_draws, flat.shape[0]))
                          .astype(int))]
    p = model.unpack(pick)
    cl = fm.closure
    t_all = np.tile(grid, temps.size)
    th_all = np.repeat(temps, grid.size)
    basis = ClosureBasis(cl.model, cl.reference_temperature_C, cl.at(th_all),
                         np.full(th_all.shape, cl.line_slope_m_per_K), cl.line_intercept_m,
                         cl.line_slope_m_per_K)
    g = fm.with_conditions(t_all, th_all, basis)
    pred = predict(g, p["backlash"] * UM, p["closure_coefficient"], p["stiffness_scale"],
                   p["chi"])
    shape = (pick.shape[0], temps.size, grid.size)
    f = pred.f_n_Hz.reshape(shape)
    k = pred.k_mean_N_per_m.reshape(shape)
    jam = pred.jammed.reshape(shape)
    cand = model.data.candidates
    typical_sd = float(np.median(cand.sd_Hz[cand.mask]))
    rng = np.random.default_rng([seed, 4])
    sd = np.sqrt(typical_sd**2 + (p["model_error"][:, None, None] * np.nan_to_num(f)) ** 2)
    f_new = f + sd * rng.standard_normal(f.shape)
    c_star = np.stack([(1.0 - p["chi"]) * p["closure_coefficient"] * float(cl.at(t)) / UM
                       for t in temps], axis=-1)
    chosen = np.array([np.nan if fit.runs[r]["mesh_mode_Hz"] is None
                       else fit.runs[r]["mesh_mode_Hz"] for r in runs.run_id])
    chosen_sd = np.full(chosen.shape, np.nan)
    for i in range(runs.n_runs):
        if np.isfinite(chosen[i]):
            j = int(np.argmin(np.abs(np.where(cand.mask[i], cand.f_Hz[i], np.inf) - chosen[i])))
            chosen_sd[i] = cand.sd_Hz[i, j]
    r_idx, j_idx = np.nonzero(cand.mask)
    return PredictiveCurves(
        variant=fit.variant, torque_Nm=grid, temperature_C=temps,
        f_n_Hz=_nanq(f, QUANTILES), f_n_new_Hz=_nanq(f_new, (0.05, 0.95)),
        k_mean_N_per_m=_nanq(k, QUANTILES),
        k_elastic_N_per_m=np.quantile(p["stiffness_scale"] * fm.k_mesh_N_per_m, QUANTILES),
        jammed_fraction=jam.mean(axis=0), critical_gap_um=np.quantile(c_star, QUANTILES, axis=0),
        backlash_um=np.quantile(p["backlash"], QUANTILES),
        run_torque_Nm=runs.torque_Nm.copy(), run_temperature_C=runs.bulk_temperature_C.copy(),
        run_f_n_Hz=chosen, run_f_n_std_Hz=chosen_sd, run_ids=runs.run_id,
        candidate_torque_Nm=runs.torque_Nm[r_idx],
        candidate_temperature_C=runs.bulk_temperature_C[r_idx],
        candidate_f_n_Hz=cand.f_Hz[r_idx, j_idx],
    )
