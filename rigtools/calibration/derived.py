r"""Derived quantities: critical gaps, margins, regimes, the flip temperature, the mesh mode.

From every posterior draw (backlash ``c``, closure coefficient ``kappa``, ``chi``, stiffness
scale ``s``, temperature offsets):

``critical_gap@<T>C`` (um)
    ``c*(T) = (1 - chi) kappa Delta_1(T)`` at every bulk temperature of the campaign (and at
    the operating temperature), ``Delta_1`` the closure per unit coefficient on the line of
    :class:`~rigtools.calibration.forward.ClosureBasis` (T written with Python's ``{:g}``).
``thermal_closure@<T>C`` (um)
    ``Delta(T) = kappa Delta_1(T)``.
``margin@<run>`` (um)
    ``c - c*`` of the run, at its own closure (its logged temperature, plus its sampled
    offset when temperatures carry a measurement error). ``margin@<T>C`` at the operating
    temperature.
``relative_margin@<run>`` (1)
    ``(c - c*) / delta_el``: the run's margin in units of its mean elastic deflection
    ``delta_el = F / (s k_m)`` (``F = T / r_b1``, ``k_m`` the cycle-mean ``k_EP``). It says how
    far the run is from the jam in the measure the stiffness responds to: ``0`` is the critical
    gap (the secant stiffness equals the elastic one at every load), ``-1`` the jam of the mesh
    taken as a whole (``secant_mesh``; the path reading jams a little earlier, at the most
    loaded node). Unlike ``margin@<run>`` it does not depend on the assumed equivalent mass.
``flip_temperature_C`` (degC)
    The bulk temperature at which ``c = c*(T)``: below it the stiffness rises with load, above
    it falls (seed 000 Table 5). Draws whose closure does not grow with temperature
    (``kappa <= 0``) have no flip temperature (+inf; the summary gives the finite fraction).
``mesh_stiffness_elastic`` (N/m)
    ``s k_m``: the rig's cycle-mean elastic mesh stiffness.

Per run (:func:`run_summaries`): the regime with its probability (``rises`` when
``c - c* > band``, ``falls`` when ``< -band``, ``unchanged`` in between; ``band`` is the
``unchanged_band_um`` tolerance), ``P(c < c*)``, the probability the run is jammed, and the
mesh mode: the candidate with the largest posterior assignment probability, that probability
summed over the rows (other channels) within three combined standard deviations of it.

What is robust (issue 18 item 8)
--------------------------------
The forward model is invariant under ``(m_e, s, c, Delta) -> (lambda m_e, lambda s,
c / lambda, Delta / lambda)`` (:mod:`rigtools.calibration.forward`) and, for a closure linear in
temperature, under ``theta_ref -> theta_ref + d`` with ``c -> c - (1 - chi) kappa Delta_1'
d``. So ``backlash``, ``critical_gap@*``, ``thermal_closure@*``, ``closure_coefficient`` and
``margin@*`` scale with ``1 / m_e`` (``stiffness_scale`` and ``mesh_stiffness_elastic`` with
``m_e``); ``backlash`` and ``critical_gap@*`` also shift with the reference temperature;
``margin@*`` does not shift; the sign of every margin, ``p_c_lt_cstar``, the regimes,
``flip_temperature_C`` and ``relative_margin@*`` are invariant to both.

Why the margin in micrometres is not invariant to ``m_e``: the data are natural frequencies,
``f_n^2 = k / m_e``, so a heavier assumed mass needs a stiffer mesh, ``s -> lambda s``; with the
rig's stiffness inside Eq. (1) (the elastic deflection the free play adds to is ``F / (s k)``)
the same frequencies then need the free play ``c - (1 - chi) Delta`` to shrink by the same
``lambda``. Only ``s / m_e`` and the play times ``s`` are identified, so every length the
calibration reports is "per assumed mass"; the margin over the elastic deflection is the length
ratio the data fix. The regimes use ``unchanged_band_um`` in micrometres, so a run within a few
percent of the band's edge can change regime with ``m_e``. :data:`ROBUSTNESS` states it per
quantity (written into ``summary.json``), and ``tests/calibration/test_robustness.py`` shows it
on posteriors.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from rigtools.calibration.model import TEMPERATURE_OFFSET, UM, CalibrationModel

__all__ = [
    "ROBUSTNESS",
    "Quantity",
    "derived_quantities",
    "regime_probabilities",
    "run_margins_um",
    "run_summaries",
    "temperature_label",
]

#: How each kind of quantity responds to the equivalent mass and to the reference temperature.
ROBUSTNESS: Final[dict[str, dict[str, str]]] = {
    "backlash": {"equivalent_mass": "scales as 1/m_e", "reference_temperature": "shifts"},
    "closure_coefficient": {"equivalent_mass": "scales as 1/m_e",
                            "reference_temperature": "invariant (linear closure)"},
    "stiffness_scale": {"equivalent_mass": "scales as m_e", "reference_temperature": "invariant"},
    "model_error": {"equivalent_mass": "invariant", "reference_temperature": "invariant"},
    "chi": {"equivalent_mass": "invariant", "reference_temperature": "invariant"},
    "critical_gap@*": {"equivalent_mass": "scales as 1/m_e", "reference_temperature": "shifts"},
    "thermal_closure@*": {"equivalent_mass": "scales as 1/m_e",
                          "reference_temperature": "shifts"},
    "margin@*": {"equivalent_mass": "scales as 1/m_e (its sign is invariant)",
                 "reference_temperature": "invariant"},
    "relative_margin@*": {"equivalent_mass": "invariant", "reference_temperature": "invariant"},
    "flip_temperature_C": {"equivalent_mass": "invariant", "reference_temperature": "invariant"},
    "mesh_stiffness_elastic": {"equivalent_mass": "scales as m_e",
                               "reference_temperature": "invariant"},
    "runs.*.regime, p_c_lt_cstar": {"equivalent_mass": "invariant",
                                    "reference_temperature": "invariant"},
}


@dataclass(frozen=True, eq=False)
class Quantity:
    """Posterior draws of one named quantity.

    Attributes
    ----------
    name : str
    unit : str
        One of ``m, um, degC, K, 1, N/m, kg``.
    kind : {"parameter", "derived"}
    draws : numpy.ndarray
        ``(W, N)``: walkers x kept draws.
    """

    name: str
    unit: str
    kind: str
    draws: np.ndarray


def temperature_label(temperature_C: float) -> str:
    """``"90C"`` for 90.0 (Python's ``{:g}``)."""
    return f"{temperature_C:g}C"


def run_margins_um(model: CalibrationModel, p: dict[str, np.ndarray]) -> np.ndarray:
    """``c - c*`` (um) of every run, ``(..., R)``, from unpacked parameters.

    Parameters
    ----------
    model : CalibrationModel
    p : dict
        :meth:`CalibrationModel.unpack` of parameter vectors.
    """
    cl = model.forward.closure
    basis = cl.run_m + cl.slope_m_per_K * p["temperature_offset_K"]
    c_star = ((1.0 - p["chi"]) * p["closure_coefficient"])[..., None] * basis
    return p["backlash"][..., None] - c_star / UM


def derived_quantities(model: CalibrationModel, samples: np.ndarray, *,
                       operating_temperature_C: float) -> list[Quantity]:
    """Parameters and derived quantities of every draw (module notes).

    Parameters
    ----------
    model : CalibrationModel
    samples : numpy.ndarray
        ``(W, N, D)``.
    operating_temperature_C : float
        Adds ``critical_gap``, ``thermal_closure`` and ``margin`` at this temperature.

    Returns
    -------
    list of Quantity
        Parameters first (vector order), then the derived ones.
    """
    out = [Quantity(n, u, "parameter", samples[..., i])
           for i, (n, u) in enumerate(zip(model.names, model.units, strict=True))]
    p = model.unpack(samples)
    cl = model.forward.closure
    temps = sorted({*model.forward.temperature_C.tolist(), float(operating_temperature_C)})
    k1 = (1.0 - p["chi"]) * p["closure_coefficient"]
    for t in temps:
        delta = p["closure_coefficient"] * float(cl.at(t)) / UM
        out.append(Quantity(f"critical_gap@{temperature_label(t)}", "um", "derived",
                            (1.0 - p["chi"]) * delta))
    for t in temps:
        out.append(Quantity(f"thermal_closure@{temperature_label(t)}", "um", "derived",
                            p["closure_coefficient"] * float(cl.at(t)) / UM))
    margins = run_margins_um(model, p)
    for r, run_id in enumerate(model.data.runs.run_id):
        out.append(Quantity(f"margin@{run_id}", "um", "derived", margins[..., r]))
    # delta_el = F / (s k_m), in um
    deflection_um = (model.forward.normal_load_N / model.forward.k_mesh_N_per_m / UM
                     / p["stiffness_scale"][..., None])
    for r, run_id in enumerate(model.data.runs.run_id):
        out.append(Quantity(f"relative_margin@{run_id}", "1", "derived",
                            margins[..., r] / deflection_um[..., r]))
    t_op = float(operating_temperature_C)
    out.append(Quantity(f"margin@{temperature_label(t_op)}", "um", "derived",
                        p["backlash"] - k1 * float(cl.at(t_op)) / UM))
    rate = k1 * cl.line_slope_m_per_K / UM          # um/K
    with np.errstate(divide="ignore", invalid="ignore"):
        flip = np.where(rate > 0, (p["backlash"] - k1 * cl.line_intercept_m / UM) / rate,
                        np.inf)
    out.append(Quantity("flip_temperature_C", "degC", "derived", flip))
    out.append(Quantity("mesh_stiffness_elastic", "N/m", "derived",
                        p["stiffness_scale"] * model.forward.k_mesh_N_per_m))
    return out


def regime_probabilities(margin_um: np.ndarray, band_um: float) -> dict[str, float]:
    """``P(rises)``, ``P(falls)``, ``P(unchanged)`` from margin draws (um).

    Examples
    --------
    >>> regime_probabilities(np.array([-3.0, 0.5, 2.0, 4.0]), 1.0)
    {'rises': 0.5, 'falls': 0.25, 'unchanged': 0.25}
    """
    m = np.asarray(margin_um, dtype=float).ravel()
    n = m.size
    rises = float(np.count_nonzero(m > band_um)) / n
    falls = float(np.count_nonzero(m < -band_um)) / n
    return {"rises": rises, "falls": falls, "unchanged": 1.0 - rises - falls}


def run_summaries(model: CalibrationModel, samples: np.ndarray, *, band_um: float,
                  max_draws: int = 2000) -> dict[str, dict[str, Any]]:
    """Regime, probabilities and the chosen mesh-mode peak of every fitted run.

    Parameters
    ----------
    model : CalibrationModel
    samples : numpy.ndarray
        ``(W, N, D)``.
    band_um : float
        ``|c - c*|`` counted as ``unchanged`` (um).
    max_draws : int
        Draws (evenly spaced) used for the assignment probabilities.

    Returns
    -------
    dict
        Run id -> ``regime``, ``regime_probability``, ``regime_probabilities``,
        ``p_c_lt_cstar``, ``jammed_probability``, ``mesh_mode_Hz``, ``mesh_mode_channel``,
        ``mesh_mode_probability``, ``p_mesh_mode_not_observed``, ``predicted_f_n_Hz``
        (mean, q05, q95), ``torque_Nm``, ``bulk_temperature_C``, ``left_out`` (None).
    """
    flat = samples.reshape(-1, samples.shape[-1])
    p = model.unpack(flat)
    margins = run_margins_um(model, p)
    pick = np.unique(np.linspace(0, flat.shape[0] - 1, min(max_draws, flat.shape[0]))
                     .astype(int))
    sub = flat[pick]
    pred = model.predict(sub)
    f = pred.f_n_Hz
    assign = model.likelihood.assignment_probabilities(f, model.unpack(sub)["model_error"])
    mean_assign = assign.mean(axis=0)                          # (R, J + 1)
    cand = model.data.candidates
    runs = model.data.runs
    out: dict[str, dict[str, Any]] = {}
    for r, run_id in enumerate(runs.run_id):
        probs = regime_probabilities(margins[:, r], band_um)
        regime = max(probs, key=lambda k: probs[k])
        j_n = int(cand.count[r])
        pj = mean_assign[r, :j_n]
        p_none = float(mean_assign[r, -1])
        best = int(np.argmax(pj))
        fb, sb = cand.f_Hz[r, best], cand.sd_Hz[r, best]
        f_row = cand.f_Hz[r, :j_n]
        tol = 3.0 * np.sqrt(cand.sd_Hz[r, :j_n] ** 2 + sb**2) + 1e-9 * fb
        group = float(pj[np.abs(f_row - fb) <= tol].sum())
        fr = f[:, r]
        finite = fr[np.isfinite(fr)]
        chosen = group > p_none
        out[run_id] = {
            "regime": regime,
            "regime_probability": probs[regime],
            "regime_probabilities": probs,
            "p_c_lt_cstar": float(np.mean(margins[:, r] < 0.0)),
            "jammed_probability": float(np.mean(pred.jammed[:, r])),
            "mesh_mode_Hz": float(fb) if chosen else None,
            "mesh_mode_channel": (None if not chosen or cand.channel[r, best] is None
                                  else str(cand.channel[r, best])),
            "mesh_mode_probability": group if chosen else 1.0 - p_none,
            "p_mesh_mode_not_observed": p_none,
            "predicted_f_n_Hz": ({"mean": float(finite.mean()),
                                  "q05": float(np.quantile(finite, 0.05)),
                                  "q95": float(np.quantile(finite, 0.95))}
                                 if finite.size else None),
            "torque_Nm": float(runs.torque_Nm[r]),
            "bulk_temperature_C": float(runs.bulk_temperature_C[r]),
            "left_out": None,
        }
        if model.has_temperature_offsets:
            i = model.names.index(f"{TEMPERATURE_OFFSET}{run_id}")
            out[run_id]["temperature_offset_K"] = float(flat[:, i].mean())
    return out
