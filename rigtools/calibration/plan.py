r"""Which run to add next: the condition that most narrows the margin at the operating point.

The target is the margin at the operating temperature, ``m = c - c*(theta_op)`` (the
quantity that decides the regime there). For every candidate run ``x = (T, theta)`` on a grid
over the ranges the campaign allows, a Fisher (Laplace) approximation predicts the posterior
standard deviation of ``m`` after adding ``x``:

.. math::

    \Sigma_x = \left(\Sigma^{-1} + p_x \, \mathbb{E}_d\!\left[\frac{J_d J_d^T}{\sigma_d^2}
               \right]\right)^{-1}, \qquad
    \mathrm{sd}_x(m) = \sqrt{g^T \Sigma_x g},

with ``Sigma`` the posterior covariance of the sampled global parameters (from the draws),
``J_d = d f_n(x) / d theta`` at posterior draw ``d`` (central differences), ``sigma_d^2 =
sd_fit^2 + (sigma_rel f_n)^2`` the predicted measurement variance (``sd_fit`` the campaign's
median relative fit sd times ``f_n``), ``p_x`` the probability that the mesh mode is seen at
``x`` (jammed or out-of-band draws contribute nothing), ``E_d`` the average over draws and
``g = d m / d theta``. ``(Sigma^{-1} + I)^{-1}`` is evaluated as
``Sigma^{1/2} (1 + Sigma^{1/2} I Sigma^{1/2})^{-1} Sigma^{1/2}``, which stays finite when the
posterior is degenerate (all runs at one temperature, where ``c`` and ``kappa`` trade off).

Ranges: ``plan_torque_range_Nm`` and ``plan_temperature_range_C`` of the ``[calibration]``
block, by default the campaign's torque range and its temperature range extended to the
operating temperature. A campaign run at one temperature cannot tell the backlash from the
thermal closure, so the margin at another (operating) temperature is uncertain, and the plan
proposes a run at a temperature the campaign lacks (``tests/calibration/test_plan.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigtools.calibration.forward import ClosureBasis, mesh_frequency
from rigtools.calibration.likelihood import detection_probability
from rigtools.calibration.model import TEMPERATURE_OFFSET, UM
from rigtools.calibration.result import CalibrationResult

__all__ = ["RunPlan", "plan_next_runs"]


@dataclass(frozen=True, eq=False)
class RunPlan:
    """Candidate runs ranked by the predicted posterior sd of the operating margin.

    Attributes
    ----------
    operating_temperature_C : float
    current_sd_um : float
        Posterior sd of the margin at the operating temperature now (Laplace, um).
    torque_Nm, temperature_C : numpy.ndarray
        Candidate conditions, best first, ``(n,)``.
    predicted_sd_um : numpy.ndarray
        Predicted sd of the margin after adding each (um).
    predicted_f_n_Hz : numpy.ndarray
        Posterior median of the mesh-mode frequency there (Hz; NaN when mostly jammed).
    detection_probability : numpy.ndarray
        Probability that the mesh mode is seen there.
    """

    operating_temperature_C: float
    current_sd_um: float
    torque_Nm: np.ndarray
    temperature_C: np.ndarray
    predicted_sd_um: np.ndarray
    predicted_f_n_Hz: np.ndarray
    detection_probability: np.ndarray

    def best(self, n: int = 3) -> list[dict[str, float]]:
        """The ``n`` best candidates as dicts (JSON-ready)."""
        return [{"torque_Nm": float(self.torque_Nm[i]),
                 "temperature_C": float(self.temperature_C[i]),
                 "predicted_sd_um": float(self.predicted_sd_um[i]),
                 "predicted_f_n_Hz": float(self.predicted_f_n_Hz[i]),
                 "detection_probability": float(self.detection_probability[i])}
                for i in range(min(n, self.torque_Nm.size))]


def _sqrtm(a: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(0.5 * (a + a.T))
    return (v * np.sqrt(np.clip(w, 0.0, None))) @ v.T


def plan_next_runs(
    result: CalibrationResult,
    *,
    torque_range_Nm: tuple[float, float] | None = None,
    temperature_range_C: tuple[float, float] | None = None,
    operating_temperature_C: float | None = None,
    n_torque: int = 9,
    n_temperature: int = 7,
    n_draws: int = 200,
) -> RunPlan:
    """Rank candidate runs by the predicted sd of the margin at the operating temperature.

    Parameters
    ----------
    result : CalibrationResult
        The headline fit is used.
    torque_range_Nm, temperature_range_C : (float, float), optional
        Ranges the campaign allows (module notes for the defaults).
    operating_temperature_C : float, optional
        Default: the result's operating temperature.
    n_torque, n_temperature : int
        Grid points (torques log-spaced).
    n_draws : int
        Posterior draws for the expected information.

    Returns
    -------
    RunPlan
    """
    fit = result.headline
    model = fit.model
    fm = model.forward
    runs = model.data.runs
    conv = result.summary["conventions"]
    t_op = float(conv["operating_temperature_C"] if operating_temperature_C is None
                 else operating_temperature_C)
    cfg = result.config
    tr = torque_range_Nm or cfg.plan_torque_range_Nm or (
        float(runs.torque_Nm.min()), float(runs.torque_Nm.max()))
    th = temperature_range_C or cfg.plan_temperature_range_C or (
        float(min(runs.bulk_temperature_C.min(), t_op)),
        float(max(runs.bulk_temperature_C.max(), t_op)))
    torques = np.geomspace(tr[0], tr[1], n_torque) if tr[1] > tr[0] else np.array([tr[0]])
    temps = np.linspace(th[0], th[1], n_temperature) if th[1] > th[0] else np.array([th[0]])
    cand_t = np.tile(torques, temps.size)
    cand_th = np.repeat(temps, torques.size)
    glob = [i for i, n in enumerate(model.names) if not n.startswith(TEMPERATURE_OFFSET)]
    flat = fit.samples.reshape(-1, fit.samples.shape[-1])
    sigma = np.cov(flat[:, glob].T).reshape(len(glob), len(glob))
    pick = flat[np.linspace(0, flat.shape[0] - 1, min(n_draws, flat.shape[0])).astype(int)]
    cl = fm.closure
    basis = ClosureBasis(cl.model, cl.reference_temperature_C, cl.at(cand_th),
                         np.full(cand_th.shape, cl.line_slope_m_per_K), cl.line_intercept_m,
                         cl.line_slope_m_per_K)
    grid = fm.with_conditions(cand_t, cand_th, basis)

    def freq(theta: np.ndarray) -> np.ndarray:
        p = model.unpack(theta)
        return mesh_frequency(grid, p["backlash"] * UM, p["closure_coefficient"],
                              p["stiffness_scale"], p["chi"])

    def margin(theta: np.ndarray) -> np.ndarray:
        p = model.unpack(theta)
        return p["backlash"] - (1.0 - p["chi"]) * p["closure_coefficient"] * float(
            cl.at(t_op)) / UM

    f0 = freq(pick)                                            # (N, C)
    sd_scale = [np.std(flat[:, i]) for i in glob]
    jac = np.zeros((*f0.shape, len(glob)))
    g = np.zeros(len(glob))
    for k, (i, scale) in enumerate(zip(glob, sd_scale, strict=True)):
        h = 1e-3 * max(scale, 1e-12)
        up, dn = pick.copy(), pick.copy()
        up[:, i] += h
        dn[:, i] -= h
        with np.errstate(invalid="ignore"):
            jac[..., k] = (freq(up) - freq(dn)) / (2.0 * h)
        g[k] = float(np.mean(margin(up) - margin(dn)) / (2.0 * h))
    cand = model.data.candidates
    rel_sd = float(np.median(cand.sd_Hz[cand.mask] / cand.f_Hz[cand.mask]))
    me = model.unpack(pick)["model_error"][:, None]
    var = (rel_sd * f0) ** 2 + (me * f0) ** 2
    p_seen = detection_probability(f0, model.settings)         # 0 where jammed (NaN)
    ok = np.isfinite(f0) & np.all(np.isfinite(jac), axis=-1)
    w = np.where(ok, p_seen / np.where(ok, var, 1.0), 0.0)
    jz = np.where(ok[..., None], jac, 0.0)
    info = np.einsum("nc,nci,ncj->cij", w, jz, jz) / pick.shape[0]      # (C, D, D)
    root = _sqrtm(sigma)
    eye = np.eye(len(glob))
    pred_var = np.empty(cand_t.size)
    for c in range(cand_t.size):
        inner = np.linalg.solve(eye + root @ info[c] @ root, eye)
        cov = root @ inner @ root
        pred_var[c] = float(g @ cov @ g)
    current = float(np.sqrt(max(float(g @ sigma @ g), 0.0)))
    order = np.argsort(pred_var, kind="stable")
    med_f = np.full(cand_t.size, np.nan)
    finite = np.isfinite(f0).mean(axis=0) > 0.5
    med_f[finite] = np.nanmedian(f0[:, finite], axis=0)
    return RunPlan(
        operating_temperature_C=t_op, current_sd_um=current, torque_Nm=cand_t[order],
        temperature_C=cand_th[order], predicted_sd_um=np.sqrt(np.clip(pred_var[order], 0,
                                                                      None)),
        predicted_f_n_Hz=med_f[order], detection_probability=p_seen.mean(axis=0)[order])
