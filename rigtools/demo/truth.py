r"""The known truth of the demo campaign: backlash, thermal closure and mesh natural frequencies.

The demo campaign (:mod:`rigtools.demo.campaign`) is generated *from* the physics of
:mod:`models.thermal`, so that every number a calibration reports can be checked against the
value the recordings were made from. This module holds that truth and computes it.

The true model
--------------
An FZG type C pair (``models.geometry.load_gear_set("fzg-c")``, seed 000 Table 1) with

* a total backlash ``c`` on the line of action (at the reference temperature
  ``theta_ref``, the assembly temperature);
* a **linear thermal closure** in the gear bulk temperature ``theta``,

  .. math:: \Delta(\theta) = \beta\,(\theta - \theta_{ref}),

  uniform along the path of contact, so the critical compensation gap is
  ``c*(theta) = (1 - chi) Delta(theta)`` (:func:`models.thermal.critical_gap`), the margin
  of a run ``c - c*(theta)``, its regime (seed 000 Table 5, :func:`models.thermal.stiffness_regime`)
  ``rises`` (``c > c*``), ``falls`` (``c < c*``) or ``unchanged``, and the flip temperature
  ``theta_f = theta_ref + c / ((1 - chi) beta)``;
* seed 000's correction factor ``chi = 0.0285``;
* a stiffness scale ``s``: the rig's elastic pair stiffness is ``s k_EP`` (Ishikawa's ``k_EP``
  times ``s``, *inside* Eq. (1) of :mod:`models.thermal.thermoelastic`, the convention of
  :mod:`rigtools.calibration.forward`);
* the mesh mode's natural frequency from :func:`models.thermal.mesh_natural_frequency`
  (Eq. (1) along the path of contact at the pair loads ``F R(s)``, the *secant* reading,
  cycle mean) with :func:`models.thermal.prepare_natural_frequency`'s equivalent mass
  ``m_e`` (discs of the operating pitch radius with the gears' bores, 0.3 d when none is
  stated: 0.1857 kg for FZG-C). With ``s`` inside Eq. (1) the cycle-mean stiffness is
  ``k(s, c, Delta) = s k_model(s c, s Delta)`` exactly (``u = c - (1 - chi) Delta`` enters
  only through ``u s k_EP / F``), so

  .. math:: f_n = \sqrt{s}\; f_n^{model}(T, s\Delta, s c, \chi) ,

  computed with the public API and checked in the tests against a plain loop over
  :func:`models.thermal.thermoelastic_pair_stiffness` with ``s k_EP``.

Why these values (FZG-C)
------------------------
``beta`` from :mod:`models.thermal`'s expansion model at the FZG-C case: seed 000's hot state
(302 N m, 1500 rpm, 90 degC oil, backlash defined at 20 degC;
:func:`models.thermal.seed_000_hot_state_closure`) closes the flank gap by 10.58 um, the
reading that reproduces the seed's ``c* ~ 10 um``. The line through 0 at 20 degC and that
value gives ``beta = 10.58 / 70 = 0.151 um/K``. Its physical reading: gears uniformly at
``theta`` in a housing whose centre distance follows a housing (oil) temperature
``theta_h = theta - beta (theta - theta_ref) / (xi a' sin alpha')``, i.e. warming 62 % as much
as the gears (:func:`housing_temperature_C`; :func:`models.thermal.thermal_deformation` with a
``"follows-oil"`` reference at ``theta_h`` gives the same closure, tested). The demo logs that
temperature as the oil temperature, so the ``expansion`` closure with ``housing =
"follows-oil"`` and coefficient 1 holds the same truth as the ``linear`` one. In the
calibration's parametrisation (``Delta = kappa xi_1 a' sin(alpha') (theta - theta_ref)``) this
is ``kappa = beta / (xi a' sin alpha') = 0.376``.

``c = 7.5 um`` and ``s = 0.8`` put the flip at 71.1 degC, between the cooler test temperatures
(30 and 55 degC: ``c > c*``, margins +6.0 and +2.4 um) and the hot ones (90 and 105 degC:
``c < c*``, margins -2.8 and -5.0 um), every margin at least twice the calibration's default
``unchanged`` band (1 um) away from zero. ``s = 0.8``: a rig 20 % softer than Ishikawa's
``k_EP`` (SEED-NOTES 3, 19: tens of percent), inside the calibration's default prior.
With these values the mesh mode lies between 1.4 and 8.8 kHz at 1500 rpm: well inside what a
25.6 kHz accelerometer channel resolves (at most 0.35 of the sampling rate, below the
anti-alias roll-off at about 0.45), at least 70 Hz away from every mesh harmonic 1-5, its
shaft-rate sidebands and the shaft harmonics (where the analysis would flag ``at_mesh_line``).
The runs at 3.3 and 35.3 N m are left out at the hot temperatures: there the closure exceeds the
elastic deflection (the jammed state, where Eq. (1) does not apply), as seed 000 Table 6 also
runs only 183.4 and 302 N m at 90 degC.

The housing mode (a bearing-cover mode at 4.9 kHz, ``zeta = 0.012``) does not move with load or
temperature; it is 320 Hz from the mesh mode at 55 degC / 35.3 N m.

The run-up
----------
The campaign's run-up run on the Kahraman-Blankenship pair (:mod:`rigtools.demo.runup`) has its
own truth, :class:`RunUpTruth` (a VVMS model: damping ratio, stiffness and fluctuation scales,
backlash, channel gains, the mesh natural frequency, the jump frequencies of its steady sweep),
kept in :attr:`CampaignTruth.runup` and written as ``truth.json["runup"]`` in the run-up
calibration's names.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final, Literal

import numpy as np

from models.geometry import EQUIVALENT_MASS_CONVENTION, GearPair, GearSet
from models.thermal import (
    FALLS,
    RISES,
    SEED_000_CHI,
    NaturalFrequencyModel,
    critical_gap,
    mesh_natural_frequency,
    seed_000_hot_state_closure,
    stiffness_regime,
)

__all__ = [
    "BACKLASH_M",
    "HOUSING_F_N_HZ",
    "HOUSING_ZETA",
    "MESH_ZETA",
    "REFERENCE_TEMPERATURE_C",
    "SPEED_RPM",
    "STIFFNESS_SCALE",
    "CampaignTruth",
    "HousingMode",
    "MeshMode",
    "Regime",
    "RunCondition",
    "RunTruth",
    "RunUpTruth",
    "TruePhysics",
    "campaign_truth",
    "closure_slope_from_seed",
    "housing_temperature_C",
    "mesh_mode",
    "regime_name",
    "temperature_label",
    "true_physics",
]

#: Assembly temperature at which the backlash is defined (degC).
REFERENCE_TEMPERATURE_C: Final[float] = 20.0
#: True total backlash on the line of action at the reference temperature (m).
BACKLASH_M: Final[float] = 7.5e-6
#: True stiffness scale ``s`` (rig pair stiffness over Ishikawa's ``k_EP``).
STIFFNESS_SCALE: Final[float] = 0.8
#: Damping ratio of the mesh mode (-).
MESH_ZETA: Final[float] = 0.03
#: Natural frequency of the housing (bearing-cover) mode (Hz), independent of load and heat.
HOUSING_F_N_HZ: Final[float] = 4900.0
#: Damping ratio of the housing mode (-).
HOUSING_ZETA: Final[float] = 0.012
#: Pinion speed of every run (rpm; seed 000 Table 1).
SPEED_RPM: Final[float] = 1500.0

Regime = Literal["rises", "falls", "unchanged"]
_HOT_STATE_OIL_C: Final[float] = 90.0  # seed_000_hot_state_closure's default oil temperature


def regime_name(code: int) -> Regime:
    """Seed 000 Table 5 regime name of a :func:`models.thermal.stiffness_regime` code."""
    if code == RISES:
        return "rises"
    if code == FALLS:
        return "falls"
    return "unchanged"


def temperature_label(temperature_C: float) -> str:
    """``30C`` for 30.0 degC: the label of ``critical_gap@<T>C`` (Python's ``{:g}``)."""
    return f"{float(temperature_C):g}C"


def closure_slope_from_seed(gear_set: GearSet,
                          reference_temperature_C: float = REFERENCE_TEMPERATURE_C) -> float:
    r"""``beta`` (m/K): seed 000's hot-state closure over its temperature rise.

    .. math:: \beta = \frac{\Delta_{hot}}{\theta_{hot} - \theta_{ref}}

    with ``Delta_hot`` from :func:`models.thermal.seed_000_hot_state_closure` (302 N m,
    1500 rpm, 90 degC oil, from ``reference_temperature_C``; the path mean).

    Parameters
    ----------
    gear_set : GearSet
        The pair (FZG-C for the demo).
    reference_temperature_C : float
        ``theta_ref`` (degC), below 90 degC.

    Returns
    -------
    float
        ``beta`` (m/K); 0.151e-6 for FZG-C from 20 degC.
    """
    if not reference_temperature_C < _HOT_STATE_OIL_C:
        raise ValueError(f"`reference_temperature_C` must be < {_HOT_STATE_OIL_C:g} degC, was "
                         f"{reference_temperature_C!r}")
    hot = seed_000_hot_state_closure(gear_set, reference_temperature_C=reference_temperature_C)
    return hot.total_m / (_HOT_STATE_OIL_C - reference_temperature_C)


def housing_temperature_C(  # noqa: N802 (unit in the name)
        pair: GearPair, bulk_temperature_C: float, slope_m_per_K: float,
        reference_temperature_C: float = REFERENCE_TEMPERATURE_C) -> float:
    r"""Housing (oil) temperature at which gears uniformly at ``theta`` close the gap by ``Delta``.

    With the centre distance following a housing at ``theta_h`` (``"follows-oil"``, housing
    expansion = the gears'), gears uniformly at ``theta`` close the flank gap by
    ``xi (theta - theta_h) a' sin(alpha')`` (:mod:`models.thermal.reference_state`); equal to
    ``beta (theta - theta_ref)`` when

    .. math:: \theta_h = \theta - \frac{\beta (\theta - \theta_{ref})}{\xi\, a' \sin\alpha'} .

    Parameters
    ----------
    pair : GearPair
    bulk_temperature_C : float
        ``theta`` (degC).
    slope_m_per_K : float
        ``beta`` (m/K).
    reference_temperature_C : float
        ``theta_ref`` (degC).

    Returns
    -------
    float
        ``theta_h`` (degC).
    """
    xi = pair.pinion.material.thermal_expansion_per_K
    full = xi * pair.line_of_action_length  # closure per K of gears in a cold housing (m/K)
    dt = float(bulk_temperature_C) - float(reference_temperature_C)
    return float(bulk_temperature_C) - float(slope_m_per_K) * dt / full


@dataclass(frozen=True)
class TruePhysics:
    """The true parameters of the demo pair.

    Attributes
    ----------
    backlash_m : float
        ``c`` (m) at the reference temperature.
    closure_slope_m_per_K : float
        ``beta`` (m/K) of the linear closure.
    reference_temperature_C : float
        ``theta_ref`` (degC).
    chi : float
        Seed 000's correction factor (-).
    stiffness_scale : float
        ``s`` (-).
    equivalent_mass_kg : float
        ``m_e`` of the prepared model (kg).
    k_EP_mean_N_per_m : float
        Cycle mean of Ishikawa's ``k_EP`` (N/m), before the scale ``s``.
    closure_coefficient : float
        ``beta / (xi a' sin alpha')`` (-): the calibration's ``closure_coefficient``.
    """

    backlash_m: float
    closure_slope_m_per_K: float
    reference_temperature_C: float
    chi: float
    stiffness_scale: float
    equivalent_mass_kg: float
    k_EP_mean_N_per_m: float
    closure_coefficient: float

    def closure_m(self, temperature_C: float) -> float:
        """``Delta(theta) = beta (theta - theta_ref)`` (m)."""
        return self.closure_slope_m_per_K * (float(temperature_C) - self.reference_temperature_C)

    def critical_gap_m(self, temperature_C: float) -> float:
        """``c*(theta) = (1 - chi) Delta(theta)`` (m), :func:`models.thermal.critical_gap`."""
        return float(critical_gap(self.closure_m(temperature_C), self.chi))

    @property
    def flip_temperature_C(self) -> float:  # noqa: N802 (unit in the name)
        """``theta_f`` (degC) where ``c = c*(theta_f)``."""
        return self.reference_temperature_C + self.backlash_m / (
            (1.0 - self.chi) * self.closure_slope_m_per_K)


def true_physics(model: NaturalFrequencyModel, gear_set: GearSet, *,
                 backlash_m: float = BACKLASH_M, stiffness_scale: float = STIFFNESS_SCALE,
                 chi: float = SEED_000_CHI,
                 reference_temperature_C: float = REFERENCE_TEMPERATURE_C,
                 slope_m_per_K: float | None = None) -> TruePhysics:
    """The demo's true parameters (defaults: module notes).

    Parameters
    ----------
    model : NaturalFrequencyModel
        From :func:`models.thermal.prepare_natural_frequency` for ``gear_set.pair``.
    gear_set : GearSet
    backlash_m : float
        ``c`` (m), >= 0.
    stiffness_scale : float
        ``s`` (-), > 0.
    chi : float
        Correction factor (-).
    reference_temperature_C : float
        ``theta_ref`` (degC).
    slope_m_per_K : float, optional
        ``beta`` (m/K); default :func:`closure_slope_from_seed`.

    Returns
    -------
    TruePhysics
    """
    if not (math.isfinite(backlash_m) and backlash_m >= 0):
        raise ValueError(f"`backlash_m` must be finite and >= 0, was {backlash_m!r}")
    if not (math.isfinite(stiffness_scale) and stiffness_scale > 0):
        raise ValueError(f"`stiffness_scale` must be finite and > 0, was {stiffness_scale!r}")
    beta = (closure_slope_from_seed(gear_set, reference_temperature_C)
            if slope_m_per_K is None else float(slope_m_per_K))
    pair = gear_set.pair
    full = pair.pinion.material.thermal_expansion_per_K * pair.line_of_action_length
    return TruePhysics(
        backlash_m=float(backlash_m), closure_slope_m_per_K=beta,
        reference_temperature_C=float(reference_temperature_C), chi=float(chi),
        stiffness_scale=float(stiffness_scale),
        equivalent_mass_kg=float(model.equivalent_mass_kg),
        k_EP_mean_N_per_m=float(np.asarray(model.k_EP_mean_N_per_m).mean()),
        closure_coefficient=beta / full)


@dataclass(frozen=True)
class MeshMode:
    """The mesh mode of one run.

    Attributes
    ----------
    f_n_Hz : float
        Natural frequency (Hz).
    k_mean_N_per_m : float
        Cycle-mean mesh stiffness with the scale ``s`` (N/m).
    jammed : bool
        Eq. (1) undefined somewhere on the path (thermal interference).
    min_net_deflection_m : float
        ``min_s (F R / (s k_EP) + c - c*)`` (m); ``<= 0`` where jammed.
    """

    f_n_Hz: float
    k_mean_N_per_m: float
    jammed: bool
    min_net_deflection_m: float


def mesh_mode(model: NaturalFrequencyModel, physics: TruePhysics, torque_Nm: float,
              temperature_C: float) -> MeshMode:
    """The mesh mode at one condition, ``s`` inside Eq. (1) (module notes).

    Parameters
    ----------
    model : NaturalFrequencyModel
    physics : TruePhysics
    torque_Nm : float
        Pinion torque (N m).
    temperature_C : float
        Bulk temperature (degC).

    Returns
    -------
    MeshMode
    """
    s = physics.stiffness_scale
    r = mesh_natural_frequency(model, torque_Nm, s * physics.closure_m(temperature_C),
                               s * physics.backlash_m, physics.chi)
    return MeshMode(f_n_Hz=float(r.f_n_Hz) * math.sqrt(s),
                    k_mean_N_per_m=float(r.k_mean_N_per_m) * s, jammed=bool(r.jammed),
                    min_net_deflection_m=float(r.min_net_deflection_m) / s)


@dataclass(frozen=True)
class HousingMode:
    """The housing mode: the same in every run.

    Attributes
    ----------
    f_n_Hz : float
    zeta : float
    """

    f_n_Hz: float = HOUSING_F_N_HZ
    zeta: float = HOUSING_ZETA


@dataclass(frozen=True)
class RunCondition:
    """One run of the design: id, pinion torque (N m) and bulk temperature (degC)."""

    run_id: str
    torque_Nm: float
    bulk_temperature_C: float


@dataclass(frozen=True)
class RunTruth:
    """What one run was made from.

    Attributes
    ----------
    run_id : str
    torque_Nm, bulk_temperature_C, oil_temperature_C, speed_rpm : float
        Conditions (N m, degC, degC, rpm); the oil temperature is the housing temperature of
        :func:`housing_temperature_C`.
    thermal_closure_m, critical_gap_m, margin_m : float
        ``Delta``, ``c*`` and ``c - c*`` at the run (m).
    regime : {'rises', 'falls', 'unchanged'}
    mesh : MeshMode
    mesh_zeta : float
        Damping ratio of the mesh mode (-).
    """

    run_id: str
    torque_Nm: float
    bulk_temperature_C: float
    oil_temperature_C: float
    speed_rpm: float
    thermal_closure_m: float
    critical_gap_m: float
    margin_m: float
    regime: Regime
    mesh: MeshMode
    mesh_zeta: float


@dataclass(frozen=True)
class RunUpTruth:
    """What the run-up run was made from (:mod:`rigtools.demo.runup`).

    In the run-up calibration's names (issue 20 contract).

    Attributes
    ----------
    run_id, gear_set : str
    model : str
        The SDOF model of the truth (``"vvms"``).
    torque_Nm : float
        Pinion torque (N m).
    zeta : float
        Damping ratio relative to ``k_ref = s kbar_F0`` (-).
    stiffness_scale, fluctuation_scale : float
        ``s`` and ``eps`` (-).
    backlash_m : float
        Total backlash ``2 b`` on the line of action (m).
    gains : dict of str to float
        ``G_c`` per channel (-).
    mesh_natural_frequency_Hz : float
        ``sqrt(s kbar_F0 / m_e) / 2 pi`` (Hz).
    model_natural_frequency_Hz : float
        The same with the model's own mean stiffness at ``T / s`` (Hz): the linear resonance.
    reference_stiffness_N_m : float
        ``kbar_F0``: error-free mean FVMS at the torque (N/m).
    equivalent_mass_kg : float
        ``m_e`` (kg).
    pinion_teeth : int
    jump_frequency_up_Hz, jump_frequency_down_Hz : float
        Mesh frequency of the jump of Arms in the up and in the down sweep (Hz): each
        direction's step out of the hysteresis band
        (:func:`rigtools.calibration.runup_forward.jump_frequencies`).
    contact_loss, backside_impact : bool
        Whether the drive flanks separate / the back flanks are reached anywhere on the path.
    speed_low_rpm, speed_high_rpm, ramp_duration_s : float
        The ramp.
    settling_time_s : float
        ``1 / (zeta omega_n)`` (s).
    crossing_ratio : float
        Time to cross the half-power band over the settling time (-): quasi-static when large.
    """

    run_id: str
    gear_set: str
    model: str
    torque_Nm: float
    zeta: float
    stiffness_scale: float
    fluctuation_scale: float
    backlash_m: float
    gains: dict[str, float]
    mesh_natural_frequency_Hz: float
    model_natural_frequency_Hz: float
    reference_stiffness_N_m: float
    equivalent_mass_kg: float
    pinion_teeth: int
    jump_frequency_up_Hz: float
    jump_frequency_down_Hz: float
    contact_loss: bool
    backside_impact: bool
    speed_low_rpm: float
    speed_high_rpm: float
    ramp_duration_s: float
    settling_time_s: float
    crossing_ratio: float

    def summary(self) -> dict[str, Any]:
        """The ``"runup"`` block of ``truth.json``.

        ``parameters`` and ``derived`` map the run-up calibration's names to ``{"value",
        "unit"}`` (``gain@<channel>``, ``mesh_natural_frequency_Hz``,
        ``mesh_natural_frequency_Hz@<run>``, ``jump_frequency_up_Hz@<run>`` /
        ``..._down_Hz@<run>``); ``conventions`` names ``k_ref`` and ``m_e``.
        """
        def q(value: float, unit: str) -> dict[str, Any]:
            return {"value": float(value), "unit": unit}

        r = self.run_id
        to_rpm = 60.0 / self.pinion_teeth
        return {
            "run_id": r, "gear_set": self.gear_set, "model": self.model,
            "torque_Nm": self.torque_Nm,
            "parameters": {
                "zeta": q(self.zeta, "1"),
                "mesh_stiffness_scale": q(self.stiffness_scale, "1"),
                "fluctuation_scale": q(self.fluctuation_scale, "1"),
                "backlash": q(self.backlash_m * 1e6, "um"),
                **{f"gain@{c}": q(g, "1") for c, g in self.gains.items()},
            },
            "derived": {
                "mesh_natural_frequency_Hz": q(self.mesh_natural_frequency_Hz, "Hz"),
                f"mesh_natural_frequency_Hz@{r}": q(self.model_natural_frequency_Hz, "Hz"),
                f"jump_frequency_up_Hz@{r}": q(self.jump_frequency_up_Hz, "Hz"),
                f"jump_frequency_down_Hz@{r}": q(self.jump_frequency_down_Hz, "Hz"),
            },
            "jump_speed_rpm": {"up": self.jump_frequency_up_Hz * to_rpm,
                               "down": self.jump_frequency_down_Hz * to_rpm},
            "contact_loss": self.contact_loss,
            "backside_impact": self.backside_impact,
            "backlash_identifiable": self.backside_impact,
            "ramp": {"speed_low_rpm": self.speed_low_rpm, "speed_high_rpm": self.speed_high_rpm,
                     "ramp_duration_s": self.ramp_duration_s, "shape": "linear up, then down, "
                     "no dwell", "settling_time_s": self.settling_time_s,
                     "crossing_over_settling": self.crossing_ratio},
            "conventions": {
                "reference_stiffness": "k_ref = s kbar_F0, kbar_F0 the error-free mean FVMS "
                                       "of the pair at the torque (models.stiffness.mesh_cycle)",
                "reference_stiffness_N_m": self.reference_stiffness_N_m,
                "equivalent_mass_kg": self.equivalent_mass_kg,
                "equivalent_mass": "models.geometry.inertia.pair_equivalent_mass",
                "mesh_natural_frequency_Hz": "sqrt(s kbar_F0 / m_e) / 2 pi",
                "mesh_natural_frequency_Hz@run": "sqrt(s kbar_model(T / s) / m_e) / 2 pi",
                "stiffness_scale": "every tooth compliance C / s: the mesh cycle at T / s "
                                   "with its stiffnesses times s",
                "backlash": "total 2b on the line of action",
                "gain": "housing acceleration = G_c x DTE acceleration (flat accelerance); "
                        "harmonic h: a = G_c (2 pi h f_m)^2 D_h",
                "jump_frequency": "each direction's step out of the hysteresis band (the "
                                  "other direction more than 10 % off) in log Arms of the "
                                  "model's periodic steady sweep along the ramp, from the "
                                  "widest band (geometric mean of the two points, Hz)",
                "pinion_teeth": self.pinion_teeth,
            },
        }


@dataclass(frozen=True)
class CampaignTruth:
    """The truth of a demo campaign.

    Attributes
    ----------
    physics : TruePhysics
    housing : HousingMode
    runs : tuple of RunTruth
    temperatures_C : tuple of float
        The campaign's bulk temperatures, ascending.
    runup : RunUpTruth or None
        The run-up run's truth, when the campaign has one.
    """

    physics: TruePhysics
    housing: HousingMode
    runs: tuple[RunTruth, ...]
    temperatures_C: tuple[float, ...]
    runup: RunUpTruth | None = None

    def run(self, run_id: str) -> RunTruth:
        """The run of that id."""
        for r in self.runs:
            if r.run_id == run_id:
                return r
        raise KeyError(run_id)

    def summary(self) -> dict[str, Any]:
        """The truth under the names of the calibration summary (issue 18 item 7).

        ``parameters`` and ``derived`` map a name to ``{"value", "unit"}``: ``backlash``
        (um), ``closure_coefficient``, ``stiffness_scale``, ``chi`` (1),
        ``critical_gap@<T>C``, ``thermal_closure@<T>C`` and ``margin@<T>C`` at each campaign
        temperature and ``margin@<run id>`` (um), ``flip_temperature_C`` (degC); ``runs``
        maps a run id to its ``regime``, ``mesh_mode_Hz`` and conditions; ``conventions``
        and ``housing_mode`` say how the numbers are meant; ``runup`` (when the campaign has
        a run-up) is :meth:`RunUpTruth.summary`.
        """
        p = self.physics
        um = 1e6

        def q(value: float, unit: str) -> dict[str, Any]:
            return {"value": float(value), "unit": unit}

        derived: dict[str, Any] = {}
        for t in self.temperatures_C:
            lab = temperature_label(t)
            derived[f"critical_gap@{lab}"] = q(p.critical_gap_m(t) * um, "um")
            derived[f"thermal_closure@{lab}"] = q(p.closure_m(t) * um, "um")
            derived[f"margin@{lab}"] = q((p.backlash_m - p.critical_gap_m(t)) * um, "um")
        for r in self.runs:
            derived[f"margin@{r.run_id}"] = q(r.margin_m * um, "um")
        derived["flip_temperature_C"] = q(p.flip_temperature_C, "degC")
        return {
            "parameters": {
                "backlash": q(p.backlash_m * um, "um"),
                "closure_coefficient": q(p.closure_coefficient, "1"),
                "stiffness_scale": q(p.stiffness_scale, "1"),
                "chi": q(p.chi, "1"),
            },
            "derived": derived,
            "runs": {r.run_id: {
                "regime": r.regime, "mesh_mode_Hz": r.mesh.f_n_Hz, "mesh_mode_zeta": r.mesh_zeta,
                "torque_Nm": r.torque_Nm, "bulk_temperature_C": r.bulk_temperature_C,
                "oil_temperature_C": r.oil_temperature_C, "speed_rpm": r.speed_rpm,
                "mesh_stiffness_N_per_m": r.mesh.k_mean_N_per_m,
                "min_net_deflection_um": r.mesh.min_net_deflection_m * um,
                "jammed": r.mesh.jammed} for r in self.runs},
            "conventions": {
                "equivalent_mass_kg": p.equivalent_mass_kg,
                "equivalent_mass": EQUIVALENT_MASS_CONVENTION,
                "k_EP_N_per_m": p.k_EP_mean_N_per_m,
                "stiffness_scale": "s multiplies k_EP inside Eq. (1): f_n = sqrt(s) "
                                   "f_n_model(T, s Delta, s c, chi)",
                "reference_temperature_C": p.reference_temperature_C,
                "chi": p.chi,
                "thermal_model": "linear",
                "closure_slope_um_per_K": p.closure_slope_m_per_K * um,
                "model_variant": "secant_path",
                "operating_temperature_C": max(self.temperatures_C),
            },
            "housing_mode": {"f_n_Hz": self.housing.f_n_Hz, "zeta": self.housing.zeta,
                             "moves_with_load_or_temperature": False},
            **({} if self.runup is None else {"runup": self.runup.summary()}),
        }


def campaign_truth(model: NaturalFrequencyModel, gear_set: GearSet,
                   conditions: Sequence[RunCondition], physics: TruePhysics, *,
                   housing: HousingMode | None = None, speed_rpm: float = SPEED_RPM,
                   mesh_zeta: float = MESH_ZETA) -> CampaignTruth:
    """Closure, critical gap, margin, regime and mesh mode of every run.

    Parameters
    ----------
    model : NaturalFrequencyModel
    gear_set : GearSet
    conditions : sequence of RunCondition
    physics : TruePhysics
    housing : HousingMode, optional
    speed_rpm : float
        Pinion speed of every run (rpm).
    mesh_zeta : float
        Damping ratio of the mesh mode.

    Returns
    -------
    CampaignTruth

    Raises
    ------
    ValueError
        A run would be jammed (the demo keeps every run out of that state), or two runs share
        an id.
    """
    ids = [c.run_id for c in conditions]
    if len(set(ids)) != len(ids):
        raise ValueError(f"`conditions` must have unique run ids, were {ids}")
    runs = []
    for c in conditions:
        t = float(c.bulk_temperature_C)
        mode = mesh_mode(model, physics, c.torque_Nm, t)
        if mode.jammed:
            raise ValueError(f"run {c.run_id!r} ({c.torque_Nm:g} N m, {t:g} degC) is jammed "
                             f"(net deflection {mode.min_net_deflection_m * 1e6:.2f} um): the "
                             "demo keeps every run out of the jammed state")
        d = physics.closure_m(t)
        code = int(stiffness_regime(physics.backlash_m, d, physics.chi))
        runs.append(RunTruth(
            run_id=c.run_id, torque_Nm=float(c.torque_Nm), bulk_temperature_C=t,
            oil_temperature_C=housing_temperature_C(gear_set.pair, t,
                                                    physics.closure_slope_m_per_K,
                                                    physics.reference_temperature_C),
            speed_rpm=float(speed_rpm), thermal_closure_m=d,
            critical_gap_m=physics.critical_gap_m(t),
            margin_m=physics.backlash_m - physics.critical_gap_m(t), regime=regime_name(code),
            mesh=mode, mesh_zeta=float(mesh_zeta)))
    temps = tuple(sorted({float(c.bulk_temperature_C) for c in conditions}))
    return CampaignTruth(physics=physics, housing=housing or HousingMode(), runs=tuple(runs),
                         temperatures_C=temps)
