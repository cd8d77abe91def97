r"""Forward models: the mesh natural frequency of every run for a whole ensemble of parameters.

Built once per calibration from :func:`models.thermal.prepare_natural_frequency` (its public
attributes only: quadrature ``weights``, ``load_share``, ``k_EP_N_per_m``,
``equivalent_mass_kg``, ``base_radius_pinion_m``, ``s_m``) and evaluated for ``W`` walkers x
``R`` runs in a few array operations.

The three variants (issue 18 item 3)
------------------------------------
With the total normal load ``F = T / r_b1``, the nodes ``j`` of the path quadrature (weights
``w_j`` over the base pitch, load share ``R_j``, Ishikawa's ``k_EP,j``), the stiffness scale
``s`` (the rig's pair stiffness is ``s k_EP``) and the free play net of the thermal closure
``u = c - (1 - chi) Delta``:

``secant_path`` (seed 000 as :func:`models.thermal.mesh_natural_frequency` implements it):
Eq. (1) at each position, at the pair load ``F R_j``, averaged over the cycle,

.. math:: \bar k = \sum_j \frac{s\, w_j k_{EP,j}}{1 + (u / F)\, s\, k_{EP,j} / R_j} ;

``secant_mesh``: Eq. (1) applied to the mesh as a whole, total load and mean stiffness
``k_m = sum_j w_j k_EP,j``,

.. math:: \bar k = \frac{s\, k_m}{1 + (u / F)\, s\, k_m} ;

``tangent``: the small-vibration (tangent) stiffness about the loaded state, ``k = s k_m``,
independent of backlash and closure (the data then say nothing about ``c`` and the thermal
coefficient; their posteriors are their priors). The jam is not modelled in this variant.

In every variant ``f_n = sqrt(k / m_e) / (2 pi)``; ``m_e`` is the model's equivalent mass
(operating-pitch discs with bores, :mod:`models.geometry.inertia`) unless the campaign
gives ``equivalent_mass_kg`` or the inertias, which enter as ``f -> f sqrt(m_model / m_e)``
without re-preparing anything.

Why ``s`` multiplies ``k_EP`` inside Eq. (1) rather than ``f_n^2``: a rig stiffer or softer
than Ishikawa's ``k_EP`` also changes the elastic deflection ``F / k_EP`` that the backlash
competes with, so the load dependence of ``f_n`` changes with it. The consequence is the exact
symmetry ``(m_e, s, c, Delta) -> (lambda m_e, lambda s, c / lambda, Delta / lambda)``: every
prediction is unchanged, so ``c``, ``c*`` and the thermal coefficient scale with the assumed
equivalent mass while the sign of ``c - c*``, the regimes and the flip temperature do not
(:mod:`rigtools.calibration.derived`, tested).

Jammed runs
-----------
``secant_path`` jams where ``(u / F) s max_j(k_EP,j / R_j) <= -1`` (some node's Eq. (1)
denominator ``<= 0``), ``secant_mesh`` where ``(u / F) s k_m <= -1``. The prediction carries
the mask; ``f_n_Hz`` is NaN there with ``jammed_model="censored"`` (the likelihood then treats
the mesh mode as unobserved, :mod:`rigtools.calibration.likelihood`), or, with
``"double_flank"``, the jammed nodes (or the whole mesh) take the double-flank tangent
stiffness ``2 s k_EP`` (:func:`models.thermal.double_flank_contact`).

The thermal closure per unit coefficient
----------------------------------------
``linear``: ``Delta = kappa xi_1 L (theta - theta_ref)`` with ``L = a' sin(alpha')`` (the
closure of both gears uniformly at ``theta`` at the nominal centre distance is
``xi (theta - theta_ref) L``; :mod:`models.thermal.expansion`). ``expansion``: ``Delta = kappa
Delta_model`` with ``Delta_model`` the path mean of
:func:`models.thermal.thermal_deformation` for gears uniformly at the run's bulk temperature
under the campaign's :class:`~models.thermal.ThermalReference` (the oil temperature of the run
for ``follows-oil``; the flash temperature is not included). With uniform gear temperatures
both closures are uniform along the path, so ``c* = (1 - chi) Delta`` is exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from models.geometry import GearPair
from models.thermal import (
    GearTemperature,
    ThermalReference,
    prepare_natural_frequency,
    thermal_deformation,
)
from rigtools.calibration.config import JammedTreatment, ThermalModel, Variant

__all__ = [
    "ClosureBasis",
    "ForwardModel",
    "Prediction",
    "closure_basis",
    "mesh_frequency",
    "predict",
    "prepare_forward",
]


def _frozen(a: ArrayLike) -> np.ndarray:
    out = np.array(a, dtype=float)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class ClosureBasis:
    """Thermal closure per unit closure coefficient, ``Delta / kappa`` (m).

    Attributes
    ----------
    model : {"linear", "expansion"}
    reference_temperature_C : float
        ``theta_ref`` (degC): the temperature of the nominal geometry.
    run_m : numpy.ndarray
        At each run's logged bulk temperature (m), shape ``(R,)``.
    slope_m_per_K : numpy.ndarray
        Its derivative with the bulk temperature at each run (m/K).
    line_intercept_m, line_slope_m_per_K : float
        The line ``Delta/kappa = intercept + slope theta`` through the runs (exact for
        ``linear`` and for the expansion model at a fixed centre distance), used for
        ``c*(theta)`` at any temperature and the flip temperature.
    """

    model: ThermalModel
    reference_temperature_C: float
    run_m: np.ndarray
    slope_m_per_K: np.ndarray
    line_intercept_m: float
    line_slope_m_per_K: float

    def at(self, temperature_C: ArrayLike) -> np.ndarray:
        """``Delta / kappa`` on the line at bulk temperatures (m)."""
        t = np.asarray(temperature_C, dtype=float)
        return self.line_intercept_m + self.line_slope_m_per_K * t


def closure_basis(
    pair: GearPair,
    temperature_C: ArrayLike,
    *,
    model: ThermalModel,
    reference: ThermalReference,
    oil_temperature_C: ArrayLike | None = None,
    s_m: ArrayLike | None = None,
    weights: ArrayLike | None = None,
) -> ClosureBasis:
    r"""The thermal closure per unit coefficient at the runs' bulk temperatures.

    Parameters
    ----------
    pair : GearPair
    temperature_C : array_like
        Bulk temperature of each run (degC), 1-D.
    model : {"linear", "expansion"}
        Module notes.
    reference : ThermalReference
        Reference temperature (both models) and housing (``expansion``).
    oil_temperature_C : array_like, optional
        Oil temperature per run (degC, NaN where not logged: the bulk temperature is used);
        only for ``expansion`` with ``housing="follows-oil"``.
    s_m, weights : array_like, optional
        Nodes and weights on the path to average the ``expansion`` closure over (default:
        the pitch point).

    Returns
    -------
    ClosureBasis

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> b = closure_basis(g, [90.0], model="linear", reference=ThermalReference(20.0))
    >>> round(float(b.run_m[0]) * 1e6, 3)   # um, = 1.15e-5 * 70 K * a' sin(alpha')
    28.115
    """
    theta = np.atleast_1d(np.asarray(temperature_C, dtype=float))
    t_ref = float(reference.reference_temperature_C)
    xi = pair.pinion.material.thermal_expansion_per_K
    length = pair.line_of_action_length
    if model == "linear":
        slope = xi * length
        run = slope * (theta - t_ref)
        return ClosureBasis("linear", t_ref, _frozen(run), _frozen(np.full(theta.shape, slope)),
                            -slope * t_ref, slope)
    nodes = np.array([pair.pitch_point]) if s_m is None else np.asarray(s_m, dtype=float)
    w = np.ones(nodes.shape) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    oil = (np.full(theta.shape, np.nan) if oil_temperature_C is None
           else np.broadcast_to(np.asarray(oil_temperature_C, dtype=float), theta.shape))

    def closure(t: float, oil_t: float) -> float:
        ref = reference
        if reference.housing == "follows-oil":
            ref = ThermalReference(
                t_ref, "follows-oil", oil_temperature_C=float(oil_t),
                housing_expansion_per_K=reference.housing_expansion_per_K)
        d = thermal_deformation(pair, nodes, ref, GearTemperature.uniform(t))
        return float(np.sum(w * d.total_m))

    runs = np.empty(theta.shape)
    slopes = np.empty(theta.shape)
    for i, (t, o) in enumerate(zip(theta.tolist(), oil.tolist(), strict=True)):
        oil_t = t if not math.isfinite(o) else o
        runs[i] = closure(t, oil_t)
        slopes[i] = closure(t + 1.0, oil_t) - runs[i]
    if np.ptp(theta) > 0:
        line_slope, intercept = np.polyfit(theta, runs, 1)
    else:
        line_slope = float(np.mean(slopes))
        intercept = float(np.mean(runs) - line_slope * theta[0])
    return ClosureBasis("expansion", t_ref, _frozen(runs), _frozen(slopes), float(intercept),
                        float(line_slope))


@dataclass(frozen=True, eq=False)
class ForwardModel:
    """Everything of the forward model that does not depend on the sampled parameters.

    Attributes
    ----------
    variant : {"secant_path", "secant_mesh", "tangent"}
    jammed_model : {"censored", "double_flank"}
    torque_Nm, normal_load_N, temperature_C : numpy.ndarray
        Per run, shape ``(R,)``; ``normal_load_N = T / r_b1``.
    closure : ClosureBasis
    q_N_per_m : numpy.ndarray
        ``k_EP,j / R_j`` at the nodes (N/m), shape ``(n,)``.
    a_N_per_m : numpy.ndarray
        ``w_j k_EP,j`` (N/m).
    q_max_N_per_m : float
    k_mesh_N_per_m : float
        ``k_m = sum_j w_j k_EP,j``, the cycle-mean elastic mesh stiffness (N/m).
    equivalent_mass_kg : float
        ``m_e`` used (kg).
    model_equivalent_mass_kg : float
        ``m_e`` of the prepared model (kg), before any override.
    equivalent_mass_basis : str
        ``"operating-disc"``, ``"reference-disc"``, ``"given-inertias"`` or ``"given"``.
    """

    variant: Variant
    jammed_model: JammedTreatment
    torque_Nm: np.ndarray
    normal_load_N: np.ndarray
    temperature_C: np.ndarray
    closure: ClosureBasis
    q_N_per_m: np.ndarray
    a_N_per_m: np.ndarray
    q_max_N_per_m: float
    k_mesh_N_per_m: float
    equivalent_mass_kg: float
    model_equivalent_mass_kg: float
    equivalent_mass_basis: str

    @property
    def n_runs(self) -> int:
        """``R``."""
        return int(self.torque_Nm.size)

    @property
    def frequency_factor(self) -> float:
        """``1 / (2 pi sqrt(m_e))``: ``f_n = factor sqrt(k)`` (Hz per sqrt(N/m))."""
        return 1.0 / (2.0 * math.pi * math.sqrt(self.equivalent_mass_kg))

    def with_variant(self, variant: Variant) -> ForwardModel:
        """The same prepared model evaluated as another variant."""
        return _replace(self, variant=variant)

    def with_conditions(self, torque_Nm: ArrayLike, temperature_C: ArrayLike,
                        closure: ClosureBasis) -> ForwardModel:
        """The same model at other run conditions (for predictions on a grid)."""
        t = np.asarray(torque_Nm, dtype=float)
        return _replace(self, torque_Nm=_frozen(t),
                        normal_load_N=_frozen(t * self.normal_load_N[0] / self.torque_Nm[0]),
                        temperature_C=_frozen(temperature_C), closure=closure)


def _replace(m: ForwardModel, **kw: object) -> ForwardModel:
    d = {k: getattr(m, k) for k in m.__dataclass_fields__}
    d.update(kw)
    return ForwardModel(**d)  # type: ignore[arg-type]


def prepare_forward(
    pair: GearPair,
    torque_Nm: ArrayLike,
    temperature_C: ArrayLike,
    *,
    variant: Variant = "secant_path",
    thermal_model: ThermalModel = "linear",
    jammed_model: JammedTreatment = "censored",
    reference: ThermalReference | None = None,
    oil_temperature_C: ArrayLike | None = None,
    equivalent_mass_kg: float | None = None,
    inertia_kg_m2: tuple[float, float] | None = None,
    disc_radius: Literal["operating", "reference"] = "operating",
) -> ForwardModel:
    """Prepare the forward model of a campaign's runs (once per calibration).

    Parameters
    ----------
    pair : GearPair
    torque_Nm, temperature_C : array_like
        Pinion torque (N m, > 0) and bulk temperature (degC) of each run, 1-D.
    variant, thermal_model, jammed_model
        Module notes.
    reference : ThermalReference, optional
        Default ``ThermalReference(20.0)`` (fixed centre distance).
    oil_temperature_C : array_like, optional
        Per run (``expansion`` with a housing that follows the oil).
    equivalent_mass_kg : float, optional
        Override of ``m_e`` (kg).
    inertia_kg_m2 : (float, float), optional
        ``(J_1, J_2)`` (kg m^2) instead of the disc inertias.
    disc_radius : {"operating", "reference"}
        Disc radius of the default inertias (:func:`models.geometry.gear_inertia`).

    Returns
    -------
    ForwardModel

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> fm = prepare_forward(load_gear_set("fzg-c").pair, [302.0], [90.0])
    >>> round(fm.equivalent_mass_kg, 4), fm.equivalent_mass_basis
    (0.1857, 'operating-disc')
    """
    t = np.atleast_1d(np.asarray(torque_Nm, dtype=float))
    theta = np.atleast_1d(np.asarray(temperature_C, dtype=float))
    if t.ndim != 1 or t.shape != theta.shape:
        raise ValueError(f"`torque_Nm` and `temperature_C` must be 1-D of one length, had "
                         f"shapes {t.shape} and {theta.shape}")
    if not np.all(np.isfinite(t) & (t > 0)):
        raise ValueError(f"`torque_Nm` must be finite and > 0, was {t.tolist()}")
    if not np.all(np.isfinite(theta)):
        raise ValueError(f"`temperature_C` must be finite, was {theta.tolist()}")
    nf = prepare_natural_frequency(pair, disc_radius=disc_radius, inertia_kg_m2=inertia_kg_m2)
    k_ep = np.asarray(nf.k_EP_N_per_m, dtype=float)
    q = k_ep / np.asarray(nf.load_share, dtype=float)
    a = np.asarray(nf.weights, dtype=float) * k_ep
    ref = ThermalReference(20.0) if reference is None else reference
    basis = closure_basis(pair, theta, model=thermal_model, reference=ref,
                          oil_temperature_C=oil_temperature_C, s_m=nf.s_m, weights=nf.weights)
    m_model = float(nf.equivalent_mass_kg)
    if equivalent_mass_kg is not None:
        m_e, how = float(equivalent_mass_kg), "given"
    elif inertia_kg_m2 is not None:
        m_e, how = m_model, "given-inertias"
    else:
        m_e, how = m_model, f"{disc_radius}-disc"
    return ForwardModel(
        variant=variant, jammed_model=jammed_model, torque_Nm=_frozen(t),
        normal_load_N=_frozen(t / nf.base_radius_pinion_m), temperature_C=_frozen(theta),
        closure=basis, q_N_per_m=_frozen(q), a_N_per_m=_frozen(a),
        q_max_N_per_m=float(q.max()), k_mesh_N_per_m=float(a.sum()), equivalent_mass_kg=m_e,
        model_equivalent_mass_kg=m_model, equivalent_mass_basis=how,
    )


@dataclass(frozen=True, eq=False)
class Prediction:
    """Predictions for ``W`` parameter sets x ``R`` runs.

    Attributes
    ----------
    f_n_Hz : numpy.ndarray
        Mesh natural frequency (Hz), ``(W, R)``; NaN where jammed and censored.
    k_mean_N_per_m : numpy.ndarray
        Cycle-mean mesh stiffness (N/m), NaN likewise.
    jammed : numpy.ndarray
        Bool, the run is jammed by thermal growth (never in the tangent variant).
    closure_m : numpy.ndarray
        Thermal closure ``Delta`` of the run (m).
    critical_gap_m : numpy.ndarray
        ``c* = (1 - chi) Delta`` (m).
    """

    f_n_Hz: np.ndarray
    k_mean_N_per_m: np.ndarray
    jammed: np.ndarray
    closure_m: np.ndarray
    critical_gap_m: np.ndarray


def _mesh_stiffness(model: ForwardModel, u: np.ndarray,
                    s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cycle-mean stiffness ``(W, R)`` and jammed mask for free play ``u`` (m) and scale ``s``.

    Jammed entries hold NaN (censored) or the double-flank value; no division by zero or
    overflow happens (jammed denominators are replaced before dividing).
    """
    a = model.a_N_per_m
    if model.variant == "tangent":
        k = s * model.k_mesh_N_per_m + 0.0 * u
        return k, np.zeros(k.shape, dtype=bool)
    ratio = u * s / model.normal_load_N
    if model.variant == "secant_path":
        jammed = ratio * model.q_max_N_per_m <= -1.0
        den = ratio[..., None] * model.q_N_per_m
        den += 1.0
        if model.jammed_model == "double_flank" and jammed.any():
            pos = den > 0.0
            k = s * np.where(pos, a / np.where(pos, den, 1.0), 2.0 * a).sum(axis=-1)
            return k, jammed
        if jammed.any():
            den[jammed] = 1.0
        k = s * (np.reciprocal(den) @ a)
    else:
        km = model.k_mesh_N_per_m
        den = 1.0 + ratio * km
        jammed = den <= 0.0
        k = s * km / np.where(jammed, 1.0, den)
        if model.jammed_model == "double_flank":
            return np.where(jammed, 2.0 * s * km, k), jammed
    if model.jammed_model == "censored" and jammed.any():
        k = np.where(jammed, np.nan, k)
    return k, jammed


def mesh_frequency(
    model: ForwardModel,
    backlash_m: np.ndarray,
    closure_coefficient: np.ndarray,
    stiffness_scale: np.ndarray,
    chi: np.ndarray,
    temperature_offset_K: np.ndarray | None = None,
) -> np.ndarray:
    """``f_n`` (Hz) only, ``(W, R)``: the lean path of :func:`predict` for the sampler.

    Arguments as :func:`predict`, already float arrays of shape ``(W,)`` (offsets
    ``(W, R)``); NaN where jammed and censored.
    """
    basis = model.closure.run_m
    if temperature_offset_K is not None:
        basis = basis + model.closure.slope_m_per_K * temperature_offset_K
    u = backlash_m[:, None] - ((1.0 - chi) * closure_coefficient)[:, None] * basis
    k, _ = _mesh_stiffness(model, u, stiffness_scale[:, None])
    return np.sqrt(k) * model.frequency_factor


def predict(
    model: ForwardModel,
    backlash_m: ArrayLike,
    closure_coefficient: ArrayLike,
    stiffness_scale: ArrayLike,
    chi: ArrayLike,
    *,
    temperature_offset_K: ArrayLike | None = None,
) -> Prediction:
    """Mesh natural frequency of every run for every parameter set (module notes).

    Parameters
    ----------
    model : ForwardModel
    backlash_m : array_like
        ``c`` (m), shape ``(W,)`` (or scalar).
    closure_coefficient : array_like
        ``kappa`` (-), ``(W,)``.
    stiffness_scale : array_like
        ``s`` (-), ``(W,)``, > 0.
    chi : array_like
        (-), ``(W,)``.
    temperature_offset_K : array_like, optional
        True minus logged bulk temperature (K), ``(W, R)``.

    Returns
    -------
    Prediction
        Arrays of shape ``(W, R)``.

    Examples
    --------
    >>> from models.geometry import load_gear_set
    >>> fm = prepare_forward(load_gear_set("fzg-c").pair, [35.3, 302.0], [90.0, 90.0])
    >>> p = predict(fm, [40e-6], [0.0], [1.0], [0.0285])
    >>> bool(p.f_n_Hz[0, 0] < p.f_n_Hz[0, 1])   # c > c*: f_n rises with load
    True
    """
    c = np.atleast_1d(np.asarray(backlash_m, dtype=float))[:, None]
    kappa = np.atleast_1d(np.asarray(closure_coefficient, dtype=float))[:, None]
    s = np.atleast_1d(np.asarray(stiffness_scale, dtype=float))[:, None]
    x = np.atleast_1d(np.asarray(chi, dtype=float))[:, None]
    basis = model.closure.run_m[None, :]
    if temperature_offset_K is not None:
        basis = basis + model.closure.slope_m_per_K[None, :] * np.asarray(
            temperature_offset_K, dtype=float)
    closure = kappa * basis
    c_star = (1.0 - x) * closure
    shape = np.broadcast_shapes(c.shape, kappa.shape, s.shape, x.shape, basis.shape)
    u = np.broadcast_to(c - c_star, shape)
    k, jammed = _mesh_stiffness(model, u, np.broadcast_to(s, shape))
    return Prediction(f_n_Hz=np.sqrt(k) * model.frequency_factor, k_mean_N_per_m=k,
                      jammed=jammed, closure_m=np.broadcast_to(closure, shape).copy(),
                      critical_gap_m=np.broadcast_to(c_star, shape).copy())
