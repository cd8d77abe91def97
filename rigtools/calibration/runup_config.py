r"""The run-up part of the ``[calibration]`` block: ``models`` and ``[calibration.runup]``.

The SDOF run-up calibration (issue 20; :mod:`rigtools.calibration.runup_api`) is enabled by
naming its models, and configured in a sub-table (every key optional; the values below are
the defaults)::

    [calibration]
    models = ["fvms", "vvms", "lste"]     # default []: no run-up calibration

    [calibration.runup]
    max_speed_points = 100        # windows per direction (up, down), after thinning a ramp
    min_speed_points = 20         # usable points per run below which the run is refused
    min_span = 1.3                # max/min mesh frequency a run-up must span
    steps_per_period = 64         # RK4 steps per mesh period of the model sweeps
    walkers = 16                  # default: [calibration] walkers if given, else 16
    max_steps = 20000             # default: [calibration] max_steps
    delayed_acceptance = true     # screen proposals with a surrogate, sweep only those passing
    mixture_move = true           # a fifth of the steps: independence proposals from a mixture

    [calibration.runup.priors]    # the same prior tables as [calibration.priors]
    zeta = {dist = "lognormal", median = 0.03, sigma = 0.7}
    mesh_stiffness_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}
    fluctuation_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}  # sampled only if given
    backlash = {dist = "uniform", lower = 0.0, upper = 300.0}   # um, total 2b
    gain = {dist = "lognormal", median = 0.01, sigma = 3.0}     # must be lognormal
    model_error = {dist = "halfnormal", sd = 0.3}
    model_error_length = {dist = "lognormal", median = 0.05, sigma = 1.5}
    channel_error = {dist = "halfnormal", sd = 0.3}

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
    ``tau``: standard deviation of ``log Arms`` about the model **shared by every channel at a
    point** (each channel sees the one DTE through its own gain, so where the model is off it
    is off on all of them): the relative model error. Default halfnormal(sd 0.3).
``model_error_length`` (1)
    ``ell``: correlation length of the model error along each sweep, in ``ln f_m`` (relative
    frequency): neighbouring points ``Delta ln f_m`` apart in one stretch of one direction are
    correlated by ``exp(-Delta / ell)`` (:mod:`rigtools.calibration.runup_likelihood`). A model
    that is off is off over a band: a steady-state model against a ramp over the resonance's
    half-power band (``2 zeta``), a wrong stiffness form over wider ones. Default
    lognormal(median 0.05, sigma 1.5): 95 % in [0.003, 0.9]. Fix it at 0 for independent
    points.
``channel_error`` (1)
    ``sigma``: standard deviation of each channel's own ``log Arms`` error (sensor noise, the
    order-spectrum floor, a transfer path that is not quite flat). Default halfnormal(sd 0.3).
    With one channel only ``tau^2 + sigma^2`` is identified (the summary says so).

Errors name the key and its line (:class:`rigtools.errors.CampaignError`), as for the rest of
the block (:mod:`rigtools.calibration.config`): besides those of every prior table, an unknown
model in ``models``, a ``gain`` prior that is not an untruncated lognormal or a fixed
``gain``, ``min_speed_points > max_speed_points``, ``min_span <= 1``, an odd number of walkers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Final, Literal

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
from rigtools.calibration.priors import Prior, prior_from_mapping

__all__ = [
    "RUNUP_MODELS",
    "RUNUP_PARAMETERS",
    "RunUpModel",
    "RunUpSettings",
    "parse_runup_table",
]

RunUpModel = Literal["fvms", "vvms", "lste"]
#: The SDOF mesh-stiffness models of the run-up calibration (issue 20).
RUNUP_MODELS: Final[tuple[RunUpModel, ...]] = ("fvms", "vvms", "lste")

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
        "tau: sd of log Arms about the model shared by every channel at a point (relative "
        "model error)"),
    "model_error_length": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 0.05,
                                                  "sigma": 1.5}),
        "ell: correlation length of the model error along a sweep, in ln f_m (0: independent "
        "points)"),
    "channel_error": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "halfnormal", "sd": 0.3}),
        "sigma: sd of each channel's own log Arms error (noise, floor, transfer path)"),
    "gain": ParameterInfo(
        "1", (0.0, math.inf), prior_from_mapping({"dist": "lognormal", "median": 0.01,
                                                  "sigma": 3.0}),
        "G_c: housing acceleration over (2 pi h f_m)^2 DTE, per channel (marginalised)"),
}

#: The settings of ``[calibration.runup]``, checked in this order.
_RUNUP_CHECKS: Final[dict[str, ValueCheck]] = {
    "max_speed_points": lambda p, k, v: p.integer(k, v, minimum=3),
    "min_speed_points": lambda p, k, v: p.integer(k, v, minimum=3),
    "min_span": lambda p, k, v: p.number(k, v, minimum=1.0, exclusive=True),
    "steps_per_period": lambda p, k, v: p.integer(k, v, minimum=16),
    "walkers": BlockParser.walkers,
    "max_steps": lambda p, k, v: p.integer(k, v, minimum=1),
    "delayed_acceptance": BlockParser.boolean,
    "mixture_move": BlockParser.boolean,
}
_RUNUP_KEYS: Final = (*_RUNUP_CHECKS, "priors", "fixed")


@dataclass(frozen=True)
class RunUpSettings:
    """The ``[calibration.runup]`` table: data preparation and sampler of the run-up fit.

    Attributes
    ----------
    max_speed_points : int
        Windows per direction (up, down) after thinning a ramp (the window nearest the median of
        each equal-log-f bin).
    min_speed_points : int
        Usable points per run below which the run is refused.
    min_span : float
        Smallest ratio max/min of the mesh frequency a run-up must span.
    steps_per_period : int
        Integration steps per mesh period of the model sweeps.
    walkers : int or None
        Walkers of the ensemble sampler; None: the ``[calibration]`` setting if given, else
        :data:`~rigtools.calibration.runup_api.RUNUP_WALKERS` (at least ``2 D + 2``).
    max_steps : int or None
        Largest number of sampler steps; None: the ``[calibration]`` setting.
    delayed_acceptance : bool
        Screen the sampler's proposals with a quadratic surrogate of the log posterior and
        sweep only those that pass (:mod:`rigtools.calibration.delayed_acceptance`; exact).
    mixture_move : bool
        A fifth of the sampler's steps are independence Metropolis-Hastings proposals from a
        Student-t mixture fitted to the chain (:mod:`rigtools.calibration.mixture_move`;
        exact): fewer steps per independent draw, and crossings between regimes.
    parameters : tuple of ParameterSpec
        In :data:`RUNUP_PARAMETERS` order (``gain`` always has its log-normal prior).
    """

    max_speed_points: int = 100
    min_speed_points: int = 20
    min_span: float = 1.3
    steps_per_period: int = 64
    walkers: int | None = None
    max_steps: int | None = None
    delayed_acceptance: bool = True
    mixture_move: bool = True
    parameters: tuple[ParameterSpec, ...] = field(
        default_factory=lambda: default_parameter_specs(RUNUP_PARAMETERS))

    def parameter(self, name: str) -> ParameterSpec:
        """The spec of run-up parameter ``name``."""
        return spec_named(self.parameters, name)

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
            "delayed_acceptance": self.delayed_acceptance,
            "mixture_move": self.mixture_move,
            **spec_tables(self.parameters),
        }
        return {k: v for k, v in d.items() if v is not None}


def parse_runup_table(p: BlockParser, value: Any) -> RunUpSettings:
    """Validate the ``[calibration.runup]`` table and resolve it with the defaults.

    Parameters
    ----------
    p : BlockParser
        The parser of the campaign's ``[calibration]`` block.
    value : mapping
        The table as ``tomllib`` parsed it.

    Returns
    -------
    RunUpSettings

    Raises
    ------
    CampaignError
        An unknown key or parameter, a wrong type or value (module notes); the message names
        the key and its line.
    """
    t = p.known_table("calibration.runup", value, _RUNUP_KEYS)
    kw = p.values("calibration.runup", t, _RUNUP_CHECKS)
    if kw.get("min_speed_points", 20) > kw.get("max_speed_points", 100):
        raise p.error("calibration.runup.min_speed_points", "min_speed_points <= max_speed_points",
                      f"{kw.get('min_speed_points', 20)} > {kw.get('max_speed_points', 100)}")
    kw["parameters"] = _runup_parameters(p, t.get("priors"), t.get("fixed"))
    return RunUpSettings(**kw)


def _runup_parameters(p: BlockParser, priors: Any, fixed: Any) -> tuple[ParameterSpec, ...]:
    where = "calibration.runup"
    if fixed is not None and "gain" in p.table(f"{where}.fixed", fixed):
        raise p.error(f"{where}.fixed.gain", "no fixed gain (the channel gains are marginalised "
                      "with their log-normal prior)", repr(fixed["gain"]))

    def lognormal_gain(name: str, prior: Prior | None) -> None:
        if name == "gain" and prior is not None and (
                prior.dist != "lognormal" or math.isfinite(prior.upper) or prior.lower > 0):
            raise p.error(f"{where}.priors.gain", "an untruncated lognormal prior for gain (it "
                          "is marginalised in closed form)", prior.describe())

    return parameter_specs(p, priors, fixed, table=RUNUP_PARAMETERS, where=where,
                           check=lognormal_gain)
