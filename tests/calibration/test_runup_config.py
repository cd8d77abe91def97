"""``[calibration] models`` and ``[calibration.runup]``: defaults, parsing, errors with lines."""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from typing import cast

import pytest

from rigtools.calibration import CalibrationConfig, default_config, parse_calibration_block
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.runup_config import RUNUP_MODELS, RUNUP_PARAMETERS, RunUpSettings
from rigtools.calibration.runup_forward import RunUpForward
from rigtools.calibration.runup_likelihood import GainPrior
from rigtools.calibration.runup_model import RunUpPosterior
from rigtools.errors import CampaignError
from rigtools.schemas import iter_errors

#: The keys and sub-tables of a full ``[calibration]`` block.
FULL = """\
models = ["fvms", "vvms", "lste"]

[calibration.runup]
max_speed_points = 80
min_speed_points = 25
min_span = 1.5
steps_per_period = 48
walkers = 24
max_steps = 9000
delayed_acceptance = false
mixture_move = false

[calibration.runup.priors]
zeta = {dist = "lognormal", median = 0.02, sigma = 0.5}
mesh_stiffness_scale = {dist = "lognormal", median = 1.0, sigma = 0.2}
fluctuation_scale = {dist = "lognormal", median = 1.0, sigma = 0.3}
backlash = {dist = "uniform", lower = 0.0, upper = 200.0}
gain = {dist = "lognormal", median = 0.005, sigma = 2.0}
model_error = {dist = "halfnormal", sd = 0.2}

[calibration.runup.fixed]
backlash = 136.0
model_error_length = 0.0
"""


def test_defaults_have_no_models_and_the_documented_priors() -> None:
    cfg = default_config()
    assert cfg.models == ()
    ru = cfg.runup
    assert ru == RunUpSettings()
    assert (ru.max_speed_points, ru.min_speed_points, ru.min_span, ru.steps_per_period,
            ru.walkers, ru.max_steps) == (100, 20, 1.3, 64, None, None)
    assert ru.free_parameters == ("zeta", "mesh_stiffness_scale", "backlash", "model_error",
                                  "model_error_length", "channel_error")
    assert ru.parameter("fluctuation_scale").fixed == 1.0
    assert ru.parameter("zeta").prior.describe() == "lognormal(median=0.03, sigma=0.7)"
    assert ru.parameter("backlash").prior.describe() == "uniform(0, 300)"
    assert ru.parameter("gain").prior.describe() == "lognormal(median=0.01, sigma=3)"
    assert ru.parameter("model_error").prior.describe() == "halfnormal(sd=0.3)"
    assert ru.parameter("model_error_length").prior.describe() == \
        "lognormal(median=0.05, sigma=1.5)"
    assert RUNUP_MODELS == ("fvms", "vvms", "lste")
    assert {p.unit for p in RUNUP_PARAMETERS.values()} <= {"1", "um"}


def test_a_full_block_is_resolved_and_round_trips(
        campaign_text: Callable[[str], str],
        parse_campaign_text: Callable[[str], CalibrationConfig]) -> None:
    cfg = parse_campaign_text(campaign_text(FULL))
    assert cfg.models == ("fvms", "vvms", "lste")
    ru = cfg.runup
    assert (ru.max_speed_points, ru.min_speed_points, ru.min_span, ru.steps_per_period,
            ru.walkers, ru.max_steps, ru.delayed_acceptance, ru.mixture_move) == (
                80, 25, 1.5, 48, 24, 9000, False, False)
    assert ru.free_parameters == ("zeta", "mesh_stiffness_scale", "fluctuation_scale",
                                  "model_error", "channel_error")
    assert ru.parameter("backlash").fixed == 136.0
    assert ru.parameter("model_error_length").fixed == 0.0   # independent points
    assert ru.parameter("gain").prior.describe() == "lognormal(median=0.005, sigma=2)"
    again = parse_calibration_block(cfg.to_dict(), source="c", line_of=lambda k: None)
    assert again.to_dict() == cfg.to_dict()
    assert again.runup.free_parameters == ru.free_parameters


def test_the_schema_accepts_the_full_block_and_rejects_unknown_keys(
        campaign_text: Callable[[str], str]) -> None:
    assert iter_errors(tomllib.loads(campaign_text(FULL)), "campaign.schema.json") == []
    for bad in ('models = ["itms2"]\n', "[calibration.runup]\nwalkerz = 4\n",
                "[calibration.runup.priors]\nzeeta = {dist = \"uniform\", lower = 0.0, "
                "upper = 1.0}\n", "[calibration.runup.fixed]\ngain = 0.01\n"):
        assert iter_errors(tomllib.loads(campaign_text(bad)), "campaign.schema.json"), bad


@pytest.mark.parametrize(("block", "line", "pattern"), [
    ('models = ["vvms", "itms"]\n', 10, r"one of 'fvms', 'vvms', 'lste' for calibration.models"),
    ('models = ["vvms", "vvms"]\n', 10, r"names without repeats"),
    ("[calibration.runup]\nwalkerz = 4\n", 11,
     r"a key of \[calibration.runup\].*unknown 'walkerz' \(did you mean 'walkers'\?\)"),
    ("[calibration.runup]\nwalkers = 15\n", 11, r"an even number of walkers, found 15"),
    ("[calibration.runup]\nmin_span = 1.0\n", 11, r"calibration.runup.min_span > 1"),
    ("[calibration.runup]\nmax_speed_points = 30\nmin_speed_points = 40\n", 12,
     r"min_speed_points <= max_speed_points, found 40 > 30"),
    ("[calibration.runup]\nsteps_per_period = 8\n", 11, r"steps_per_period >= 16"),
    ("[calibration.runup]\ndelayed_acceptance = 1\n", 11,
     r"true or false for calibration.runup.delayed_acceptance, found 1"),
    ("[calibration.runup.priors]\nzeeta = {dist = \"uniform\", lower = 0.0, upper = 1.0}\n",
     11, r"a parameter name in \[calibration.runup.priors\].*unknown 'zeeta' \(did you mean "
     r"'zeta'\?\)"),
    ("[calibration.runup.priors]\nzeta = {dist = \"uniform\", lower = 0.2, upper = 0.1}\n",
     11, r"lower < upper in calibration.runup.priors.zeta"),
    ("[calibration.runup.priors]\ngain = {dist = \"uniform\", lower = 0.0, upper = 1.0}\n",
     11, r"an untruncated lognormal prior for gain"),
    ("[calibration.runup.priors]\ngain = {dist = \"lognormal\", median = 0.01, sigma = 1.0, "
     "upper = 5.0}\n", 11, r"an untruncated lognormal prior for gain"),
    ("[calibration.runup.fixed]\ngain = 0.01\n", 11, r"no fixed gain"),
    ("[calibration.runup.fixed]\nzeta = -0.1\n", 11, r"a fixed zeta in its domain"),
    ("[calibration.runup.priors]\nbacklash = {dist = \"uniform\", lower = 0.0, upper = 50.0}\n"
     "[calibration.runup.fixed]\nbacklash = 136.0\n", 13,
     r"a fixed backlash that its prior uniform\(0, 50\) "
     r"\(calibration.runup.priors.backlash\) admits, found 136"),
])
def test_errors_name_the_key_and_its_line(
        block: str, line: int, pattern: str, campaign_text: Callable[[str], str],
        parse_campaign_text: Callable[[str], CalibrationConfig]) -> None:
    with pytest.raises(CampaignError, match=pattern) as info:
        parse_campaign_text(campaign_text(block))
    assert str(info.value).startswith(f"c.toml at line {line}: expected "), str(info.value)


def test_every_parameter_with_a_positive_support_is_moved_in_log_coordinates() -> None:
    """Default priors: all six free run-up parameters are moved in ``ln x``.

    The backlash included (its prior reaches 0); a prior reaching below 0 is moved in its own
    units.
    """
    st = default_config().runup
    names = ("zeta", "mesh_stiffness_scale", "backlash", "model_error", "model_error_length",
             "channel_error")
    priors = tuple(st.parameter(n).prior for n in names)
    assert all(p is not None for p in priors)
    post = RunUpPosterior(forward=cast(RunUpForward, None), names=names,
                          priors=cast(tuple, priors), fixed={}, gain_prior=GainPrior(0.0, 1.0),
                          log_observed=(), gaps=())
    assert post.log_scale == (True,) * 6
    wide = prior_from_mapping({"dist": "uniform", "lower": -10.0, "upper": 300.0})
    post = RunUpPosterior(forward=cast(RunUpForward, None), names=("backlash",), priors=(wide,),
                          fixed={}, gain_prior=GainPrior(0.0, 1.0), log_observed=(), gaps=())
    assert post.log_scale == (False,)
