"""The [calibration] block: defaults, parsing, and errors that name the key and its line."""

from __future__ import annotations

import tomllib
from collections.abc import Callable

import pytest

from models.thermal import SEED_000_CHI
from rigtools.calibration import (
    PARAMETERS,
    CalibrationConfig,
    default_config,
    parse_calibration_block,
)
from rigtools.errors import CampaignError
from rigtools.schemas import iter_errors

#: The keys and sub-tables of a full ``[calibration]`` block.
FULL = """\
model_variant = "secant_mesh"
compare_variants = ["secant_mesh", "tangent"]
thermal_model = "expansion"
jammed_model = "double_flank"
likelihood = "student_t"
student_t_dof = 5
channels = ["accel_1"]
detection_probability = 0.8
structural_modes = "none"
band_Hz = [500.0, 12000.0]
equivalent_mass_kg = 0.2
reference_temperature_C = 25.0
operating_temperature_C = 95.0
temperature_sd_K = 2.0
walkers = 40
max_steps = 5000
check_every = 50
seed = 7
map_starts = 3
plan_torque_range_Nm = [20.0, 350.0]
plan_temperature_range_C = [40.0, 100.0]

[calibration.priors]
backlash = {dist = "uniform", lower = 0.0, upper = 60.0}
stiffness_scale = {dist = "lognormal", median = 1.1, sigma = 0.2}
chi = {dist = "truncated_normal", mu = 0.03, sd = 0.01, lower = 0.0, upper = 0.1}

[calibration.fixed]
model_error = 0.03

[calibration.tolerances]
unchanged_band_um = 0.5
max_r_hat = 1.02
acceptance_range = [0.1, 0.8]
"""


def test_no_block_gives_the_documented_defaults() -> None:
    cfg = parse_calibration_block(None, source="c.toml", line_of=lambda k: None)
    assert cfg == default_config()
    assert cfg.model_variant == "secant_path"
    assert cfg.compare_variants == ("secant_path", "secant_mesh", "tangent")
    assert cfg.free_parameters == ("backlash", "closure_coefficient", "stiffness_scale",
                                   "model_error")
    assert cfg.parameter("chi").fixed == SEED_000_CHI
    assert cfg.parameter("backlash").prior.describe() == "uniform(0, 100)"
    assert cfg.parameter("stiffness_scale").prior.describe() == \
        "lognormal(median=1, sigma=0.3)"
    assert cfg.parameter("model_error").prior.describe() == "halfnormal(sd=0.05)"


def test_a_full_block_is_resolved(
        campaign_text: Callable[[str], str],
        parse_campaign_text: Callable[[str], CalibrationConfig]) -> None:
    cfg = parse_campaign_text(campaign_text(FULL))
    assert (cfg.model_variant, cfg.thermal_model, cfg.jammed_model, cfg.likelihood) == \
        ("secant_mesh", "expansion", "double_flank", "student_t")
    assert cfg.compare_variants == ("secant_mesh", "tangent")
    assert cfg.band_Hz == (500.0, 12000.0) and cfg.channels == ("accel_1",)
    assert (cfg.walkers, cfg.max_steps, cfg.check_every, cfg.seed) == (40, 5000, 50, 7)
    assert cfg.parameter("model_error").fixed == 0.03
    chi = cfg.parameter("chi")
    assert chi.free and chi.prior.describe() == \
        "normal(mu=0.03, sd=0.01) truncated to [0, 0.1]"
    assert cfg.tolerances.max_r_hat == 1.02
    assert cfg.tolerances.acceptance_range == (0.1, 0.8)
    assert cfg.plan_torque_range_Nm == (20.0, 350.0)
    assert cfg.plan_temperature_range_C == (40.0, 100.0)
    assert cfg.free_parameters == ("backlash", "closure_coefficient", "stiffness_scale", "chi")
    # the block's JSON form round-trips through the parser
    again = parse_calibration_block(cfg.to_dict() | {"walkers": 40}, source="c",
                                    line_of=lambda k: None)
    assert again.to_dict() == cfg.to_dict()


def test_the_schema_accepts_the_full_block(campaign_text: Callable[[str], str]) -> None:
    assert iter_errors(tomllib.loads(campaign_text(FULL)), "campaign.schema.json") == []


@pytest.mark.parametrize(("block", "line", "pattern"), [
    ("walkerz = 40\n", 10, r"unknown 'walkerz' \(did you mean 'walkers'\?\)"),
    ("walkers = 41\n", 10, r"an even number of walkers, found 41"),
    ("model_variant = \"secant\"\n", 10, r"one of 'secant_path', 'secant_mesh', 'tangent'"),
    ("seed = 1.5\n", 10, r"an integer for calibration.seed"),
    ("band_Hz = [900.0, 100.0]\n", 10, r"low < high"),
    ("[calibration.priors]\nbacklsh = {dist = \"uniform\", lower = 0.0, upper = 60.0}\n", 11,
     r"a parameter name in \[calibration.priors\].*unknown 'backlsh' \(did you mean "
     r"'backlash'\?\)"),
    ("[calibration.priors]\nbacklash = {dist = \"uniform\", lower = 60.0, upper = 0.0}\n",
     11, r"lower < upper in calibration.priors.backlash, found lower = 60, upper = 0"),
    ("[calibration.priors]\nstiffness_scale = {dist = \"normal\", mu = 1.0, sd = 0.0}\n",
     11, r"sd > 0 in calibration.priors.stiffness_scale, found sd = 0"),
    ("[calibration.priors]\nstiffness_scale = {dist = \"lognormal\", median = 1.0, "
     "sigma = -0.1}\n", 11, r"sigma > 0"),
    ("[calibration.priors]\nbacklash = {dist = \"uniform\", lower = 0.0}\n", 11,
     r"key 'upper' of a uniform prior"),
    ("[calibration.priors]\nbacklash = {dist = \"uniform\", lower = 0.0, upper = 9.0, "
     "sd = 1.0}\n", 11, r"unknown 'sd'"),
    ("[calibration.priors]\nbacklash = {dist = \"uniform\", lower = 0.0, upper = 60.0}\n"
     "[calibration.fixed]\nbacklash = 150.0\n", 13,
     r"a fixed backlash that its prior uniform\(0, 60\) \(calibration.priors.backlash\) "
     r"admits, found 150"),
    ("[calibration.fixed]\nchi = 1.5\n", 11, r"a fixed chi in its domain \[0, 1\]"),
    ("[calibration.fixed]\nstiffnes_scale = 1.0\n", 11, r"unknown 'stiffnes_scale'"),
    ("[calibration.tolerances]\nmax_rhat = 1.1\n", 11, r"unknown 'max_rhat'"),
    ("compare_variants = [\"tangent\"]\n", 10, r"headline model_variant 'secant_path'"),
])
def test_errors_name_the_key_and_its_line(
        block: str, line: int, pattern: str, campaign_text: Callable[[str], str],
        parse_campaign_text: Callable[[str], CalibrationConfig]) -> None:
    text = campaign_text(block)
    with pytest.raises(CampaignError, match=pattern) as info:
        parse_campaign_text(text)
    assert str(info.value).startswith(f"c.toml at line {line}: expected "), str(info.value)


def test_unknown_keys_are_errors_in_the_schema_too(campaign_text: Callable[[str], str]) -> None:
    for bad in ("walkerz = 40\n", "[calibration.priors]\nbacklsh = {dist = \"uniform\", "
                "lower = 0.0, upper = 6.0}\n", "[calibration.tolerances]\nmax_rhat = 1.1\n"):
        assert iter_errors(tomllib.loads(campaign_text(bad)), "campaign.schema.json"), bad


def test_every_parameter_has_a_unit_from_the_summary_vocabulary() -> None:
    assert {p.unit for p in PARAMETERS.values()} <= {"m", "um", "degC", "K", "1", "N/m", "kg"}
