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

``models`` and ``[calibration.runup]`` configure the SDOF run-up calibration:
:mod:`rigtools.calibration.runup_config` lists their keys, parameters and defaults.

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

Errors name the key and its line (:class:`rigtools.errors.CampaignError`,
:class:`~rigtools.calibration.config_parsing.BlockParser`): an unknown key or parameter, a
value of the wrong type, ``lower >= upper``, ``sd <= 0`` (or ``sigma``), a fixed value that
its prior (or the parameter's domain) excludes, an odd number of walkers; for the run-up
(:mod:`rigtools.calibration.runup_config`): an unknown model in ``models``, a ``gain`` prior
that is not an untruncated lognormal or a fixed ``gain``, ``min_speed_points >
max_speed_points``, ``min_span <= 1``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Final, Literal

from models.thermal import SEED_000_CHI
from rigtools.calibration.config_parsing import (
    BlockParser,
    ParameterInfo,
    ParameterSpec,
    ValueCheck,
    default_parameter_specs,
    parameter_specs,
    spec_named,
    spec_tables,
)
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.runup_config import (
    RUNUP_MODELS,
    RunUpModel,
    RunUpSettings,
    parse_runup_table,
)

__all__ = [
    "JAMMED_TREATMENTS",
    "LIKELIHOODS",
    "PARAMETERS",
    "THERMAL_MODELS",
    "VARIANTS",
    "CalibrationConfig",
    "JammedTreatment",
    "LikelihoodKind",
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
#: The model variants (issue 18 item 3), headline default first.
VARIANTS: Final[tuple[Variant, ...]] = ("secant_path", "secant_mesh", "tangent")
THERMAL_MODELS: Final[tuple[ThermalModel, ...]] = ("linear", "expansion")
JAMMED_TREATMENTS: Final[tuple[JammedTreatment, ...]] = ("censored", "double_flank")
LIKELIHOODS: Final[tuple[LikelihoodKind, ...]] = ("normal", "student_t")


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

_TOP_KEYS: Final = (
    "model_variant", "compare_variants", "thermal_model", "jammed_model", "likelihood",
    "student_t_dof", "channels", "detection_probability", "structural_modes", "band_Hz",
    "equivalent_mass_kg", "inertia_kg_m2", "disc_radius", "reference_temperature_C",
    "operating_temperature_C", "temperature_sd_K", "walkers", "max_steps", "check_every",
    "seed", "map_starts", "plan_torque_range_Nm", "plan_temperature_range_C", "priors", "fixed",
    "tolerances", "models", "runup",
)


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
    parameters: tuple[ParameterSpec, ...] = field(
        default_factory=lambda: default_parameter_specs(PARAMETERS))
    tolerances: Tolerances = field(default_factory=Tolerances)
    models: tuple[RunUpModel, ...] = ()
    runup: RunUpSettings = field(default_factory=RunUpSettings)

    def parameter(self, name: str) -> ParameterSpec:
        """The spec of parameter ``name``."""
        return spec_named(self.parameters, name)

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
            **spec_tables(self.parameters),
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


def default_config() -> CalibrationConfig:
    """The configuration used when a campaign has no ``[calibration]`` block."""
    return CalibrationConfig()


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
    p = BlockParser(source, line_of)
    block = p.known_table("calibration", block, _TOP_KEYS)
    kw: dict[str, Any] = {}

    def key(k: str) -> str:
        return f"calibration.{k}"

    if "model_variant" in block:
        kw["model_variant"] = p.choice(key("model_variant"), block["model_variant"], VARIANTS)
    if "compare_variants" in block:
        kw["compare_variants"] = p.choices(key("compare_variants"), block["compare_variants"],
                                           VARIANTS)
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
        kw["walkers"] = p.walkers(key("walkers"), block["walkers"])
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
        kw["tolerances"] = _tolerances(p, block["tolerances"])
    if "models" in block:
        kw["models"] = p.choices(key("models"), block["models"], RUNUP_MODELS)
    if "runup" in block:
        kw["runup"] = parse_runup_table(p, block["runup"])
    kw["parameters"] = parameter_specs(p, block.get("priors"), block.get("fixed"),
                                       table=PARAMETERS, where="calibration")
    cfg = CalibrationConfig(**kw)
    if cfg.compare_variants and cfg.model_variant not in cfg.compare_variants:
        raise p.error(key("compare_variants"),
                      f"the headline model_variant {cfg.model_variant!r} among the compared "
                      "variants (or [] for no comparison)", repr(list(cfg.compare_variants)))
    return cfg


def _tolerances(p: BlockParser, value: Any) -> Tolerances:
    t = p.known_table("calibration.tolerances", value, _TOLERANCE_KEYS)
    return replace(Tolerances(), **p.values("calibration.tolerances", t, _TOLERANCE_CHECKS))


def _acceptance_range(p: BlockParser, key: str, value: Any) -> tuple[float, float]:
    lo, hi = p.pair(key, value)
    if hi >= 1.0:
        raise p.error(key, "bounds inside (0, 1)", repr(list(value)))
    return lo, hi


#: The keys of ``[calibration.tolerances]``, checked in this order.
_TOLERANCE_CHECKS: Final[dict[str, ValueCheck]] = {
    "unchanged_band_um": lambda p, k, v: p.number(k, v, minimum=0.0),
    "regime_probability": lambda p, k, v: p.number(k, v, minimum=0.5, exclusive=True,
                                                   maximum=1.0, exclusive_max=True),
    "max_r_hat": lambda p, k, v: p.number(k, v, minimum=1.0, exclusive=True),
    "min_ess_bulk": lambda p, k, v: p.number(k, v, minimum=0.0, exclusive=True),
    "acceptance_range": _acceptance_range,
    "min_narrowing": lambda p, k, v: p.number(k, v, minimum=1.0),
}
_TOLERANCE_KEYS: Final = tuple(_TOLERANCE_CHECKS)
