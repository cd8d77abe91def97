"""Bayesian calibration of backlash, thermal closure and stiffness from natural frequencies.

Modules: ``priors`` (prior families, truncation), ``config`` (the ``[calibration]`` block and
its defaults), ``config_parsing`` (the checks of its tables, errors naming key and line),
``data`` (observations table -> runs, conditions, candidate peaks), ``forward``
(the three model variants of the mesh natural frequency, two thermal closures, the jammed
state), ``likelihood`` (the mixture over candidate peaks with a background component),
``kernel`` (the same log posterior compiled), ``model`` (the log posterior of a campaign),
``checkpoint`` (crash-safe chain storage), ``sampler`` (MAP, emcee, convergence), ``derived``
(critical gaps, margins, regimes, flip temperature, mesh mode), ``diagnostics`` (summaries,
checks, identifiability), ``comparison`` (PSIS-LOO of the variants), ``result``, ``outputs``
(``posterior.nc``, ``summary.json``, ``summary.csv``), ``api`` (:func:`calibrate_observations`),
``simulate`` (synthetic observation tables), ``curves`` (posterior predictive bands for the
figures), ``plan`` (which runs to add), ``campaign_inputs`` (:func:`calibrate` of a campaign:
its pair, ``[calibration]`` and ``[thermal]`` blocks and observations), ``autocorr``
(integrated autocorrelation time), ``errors``.

The SDOF run-up calibration (issue 20: FVMS, VVMS and LSTE against the measured Arms run-up
curves): ``runup_config`` (``models`` and ``[calibration.runup]``), ``runup_data`` (arms rows
-> time-ordered curves), ``runup_forward`` (parameters ->
modelled Arms along each path), ``runup_likelihood`` (log-normal, gains marginalised),
``runup_model`` (the vectorised log posterior), ``runup_map`` (MAP by differential
evolution), ``runup_summary`` (parameters, identifiability, derived natural frequencies),
``runup_api`` (:func:`calibrate_runups`), ``runup_outputs`` (:class:`RunUpResult` and its files).
"""

from rigtools.calibration.api import CHECKPOINT_FILE, calibrate_observations, resolve_reference
from rigtools.calibration.campaign_inputs import (
    calibrate,
    campaign_config,
    campaign_observations,
    campaign_reference,
)
from rigtools.calibration.comparison import ModelComparison, compare_variants
from rigtools.calibration.config import (
    PARAMETERS,
    VARIANTS,
    CalibrationConfig,
    Tolerances,
    default_config,
    parse_calibration_block,
)
from rigtools.calibration.config_parsing import ParameterSpec
from rigtools.calibration.curves import PredictiveCurves, predictive_curves
from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.outputs import write_outputs
from rigtools.calibration.plan import RunPlan, plan_next_runs
from rigtools.calibration.priors import Prior, prior_from_mapping
from rigtools.calibration.result import CalibrationResult, VariantFit
from rigtools.calibration.runup_api import calibrate_runup_data, calibrate_runups
from rigtools.calibration.runup_config import RUNUP_MODELS, RUNUP_PARAMETERS, RunUpSettings
from rigtools.calibration.runup_outputs import (
    RunPredictive,
    RunUpFit,
    RunUpResult,
    write_runup_outputs,
)
from rigtools.calibration.simulate import simulate_observations

__all__ = [
    "CHECKPOINT_FILE",
    "PARAMETERS",
    "RUNUP_MODELS",
    "RUNUP_PARAMETERS",
    "VARIANTS",
    "CalibrationConfig",
    "CalibrationError",
    "CalibrationResult",
    "ModelComparison",
    "ParameterSpec",
    "PredictiveCurves",
    "Prior",
    "RunPlan",
    "RunPredictive",
    "RunUpFit",
    "RunUpResult",
    "RunUpSettings",
    "Tolerances",
    "VariantFit",
    "calibrate",
    "calibrate_observations",
    "calibrate_runup_data",
    "calibrate_runups",
    "campaign_config",
    "campaign_observations",
    "campaign_reference",
    "compare_variants",
    "default_config",
    "parse_calibration_block",
    "plan_next_runs",
    "predictive_curves",
    "prior_from_mapping",
    "resolve_reference",
    "simulate_observations",
    "write_outputs",
    "write_runup_outputs",
]
