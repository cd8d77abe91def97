r"""The ``[calibration]`` block of a campaign file: model, priors, sampler and tolerances.

Every key is optional; with no block at all the defaults below apply. A complete block::

    [calibration]
    model_variant = "secant_path"     # headline: secant_path | secant_mesh | tangent
    compare_variants = ["secant_path", "secant_mesh", "tangent"]   # PSIS-LOO; [] to skip
    thermal_model = "linear"          # or "expansion" (models.thermal with [thermal])
    jammed_model = "censored"         # or "double_flank"
    likelihood = "normal"             # or "student_t" (with student_t_dof)
    channels = ["accel_1", "accel_2"] # default: every channel of the table
    detection_probability = 0.9       # P(the mesh mode is among a run's peaks | in band)
    structural_modes = "auto"         # recurring peaks are background; "none": uniform only
    band_Hz = [500.0, 12000.0]        # band the peaks were searched in
    equivalent_mass_kg = 0.19         # or inertia_kg_m2 = [J1, J2], or disc_radius
    reference_temperature_C = 20.0    # default: [thermal], else 20 degC
    operating_temperature_C = 90.0    # default: the campaign's highest temperature
    temperature_sd_K = 2.0            # measurement error of the logged temperatures
    walkers = 32
    max_steps = 20000
    check_every = 100
    seed = 1
    map_starts = 8
    plan_torque_range_Nm = [20.0, 350.0]      # where `rigtools plan` may put new runs
    plan_temperature_range_C = [40.0, 100.0]

    [calibration.priors]              # in the parameter's unit (backlash in um)
    backlash = {dist = "uniform", lower = 0.0, upper = 100.0}
    closure_coefficient = {dist = "uniform", lower = 0.0, upper = 1.5}
    stiffness_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}
    model_error = {dist = "halfnormal", sd = 0.05}

    [calibration.fixed]               # fixed instead of sampled
    chi = 0.0285

    [calibration.tolerances]
    unchanged_band_um = 1.0           # |c - c*| below this counts as "unchanged"
    regime_probability = 0.9          # a run's regime is decided above this probability
    max_r_hat = 1.03                  # split-walker R-hat (see Tolerances)
    min_ess_bulk = 400
    acceptance_range = [0.15, 0.75]
    min_narrowing = 2.0               # posterior sd at most prior sd / this, else a warning

The SDOF run-up calibration (issue 20; :mod:`rigtools.calibration.runup_api`) is enabled by
naming its models, and configured in a sub-table (every key optional; the values below are
the defaults)::

    [calibration]
    models = ["fvms", "vvms", "lste"]     # default []: no run-up calibration

    [calibration.runup]
    max_speed_points = 100        # per direction (up, down), after binning a ramp
    min_speed_points = 20         # usable points per run below which the run is refused
    min_span = 1.3                # max/min mesh frequency a run-up must span
    steps_per_period = 64         # RK4 steps per mesh period of the model sweeps
    walkers = 32                  # default: [calibration] walkers
    max_steps = 20000             # default: [calibration] max_steps

    [calibration.runup.priors]    # the same prior tables as [calibration.priors]
    zeta = {dist = "lognormal", median = 0.03, sigma = 0.7}
    mesh_stiffness_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}
    fluctuation_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}  # sampled only if given
    backlash = {dist = "uniform", lower = 0.0, upper = 300.0}   # um, total 2b
    gain = {dist = "lognormal", median = 0.01, sigma = 3.0}     # must be lognormal
    model_error = {dist = "halfnormal", sd = 0.3}

    [calibration.runup.fixed]
    fluctuation_scale = 1.0       # the default; give it a prior (and no fixed value) to sample it

Run-up parameters (``[calibration.runup.priors]`` / ``.fixed``; the ``[calibration]``
tolerances, ``check_every``, ``seed`` and the equivalent-mass keys apply to it too):

``zeta`` (1)
    Damping ratio of the mesh relative to ``k_ref = s kbar_F0``: ``c = 2 zeta sqrt(k_ref m_e)``.
    Default lognormal(median 0.03, sigma 0.7): 95 % in [0.008, 0.12], the range of spur-gear
    mesh damping ratios in the literature.
``mesh_stiffness_scale`` (1)
    ``s``: every tooth compliance is ``C / s`` (the model at ``s`` is the mesh cycle at
    ``T / s`` with ``k_ref = s kbar_F0``, ``kbar_F0`` the mean error-free FVMS mesh stiffness
    of the pair); sets the mesh natural frequency ``sqrt(s kbar_F0 / m_e) / 2 pi``.
    Default lognormal(1, 0.3), cut to the cycle banks' range [0.3, 3].
``fluctuation_scale`` (1)
    Scale of the alternating part of the mesh stiffness (FVMS, VVMS) or of the loaded static
    transmission error (LSTE). Fixed at 1 by default: in the linear range only its product
    with the gains is identified.
``backlash`` (um)
    Total backlash ``2b`` on the line of action. Identified only through back-side impacts;
    default uniform(0, 300).
``gain`` (1)
    Prior of every channel gain ``G_c`` (housing acceleration over ``(2 pi h f_m)^2`` times
    the DTE harmonic), one per run and channel, marginalised in closed form: it must be an
    untruncated lognormal and cannot be fixed. Default lognormal(median 0.01, sigma 3): wide
    (95 % over five decades), so the data set the gains.
``model_error`` (1)
    Standard deviation of ``log Arms`` about the model: the relative model and measurement
    error of the curves. Default halfnormal(sd 0.3).

Parameters
----------
``backlash`` (um)
    Total backlash ``c`` on the line of action, as at the reference temperature.
``closure_coefficient`` (1)
    Scale ``kappa`` of the thermal closure. ``linear``: ``Delta(theta) = kappa xi_1 a'
    sin(alpha') (theta - theta_ref)``, i.e. the fraction of the closure that both gears uniformly
    at the bulk temperature would cause at the nominal centre distance (0.40 um/K for FZG-C);
    ``expansion``: the factor on :func:`models.thermal.thermal_deformation` of the gears at the
    bulk temperature under the campaign's :class:`~models.thermal.ThermalReference`.
``stiffness_scale`` (1)
    ``s``: the rig's elastic pair stiffness is ``s k_EP`` (Ishikawa's ``k_EP`` times ``s``,
    inside Eq. (1), so it also scales the elastic deflection the backlash competes with).
``model_error`` (1)
    Relative standard deviation of the model error of ``f_n``.
``chi`` (1)
    Thermoelastic correction factor of seed 000 (fixed at 0.0285 unless given a prior).
``temperature_offset@<run>`` (K)
    Only with ``temperature_sd_K``: the run's true bulk temperature minus the logged one,
    prior ``normal(0, temperature_sd_K)``.

Defaults, and why a test engineer can trust them on an FZG-type campaign
-------------------------------------------------------------------------
* ``backlash ~ uniform(0, 100) um``: seed 000 studies 0-100 um on FZG-C; flat, so the data
  decide anywhere a new or worn FZG-C pair can be.
* ``closure_coefficient ~ uniform(0, 1.5)``: 0 is a housing that grows with the gears (no
  closure), 1 gears uniformly at the bulk temperature in a housing at the reference
  temperature; seed 000's ``c* ~ 10 um`` at 90 degC from 20 degC is 0.37; up to 1.5 leaves
  room for flanks hotter than the bulk. Negative closures (a housing hotter than the gears)
  need an explicit prior.
* ``stiffness_scale ~ lognormal(median 1, sigma 0.3)``: Ishikawa's ``k_EP`` and the rig's
  stiffness differ by tens of percent (SEED-NOTES 3 and 19); 95 % in ``[0.56, 1.8]``.
* ``model_error ~ halfnormal(sd 0.05)``: a few percent of ``f_n`` is what an SDOF mesh model
  of a real rig misses; the data can push it up.
* ``chi = 0.0285`` fixed: seed 000's coupled-FE value; with the ``linear`` closure only
  ``(1 - chi) kappa`` is identified, so freeing it only widens the posterior.
* ``model_variant = "secant_path"`` (seed 000's model as ``models.thermal`` implements it) for
  the headline numbers, all three variants compared by PSIS-LOO.
* ``jammed_model = "censored"``: see :mod:`rigtools.calibration.likelihood`.
* Equivalent mass: the package's one convention (:mod:`models.geometry.inertia`): discs of the
  operating pitch radius with the gears' bores (0.3 of the reference radius when none is
  stated); ``equivalent_mass_kg``, ``inertia_kg_m2`` or ``disc_radius = "reference"`` override
  it. Backlash, critical gaps and margins in micrometres scale with ``1 / m_e``: give measured
  inertias when the gears carry hubs or shafts (:mod:`rigtools.calibration.derived`).
* Sampler: 32 walkers (at least ``2 ndim + 2``), at most 20000 steps, convergence checked every
  100 steps, 8 MAP starts, seed 1.

Errors name the key and its line (:class:`rigtools.errors.CampaignError`): an unknown key or
parameter, a value of the wrong type, ``lower >= upper``, ``sd <= 0`` (or ``sigma``), a fixed
value that its prior (or the parameter's domain) excludes; for the run-up: an unknown model
in ``models``, a ``gain`` prior that is not an untruncated lognormal or a fixed ``gain``,
``min_speed_points > max_speed_points``, ``min_span <= 1``, an odd number of walkers.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Final, Literal

from models.thermal import SEED_000_CHI
from rigtools.calibration.priors import DISTRIBUTIONS, Prior, prior_from_mapping
from rigtools.errors import CampaignError

__all__ = [
    "JAMMED_TREATMENTS",
    "LIKELIHOODS",
    "PARAMETERS",
    "RUNUP_MODELS",
    "RUNUP_PARAMETERS",
    "THERMAL_MODELS",
    "VARIANTS",
    "CalibrationConfig",
    "JammedTreatment",
    "LikelihoodKind",
    "ParameterInfo",
    "ParameterSpec",
    "RunUpModel",
    "RunUpSettings",
    "ThermalModel",
    "Tolerances",
    "Variant",
    "default_config",
    "parse_calibration_block",
]

Variant = Literal["secant_path", "secant_mesh", "tangent"]
ThermalModel = Literal["linear", "expansion"]
JammedTreatment = Literal["censored", "double_flank"]
LikelihoodKind = Literal["normal", "student_t"]
RunUpModel = Literal["fvms", "vvms", "lste"]
#: The model variants (issue 18 item 3), headline default first.
VARIANTS: Final[tuple[Variant, ...]] = ("secant_path", "secant_mesh", "tangent")
THERMAL_MODELS: Final[tuple[ThermalModel, ...]] = ("linear", "expansion")
JAMMED_TREATMENTS: Final[tuple[JammedTreatment, ...]] = ("censored", "double_flank")
LIKELIHOODS: Final[tuple[LikelihoodKind, ...]] = ("normal", "student_t")
#: The SDOF mesh-stiffness models of the run-up calibration (issue 20).
RUNUP_MODELS: Final[tuple[RunUpModel, ...]] = ("fvms", "vvms", "lste")


@dataclass(frozen=True)
class ParameterInfo:
    """What a calibration parameter is.

    Attributes
    ----------
    unit : str
        Unit of its values in priors, fixed values and the summary.
    domain : (float, float)
        Values the physics accepts (a prior is cut to it, a fixed value must lie in it).
    default : Prior or float
        Default prior, or the default fixed value.
    description : str
    """

    unit: str
    domain: tuple[float, float]
    default: Prior | float
    description: str


#: The global parameters, in sampling order.
PARAMETERS: Final[dict[str, ParameterInfo]] = {
    "backlash": ParameterInfo(
        "um", (0.0, math.inf), prior_from_mapping({"dist": "uniform", "lower": 0.0,
                                                   "upper": 100.0}),
        "total backlash c on the line of action (at the reference temperature)"),
    "closure_coefficient": ParameterInfo(
        "1", (-math.inf, math.inf), prior_from_mapping({"dist": "uniform", "lower": 0.0,
                                                        "upper": 1.5}),
        "scale of the thermal closure (fraction of free uniform expansion for 'linear')"),
    "stiffness_scale": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 1.0,
                                                  "sigma": 0.3}),
        "s: the rig's elastic pair stiffness over Ishikawa's k_EP"),
    "model_error": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "halfnormal", "sd": 0.05}),
        "relative standard deviation of the model error of f_n"),
    "chi": ParameterInfo("1", (0.0, 1.0), SEED_000_CHI,
                         "seed 000's thermoelastic correction factor"),
}

#: The parameters of the run-up (SDOF Arms) calibration, in sampling order. ``gain`` is the
#: prior of every channel gain ``G_c``; the gains are marginalised, never sampled, so it must
#: be log-normal and cannot be fixed.
RUNUP_PARAMETERS: Final[dict[str, ParameterInfo]] = {
    "zeta": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 0.03,
                                                  "sigma": 0.7}),
        "damping ratio of the mesh, relative to k_ref = s kbar_F0"),
    "mesh_stiffness_scale": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 1.0,
                                                  "sigma": 0.3}),
        "s: mesh compliance C/s (the model at s is the mesh cycle at T/s, k_ref = s kbar_F0)"),
    "fluctuation_scale": ParameterInfo(
        "1", (0.0, math.inf), 1.0,  # fixed by default: only G eps is identified when linear
        "scale of the alternating part of the mesh stiffness (FVMS, VVMS) or of the loaded "
        "static transmission error (LSTE)"),
    "backlash": ParameterInfo(
        "um", (0.0, math.inf), prior_from_mapping({"dist": "uniform", "lower": 0.0,
                                                   "upper": 300.0}),
        "total backlash 2b on the line of action"),
    "model_error": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "halfnormal", "sd": 0.3}),
        "sigma of log Arms: relative model error of the Arms curves"),
    "gain": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 0.01,
                                                  "sigma": 3.0}),
        "G_c: housing acceleration over (2 pi h f_m)^2 DTE, per channel (marginalised)"),
}

_TOP_KEYS: Final = (
    "model_variant", "compare_variants", "thermal_model", "jammed_model", "likelihood",
    "student_t_dof", "channels", "detection_probability", "structural_modes", "band_Hz",
    "equivalent_mass_kg", "inertia_kg_m2", "disc_radius", "reference_temperature_C",
    "operating_temperature_C", "temperature_sd_K", "walkers", "max_steps", "check_every",
    "seed", "map_starts", "plan_torque_range_Nm", "plan_temperature_range_C", "priors", "fixed",
    "tolerances", "models", "runup",
)
_RUNUP_KEYS: Final = ("max_speed_points", "min_speed_points", "min_span", "steps_per_period",
                       "walkers", "max_steps", "priors", "fixed")
_TOLERANCE_KEYS: Final = ("unchanged_band_um", "regime_probability", "max_r_hat",
                          "min_ess_bulk", "acceptance_range", "min_narrowing")


@dataclass(frozen=True)
class ParameterSpec:
    """One global parameter as configured: a prior (sampled) or a fixed value.

    Attributes
    ----------
    name : str
    unit : str
    prior : Prior or None
        None when fixed.
    fixed : float or None
        The fixed value, in ``unit``.
    """

    name: str
    unit: str
    prior: Prior | None
    fixed: float | None

    @property
    def free(self) -> bool:
        """Sampled (has a prior and no fixed value)."""
        return self.fixed is None


@dataclass(frozen=True)
class Tolerances:
    """Pass/fail tolerances of a calibration (``[calibration.tolerances]``).

    Attributes
    ----------
    unchanged_band_um : float
        ``|c - c*|`` below which a run counts as ``unchanged`` (um).
    regime_probability : float
        A run's regime is decided when its posterior probability exceeds this.
    max_r_hat : float
        Largest acceptable split-walker R-hat. 1.03, not the 1.01 recommended for independent
        chains: emcee's walkers are chains only about 50 tau long when the autocorrelation rule
        stops them, each with a few dozen independent draws, and on a perfectly sampled
        two-dimensional Gaussian the largest split-walker R-hat at that point is already 1.004
        to 1.010 (12 seeds, 24 walkers); 1.03 flags walkers that disagree (a stranded walker
        or an unmixed mode gave 1.09 and 1.4 in tests), not that noise.
    min_ess_bulk : float
        Smallest acceptable bulk effective sample size.
    acceptance_range : (float, float)
        Acceptable mean acceptance fraction of the walkers.
    min_narrowing : float
        A posterior should be at least this many times narrower (sd) than its prior.
    """

    unchanged_band_um: float = 1.0
    regime_probability: float = 0.9
    max_r_hat: float = 1.03
    min_ess_bulk: float = 400.0
    acceptance_range: tuple[float, float] = (0.15, 0.75)
    min_narrowing: float = 2.0


@dataclass(frozen=True)
class RunUpSettings:
    """The ``[calibration.runup]`` table: data preparation and sampler of the run-up fit.

    Attributes
    ----------
    max_speed_points : int
        Points per direction (up, down) after binning a ramp (median per equal-log-f bin).
    min_speed_points : int
        Usable points per run below which the run is refused.
    min_span : float
        Smallest ratio max/min of the mesh frequency a run-up must span.
    steps_per_period : int
        Integration steps per mesh period of the model sweeps.
    walkers : int or None
        Walkers of the ensemble sampler; None: the ``[calibration]`` setting.
    max_steps : int or None
        Largest number of sampler steps; None: the ``[calibration]`` setting.
    parameters : tuple of ParameterSpec
        In :data:`RUNUP_PARAMETERS` order (``gain`` always has its log-normal prior).
    """

    max_speed_points: int = 100
    min_speed_points: int = 20
    min_span: float = 1.3
    steps_per_period: int = 64
    walkers: int | None = None
    max_steps: int | None = None
    parameters: tuple[ParameterSpec, ...] = field(
        default_factory=lambda: _default_runup_parameters())

    def parameter(self, name: str) -> ParameterSpec:
        """The spec of run-up parameter ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def free_parameters(self) -> tuple[str, ...]:
        """Names of the sampled run-up parameters (``gain`` excluded: marginalised)."""
        return tuple(p.name for p in self.parameters if p.free and p.name != "gain")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form in the keys of the TOML table (unset keys left out)."""
        d: dict[str, Any] = {
            "max_speed_points": self.max_speed_points,
            "min_speed_points": self.min_speed_points,
            "min_span": self.min_span,
            "steps_per_period": self.steps_per_period,
            "walkers": self.walkers,
            "max_steps": self.max_steps,
            "priors": {p.name: p.prior.to_dict() for p in self.parameters
                       if p.prior is not None and p.free},
            "fixed": {p.name: p.fixed for p in self.parameters if not p.free},
        }
        return {k: v for k, v in d.items() if v is not None}


@dataclass(frozen=True)
class CalibrationConfig:
    """The resolved ``[calibration]`` block (module docstring for every key and default).

    Attributes
    ----------
    model_variant : {"secant_path", "secant_mesh", "tangent"}
        Variant of the headline numbers.
    compare_variants : tuple of str
        Variants fitted and compared by PSIS-LOO (the headline one always among them when
        not empty).
    thermal_model : {"linear", "expansion"}
    jammed_model : {"censored", "double_flank"}
    likelihood : {"normal", "student_t"}
    student_t_dof : float
    channels : tuple of str
        Channels whose peaks are candidates; empty: all.
    detection_probability : float
        Probability that the mesh mode is among a run's peaks when it lies in the band.
    structural_modes : {"auto", "none"}
        Recurring peaks are taken as structural modes of the background
        (:mod:`rigtools.calibration.data`), or the background is uniform.
    band_Hz : (float, float) or None
        Band the peaks were searched in; None: from the data (module ``data``).
    equivalent_mass_kg : float or None
    inertia_kg_m2 : (float, float) or None
    disc_radius : {"operating", "reference"}
    reference_temperature_C : float or None
    operating_temperature_C : float or None
    temperature_sd_K : float or None
    walkers : int or None
        None: ``max(32, 2 ndim + 2)`` rounded up to even.
    max_steps, check_every, seed, map_starts : int
    plan_torque_range_Nm, plan_temperature_range_C : (float, float) or None
        Where :func:`rigtools.calibration.plan.plan_next_runs` may propose runs; None: the
        campaign's torque range, and its temperature range extended to the operating
        temperature.
    parameters : tuple of ParameterSpec
        In :data:`PARAMETERS` order.
    tolerances : Tolerances
    models : tuple of {"fvms", "vvms", "lste"}
        SDOF models calibrated against the Arms run-up curves (empty: no run-up
        calibration).
    runup : RunUpSettings
        The ``[calibration.runup]`` table.
    """

    model_variant: Variant = "secant_path"
    compare_variants: tuple[Variant, ...] = VARIANTS
    thermal_model: ThermalModel = "linear"
    jammed_model: JammedTreatment = "censored"
    likelihood: LikelihoodKind = "normal"
    student_t_dof: float = 4.0
    channels: tuple[str, ...] = ()
    detection_probability: float = 0.9
    structural_modes: Literal["auto", "none"] = "auto"
    band_Hz: tuple[float, float] | None = None
    equivalent_mass_kg: float | None = None
    inertia_kg_m2: tuple[float, float] | None = None
    disc_radius: Literal["operating", "reference"] = "operating"
    reference_temperature_C: float | None = None
    operating_temperature_C: float | None = None
    temperature_sd_K: float | None = None
    walkers: int | None = None
    max_steps: int = 20000
    check_every: int = 100
    seed: int = 1
    map_starts: int = 8
    plan_torque_range_Nm: tuple[float, float] | None = None
    plan_temperature_range_C: tuple[float, float] | None = None
    parameters: tuple[ParameterSpec, ...] = field(default_factory=lambda: _default_parameters())
    tolerances: Tolerances = field(default_factory=Tolerances)
    models: tuple[RunUpModel, ...] = ()
    runup: RunUpSettings = field(default_factory=RunUpSettings)

    def parameter(self, name: str) -> ParameterSpec:
        """The spec of parameter ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def free_parameters(self) -> tuple[str, ...]:
        """Names of the sampled global parameters, in order."""
        return tuple(p.name for p in self.parameters if p.free)

    def with_variant(self, variant: Variant) -> CalibrationConfig:
        """The same configuration with another headline variant."""
        return replace(self, model_variant=variant)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (recorded in every output), in the keys of the TOML block.

        Unset optional keys are left out, so the result parses back to the same config.
        """
        t = self.tolerances
        d = {
            "model_variant": self.model_variant,
            "compare_variants": list(self.compare_variants),
            "thermal_model": self.thermal_model,
            "jammed_model": self.jammed_model,
            "likelihood": self.likelihood,
            "student_t_dof": self.student_t_dof,
            "channels": list(self.channels),
            "detection_probability": self.detection_probability,
            "structural_modes": self.structural_modes,
            "band_Hz": None if self.band_Hz is None else list(self.band_Hz),
            "equivalent_mass_kg": self.equivalent_mass_kg,
            "inertia_kg_m2": None if self.inertia_kg_m2 is None else list(self.inertia_kg_m2),
            "disc_radius": self.disc_radius,
            "reference_temperature_C": self.reference_temperature_C,
            "operating_temperature_C": self.operating_temperature_C,
            "temperature_sd_K": self.temperature_sd_K,
            "walkers": self.walkers,
            "max_steps": self.max_steps,
            "check_every": self.check_every,
            "seed": self.seed,
            "map_starts": self.map_starts,
            "plan_torque_range_Nm": (None if self.plan_torque_range_Nm is None
                                     else list(self.plan_torque_range_Nm)),
            "plan_temperature_range_C": (None if self.plan_temperature_range_C is None
                                         else list(self.plan_temperature_range_C)),
            "priors": {p.name: p.prior.to_dict() for p in self.parameters
                       if p.prior is not None and p.free},
            "fixed": {p.name: p.fixed for p in self.parameters if not p.free},
            "tolerances": {"unchanged_band_um": t.unchanged_band_um,
                           "regime_probability": t.regime_probability,
                           "max_r_hat": t.max_r_hat, "min_ess_bulk": t.min_ess_bulk,
                           "acceptance_range": list(t.acceptance_range),
                           "min_narrowing": t.min_narrowing},
            "models": list(self.models),
            "runup": self.runup.to_dict(),
        }
        return {k: v for k, v in d.items() if (v is not None and v != [])
                or k == "compare_variants"}


def _default_parameters() -> tuple[ParameterSpec, ...]:
    out = []
    for name, info in PARAMETERS.items():
        if isinstance(info.default, Prior):
            out.append(ParameterSpec(name, info.unit, info.default, None))
        else:
            out.append(ParameterSpec(name, info.unit, None, float(info.default)))
    return tuple(out)


def _default_runup_parameters() -> tuple[ParameterSpec, ...]:
    out = []
    for name, info in RUNUP_PARAMETERS.items():
        if isinstance(info.default, Prior):
            out.append(ParameterSpec(name, info.unit, info.default, None))
        else:
            out.append(ParameterSpec(name, info.unit, None, float(info.default)))
    return tuple(out)


def default_config() -> CalibrationConfig:
    """The configuration used when a campaign has no ``[calibration]`` block."""
    return CalibrationConfig()


# --------------------------------------------------------------------------------------------
# parsing


class _Parser:
    """Checks one block, raising :class:`CampaignError` with the key and its line."""

    def __init__(self, source: str, line_of: Callable[[str], int | None]) -> None:
        self.source = source
        self.line_of = line_of

    def error(self, key: str, expected: str, found: str) -> CampaignError:
        line = self.line_of(key)
        return CampaignError(self.source, f"line {line}" if line else None, expected, found)

    def unknown(self, key: str, name: str, allowed: Sequence[str], what: str) -> CampaignError:
        close = difflib.get_close_matches(name, list(allowed), n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        return self.error(key, f"{what}: {', '.join(allowed)}", f"unknown {name!r}{hint}")

    def table(self, key: str, value: Any) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.error(key, f"a table for {key}", repr(value))
        return value

    def number(self, key: str, value: Any, *, minimum: float | None = None,
               exclusive: bool = False, maximum: float | None = None,
               exclusive_max: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"a number for {key}", repr(value))
        v = float(value)
        if not math.isfinite(v):
            raise self.error(key, f"a finite number for {key}", repr(value))
        if minimum is not None and (v <= minimum if exclusive else v < minimum):
            raise self.error(key, f"{key} {'>' if exclusive else '>='} {minimum:g}", f"{v:g}")
        if maximum is not None and (v >= maximum if exclusive_max else v > maximum):
            raise self.error(key, f"{key} {'<' if exclusive_max else '<='} {maximum:g}",
                             f"{v:g}")
        return v

    def integer(self, key: str, value: Any, *, minimum: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"an integer for {key}", repr(value))
        if value < minimum:
            raise self.error(key, f"{key} >= {minimum}", str(value))
        return int(value)

    def choice(self, key: str, value: Any, allowed: Sequence[str]) -> str:
        if not isinstance(value, str) or value not in allowed:
            raise self.error(key, f"one of {', '.join(repr(a) for a in allowed)} for {key}",
                             repr(value))
        return value

    def pair(self, key: str, value: Any, *, positive: bool = True) -> tuple[float, float]:
        if not isinstance(value, list | tuple) or len(value) != 2:
            raise self.error(key, f"two numbers [low, high] for {key}", repr(value))
        lo, hi = (self.number(key, v, minimum=0.0, exclusive=positive) for v in value)
        if not lo < hi:
            raise self.error(key, f"{key} = [low, high] with low < high", repr(list(value)))
        return lo, hi

    def strings(self, key: str, value: Any) -> tuple[str, ...]:
        if not isinstance(value, list | tuple) or not all(
                isinstance(v, str) and v for v in value):
            raise self.error(key, f"a list of names for {key}", repr(value))
        if len(set(value)) != len(value):
            raise self.error(key, f"names without repeats for {key}", repr(list(value)))
        return tuple(value)

    # -- priors ---------------------------------------------------------------------------
    def prior(self, name: str, spec: Any, *, where: str = "calibration.priors",
              table: Mapping[str, ParameterInfo] = PARAMETERS) -> Prior:
        key = f"{where}.{name}"
        spec = self.table(key, spec)
        if "dist" not in spec:
            raise self.error(key, f"key 'dist' ({', '.join(DISTRIBUTIONS)}) in {key}", "none")
        dist = self.choice(f"{key}.dist", spec["dist"], list(DISTRIBUTIONS))
        required, optional = DISTRIBUTIONS[dist]
        for k in spec:
            if k != "dist" and k not in required + optional:
                raise self.unknown(f"{key}.{k}", k, ("dist", *required, *optional),
                                   f"a key of a {dist} prior in {key}")
        for k in required:
            if k not in spec:
                raise self.error(key, f"key {k!r} of a {dist} prior in {key}", "none")
        values = {k: self.number(f"{key}.{k}", spec[k]) for k in spec if k != "dist"}
        for k in ("sd", "sigma", "median"):
            if k in values and not values[k] > 0:
                raise self.error(f"{key}.{k}", f"{k} > 0 in {key}", f"{k} = {values[k]:g}")
        if "lower" in values and "upper" in values and not values["lower"] < values["upper"]:
            raise self.error(f"{key}.lower", f"lower < upper in {key}",
                             f"lower = {values['lower']:g}, upper = {values['upper']:g}")
        lo_dom, hi_dom = table[name].domain
        natural_lo = {"lognormal": 0.0, "halfnormal": 0.0}.get(dist, -math.inf)
        lo = max(values.get("lower", natural_lo), lo_dom, natural_lo)
        hi = min(values.get("upper", math.inf), hi_dom)
        if not lo < hi:
            raise self.error(key, f"a prior for {name} that admits values in its domain "
                             f"[{lo_dom:g}, {hi_dom:g}] {table[name].unit}",
                             f"support [{values.get('lower', natural_lo):g}, "
                             f"{values.get('upper', math.inf):g}]")
        if "lower" in values and dist == "lognormal" and values["lower"] < 0:
            raise self.error(f"{key}.lower", f"lower >= 0 for a lognormal prior in {key}",
                             f"lower = {values['lower']:g}")
        built = dict(values, dist=dist)
        if (lo, hi) != (values.get("lower", natural_lo), values.get("upper", math.inf)):
            built.update(lower=lo, upper=hi)
            if dist == "uniform" and not math.isfinite(hi):
                raise self.error(key, f"finite bounds for {name}", f"[{lo:g}, {hi:g}]")
            if dist == "halfnormal":
                built.pop("lower", None)
        try:
            return prior_from_mapping(built)
        except ValueError as exc:  # every case is checked above; kept as a safety net
            raise self.error(key, f"a valid prior for {name}", str(exc)) from None


def parse_calibration_block(
    block: Mapping[str, Any] | None,
    *,
    source: str,
    line_of: Callable[[str], int | None],
) -> CalibrationConfig:
    """Validate a campaign's ``[calibration]`` table and resolve it with the defaults.

    Parameters
    ----------
    block : mapping or None
        The table as ``tomllib`` parsed it (``doc.get("calibration")``); None for the defaults.
    source : str
        The campaign file, for the messages.
    line_of : callable
        ``line_of("calibration.priors.backlash.lower")`` returns the line of that key (or of
        its nearest enclosing table) in the file, or None when unknown. Keys are dotted paths
        from the top of the file.

    Returns
    -------
    CalibrationConfig

    Raises
    ------
    CampaignError
        An unknown key or parameter, a wrong type, ``lower >= upper``, ``sd <= 0``, a fixed
        value its prior or domain excludes, an unknown variant; the message names the key and
        its line.

    Examples
    --------
    >>> cfg = parse_calibration_block({"walkers": 40, "priors": {"backlash": {
    ...     "dist": "uniform", "lower": 0.0, "upper": 60.0}}}, source="c.toml",
    ...     line_of=lambda key: None)
    >>> cfg.walkers, cfg.parameter("backlash").prior.describe()
    (40, 'uniform(0, 60)')
    """
    if block is None:
        return default_config()
    p = _Parser(source, line_of)
    block = p.table("calibration", block)
    for k in block:
        if k not in _TOP_KEYS:
            raise p.unknown(f"calibration.{k}", k, _TOP_KEYS, "a key of [calibration]")
    kw: dict[str, Any] = {}

    def key(k: str) -> str:
        return f"calibration.{k}"

    if "model_variant" in block:
        kw["model_variant"] = p.choice(key("model_variant"), block["model_variant"], VARIANTS)
    if "compare_variants" in block:
        names = p.strings(key("compare_variants"), block["compare_variants"])
        for n in names:
            p.choice(key("compare_variants"), n, VARIANTS)
        kw["compare_variants"] = names
    if "thermal_model" in block:
        kw["thermal_model"] = p.choice(key("thermal_model"), block["thermal_model"],
                                       THERMAL_MODELS)
    if "jammed_model" in block:
        kw["jammed_model"] = p.choice(key("jammed_model"), block["jammed_model"],
                                      JAMMED_TREATMENTS)
    if "likelihood" in block:
        kw["likelihood"] = p.choice(key("likelihood"), block["likelihood"], LIKELIHOODS)
    if "student_t_dof" in block:
        kw["student_t_dof"] = p.number(key("student_t_dof"), block["student_t_dof"],
                                       minimum=0.0, exclusive=True)
    if "channels" in block:
        kw["channels"] = p.strings(key("channels"), block["channels"])
        if not kw["channels"]:
            raise p.error(key("channels"), "at least one channel name", "[]")
    if "detection_probability" in block:
        kw["detection_probability"] = p.number(
            key("detection_probability"), block["detection_probability"], minimum=0.0,
            exclusive=True, maximum=1.0, exclusive_max=True)
    if "structural_modes" in block:
        kw["structural_modes"] = p.choice(key("structural_modes"), block["structural_modes"],
                                          ("auto", "none"))
    if "band_Hz" in block:
        kw["band_Hz"] = p.pair(key("band_Hz"), block["band_Hz"])
    if "equivalent_mass_kg" in block and "inertia_kg_m2" in block:
        raise p.error(key("inertia_kg_m2"), "either equivalent_mass_kg or inertia_kg_m2",
                      "both")
    if "equivalent_mass_kg" in block:
        kw["equivalent_mass_kg"] = p.number(key("equivalent_mass_kg"),
                                            block["equivalent_mass_kg"], minimum=0.0,
                                            exclusive=True)
    if "inertia_kg_m2" in block:
        v = block["inertia_kg_m2"]
        if not isinstance(v, list | tuple) or len(v) != 2:
            raise p.error(key("inertia_kg_m2"), "[J_pinion, J_wheel] (kg m^2)", repr(v))
        kw["inertia_kg_m2"] = tuple(p.number(key("inertia_kg_m2"), x, minimum=0.0,
                                             exclusive=True) for x in v)
    if "disc_radius" in block:
        kw["disc_radius"] = p.choice(key("disc_radius"), block["disc_radius"],
                                     ("operating", "reference"))
    for k in ("reference_temperature_C", "operating_temperature_C"):
        if k in block:
            kw[k] = p.number(key(k), block[k], minimum=-273.15, exclusive=True)
    if "temperature_sd_K" in block:
        kw["temperature_sd_K"] = p.number(key("temperature_sd_K"), block["temperature_sd_K"],
                                          minimum=0.0, exclusive=True)
    if "walkers" in block:
        w = p.integer(key("walkers"), block["walkers"], minimum=4)
        if w % 2:
            raise p.error(key("walkers"), "an even number of walkers", str(w))
        kw["walkers"] = w
    if "max_steps" in block:
        kw["max_steps"] = p.integer(key("max_steps"), block["max_steps"], minimum=1)
    if "check_every" in block:
        kw["check_every"] = p.integer(key("check_every"), block["check_every"], minimum=10)
    if "seed" in block:
        kw["seed"] = p.integer(key("seed"), block["seed"], minimum=0)
    if "map_starts" in block:
        kw["map_starts"] = p.integer(key("map_starts"), block["map_starts"], minimum=1)
    if "plan_torque_range_Nm" in block:
        kw["plan_torque_range_Nm"] = p.pair(key("plan_torque_range_Nm"),
                                            block["plan_torque_range_Nm"])
    if "plan_temperature_range_C" in block:
        v = block["plan_temperature_range_C"]
        if not isinstance(v, list | tuple) or len(v) != 2:
            raise p.error(key("plan_temperature_range_C"), "two numbers [low, high] for "
                          "calibration.plan_temperature_range_C", repr(v))
        lo, hi = (p.number(key("plan_temperature_range_C"), x, minimum=-273.15,
                           exclusive=True) for x in v)
        if not lo <= hi:
            raise p.error(key("plan_temperature_range_C"), "[low, high] with low <= high",
                          repr(list(v)))
        kw["plan_temperature_range_C"] = (lo, hi)
    if "tolerances" in block:
        kw["tolerances"] = _tolerances(p, p.table(key("tolerances"), block["tolerances"]))
    if "models" in block:
        names = p.strings(key("models"), block["models"])
        for n in names:
            p.choice(key("models"), n, RUNUP_MODELS)
        kw["models"] = names
    if "runup" in block:
        kw["runup"] = _runup(p, p.table(key("runup"), block["runup"]))
    kw["parameters"] = _parameters(p, block.get("priors"), block.get("fixed"))
    cfg = CalibrationConfig(**kw)
    if cfg.compare_variants and cfg.model_variant not in cfg.compare_variants:
        raise p.error(key("compare_variants"),
                      f"the headline model_variant {cfg.model_variant!r} among the compared "
                      "variants (or [] for no comparison)", repr(list(cfg.compare_variants)))
    return cfg


def _tolerances(p: _Parser, t: Mapping[str, Any]) -> Tolerances:
    for k in t:
        if k not in _TOLERANCE_KEYS:
            raise p.unknown(f"calibration.tolerances.{k}", k, _TOLERANCE_KEYS,
                            "a key of [calibration.tolerances]")
    d = Tolerances()
    kw: dict[str, Any] = {}

    def key(k: str) -> str:
        return f"calibration.tolerances.{k}"

    if "unchanged_band_um" in t:
        kw["unchanged_band_um"] = p.number(key("unchanged_band_um"), t["unchanged_band_um"],
                                           minimum=0.0)
    if "regime_probability" in t:
        kw["regime_probability"] = p.number(key("regime_probability"), t["regime_probability"],
                                            minimum=0.5, exclusive=True, maximum=1.0,
                                            exclusive_max=True)
    if "max_r_hat" in t:
        kw["max_r_hat"] = p.number(key("max_r_hat"), t["max_r_hat"], minimum=1.0,
                                   exclusive=True)
    if "min_ess_bulk" in t:
        kw["min_ess_bulk"] = p.number(key("min_ess_bulk"), t["min_ess_bulk"], minimum=0.0,
                                      exclusive=True)
    if "acceptance_range" in t:
        lo, hi = p.pair(key("acceptance_range"), t["acceptance_range"])
        if hi >= 1.0:
            raise p.error(key("acceptance_range"), "bounds inside (0, 1)",
                          repr(list(t["acceptance_range"])))
        kw["acceptance_range"] = (lo, hi)
    if "min_narrowing" in t:
        kw["min_narrowing"] = p.number(key("min_narrowing"), t["min_narrowing"], minimum=1.0)
    return replace(d, **kw)


def _parameter_specs(p: _Parser, priors: Any, fixed: Any, *,
                     table: Mapping[str, ParameterInfo], where: str,
                     check: Callable[[str, Prior | None], None] | None = None,
                     ) -> tuple[ParameterSpec, ...]:
    """``[<where>.priors]`` and ``[<where>.fixed]`` resolved over ``table``, in its order.

    ``check(name, prior)`` may refuse a prior the caller cannot use (a :class:`CampaignError`).
    """
    pwhere, fwhere = f"{where}.priors", f"{where}.fixed"
    priors = {} if priors is None else p.table(pwhere, priors)
    fixed = {} if fixed is None else p.table(fwhere, fixed)
    names = list(table)
    for given, at in ((priors, pwhere), (fixed, fwhere)):
        for n in given:
            if n not in table:
                raise p.unknown(f"{at}.{n}", n, names, f"a parameter name in [{at}]")
    out = []
    for name, info in table.items():
        prior = p.prior(name, priors[name], where=pwhere, table=table) if name in priors else None
        if check is not None:
            check(name, prior)
        if name in fixed:
            key = f"{fwhere}.{name}"
            v = p.number(key, fixed[name])
            lo, hi = info.domain
            if not lo <= v <= hi:
                raise p.error(key, f"a fixed {name} in its domain [{lo:g}, {hi:g}] "
                              f"{info.unit}", f"{v:g}")
            if prior is not None and not prior.contains(v):
                raise p.error(key, f"a fixed {name} that its prior {prior.describe()} "
                              f"({pwhere}.{name}) admits", f"{v:g}")
            out.append(ParameterSpec(name, info.unit, prior, v))
        elif prior is not None:
            out.append(ParameterSpec(name, info.unit, prior, None))
        elif isinstance(info.default, Prior):
            out.append(ParameterSpec(name, info.unit, info.default, None))
        else:
            out.append(ParameterSpec(name, info.unit, None, float(info.default)))
    return tuple(out)


def _parameters(p: _Parser, priors: Any, fixed: Any) -> tuple[ParameterSpec, ...]:
    return _parameter_specs(p, priors, fixed, table=PARAMETERS, where="calibration")


def _runup(p: _Parser, t: Mapping[str, Any]) -> RunUpSettings:
    for k in t:
        if k not in _RUNUP_KEYS:
            raise p.unknown(f"calibration.runup.{k}", k, _RUNUP_KEYS,
                            "a key of [calibration.runup]")
    kw: dict[str, Any] = {}

    def key(k: str) -> str:
        return f"calibration.runup.{k}"

    if "max_speed_points" in t:
        kw["max_speed_points"] = p.integer(key("max_speed_points"), t["max_speed_points"],
                                           minimum=3)
    if "min_speed_points" in t:
        kw["min_speed_points"] = p.integer(key("min_speed_points"), t["min_speed_points"],
                                           minimum=3)
    if "min_span" in t:
        kw["min_span"] = p.number(key("min_span"), t["min_span"], minimum=1.0, exclusive=True)
    if "steps_per_period" in t:
        kw["steps_per_period"] = p.integer(key("steps_per_period"), t["steps_per_period"],
                                           minimum=16)
    if "walkers" in t:
        w = p.integer(key("walkers"), t["walkers"], minimum=4)
        if w % 2:
            raise p.error(key("walkers"), "an even number of walkers", str(w))
        kw["walkers"] = w
    if "max_steps" in t:
        kw["max_steps"] = p.integer(key("max_steps"), t["max_steps"], minimum=1)
    if kw.get("min_speed_points", 20) > kw.get("max_speed_points", 100):
        raise p.error(key("min_speed_points"), "min_speed_points <= max_speed_points",
                      f"{kw.get('min_speed_points', 20)} > {kw.get('max_speed_points', 100)}")
    kw["parameters"] = _runup_parameters(p, t.get("priors"), t.get("fixed"))
    return RunUpSettings(**kw)


def _runup_parameters(p: _Parser, priors: Any, fixed: Any) -> tuple[ParameterSpec, ...]:
    where = "calibration.runup"
    if fixed is not None and "gain" in p.table(f"{where}.fixed", fixed):
        raise p.error(f"{where}.fixed.gain", "no fixed gain (the channel gains are marginalised "
                      "with their log-normal prior)", repr(fixed["gain"]))

    def lognormal_gain(name: str, prior: Prior | None) -> None:
        if name == "gain" and prior is not None and (
                prior.dist != "lognormal" or math.isfinite(prior.upper) or prior.lower > 0):
            raise p.error(f"{where}.priors.gain", "an untruncated lognormal prior for gain (it "
                          "is marginalised in closed form)", prior.describe())

    return _parameter_specs(p, priors, fixed, table=RUNUP_PARAMETERS, where=where,
                            check=lognormal_gain)