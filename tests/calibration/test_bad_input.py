"""Issue 18 item 12: bad input gives a message naming the run or key, never a traceback."""

from __future__ import annotations

import numpy as np
import pytest
from calibration_cases import campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import CalibrationError, calibrate_observations, parse_calibration_block
from rigtools.errors import RigtoolsError


def _cfg(priors: dict, **kw: object) -> object:
    block = {"priors": priors, "compare_variants": [], "walkers": 24, "max_steps": 3000,
             "map_starts": 4, **kw}
    return parse_calibration_block(block, source="c.toml", line_of=lambda k: None)


def test_left_out_runs_are_listed_in_the_summary(pair: GearPair) -> None:
    obs = campaign(pair).copy()
    obs.loc[(obs["run_id"] == "R1") & (obs["quantity"] == "run"), ["status", "message"]] = \
        ["failed", "r1.blf: cut at byte 12"]
    obs.loc[obs["run_id"] == "R2", "bulk_temperature_C"] = np.nan
    obs = obs[~((obs["run_id"] == "R3") & (obs["quantity"] == "natural_frequency"))]
    res = calibrate_observations(obs, pair, fast_config())
    runs = res.summary["runs"]
    assert runs["R1"]["left_out"] == \
        "the run failed in the observations stage: r1.blf: cut at byte 12"
    assert runs["R2"]["left_out"] == "bulk_temperature_C is missing or NaN"
    assert runs["R3"]["left_out"] == "no natural-frequency rows"
    assert runs["R3"]["regime"] is None and runs["R0"]["left_out"] is None
    assert "run 'R3' left out: no natural-frequency rows" in res.warnings
    assert res.summary["data"]["runs_left_out"]["R2"] == "bulk_temperature_C is missing or NaN"


def test_one_temperature_warns_of_the_degeneracy(pair: GearPair) -> None:
    obs = campaign(pair, temperatures=(90.0,) * 10)
    res = calibrate_observations(obs, pair, fast_config(max_steps=2000))
    assert any(w.startswith("all runs at one bulk temperature (90 degC): the backlash and the "
                            "closure coefficient are degenerate") for w in res.warnings)


def test_priors_that_exclude_the_data_name_the_key(pair: GearPair) -> None:
    cfg = _cfg({"stiffness_scale": {"dist": "uniform", "lower": 6.0, "upper": 8.0}})
    with pytest.raises(CalibrationError, match=r"^calibration.priors.stiffness_scale: the "
                       r"priors exclude the data") as info:
        calibrate_observations(campaign(pair), pair, cfg)
    assert isinstance(info.value, RigtoolsError)


def test_a_campaign_whose_runs_all_jam_names_the_key(pair: GearPair) -> None:
    cfg = _cfg({"backlash": {"dist": "uniform", "lower": 0.0, "upper": 0.5},
                "closure_coefficient": {"dist": "uniform", "lower": 3.0, "upper": 3.5}})
    with pytest.raises(CalibrationError, match=r"^calibration.priors.backlash: every run "
                       r"\(R0, R1, .*\) is jammed by thermal growth"):
        calibrate_observations(campaign(pair), pair, cfg)


def test_too_few_walkers_name_the_key(pair: GearPair) -> None:
    cfg = _cfg({}, walkers=4)
    with pytest.raises(CalibrationError, match=r"^calibration.walkers: 4 walkers for 4 free "
                       r"parameters"):
        calibrate_observations(campaign(pair), pair, cfg)


def test_nothing_usable_names_every_run(pair: GearPair) -> None:
    obs = campaign(pair).copy()
    obs["torque_Nm"] = np.nan
    with pytest.raises(CalibrationError, match=r"R0: torque_Nm is missing or NaN; R1"):
        calibrate_observations(obs, pair, fast_config())
