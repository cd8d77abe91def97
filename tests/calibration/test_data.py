"""Observations table -> runs and candidates: left-out runs with reasons, structural modes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from calibration_cases import HOUSING_HZ, campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import CalibrationError
from rigtools.calibration.data import prepare_data


def test_every_natural_frequency_row_is_a_candidate(pair: GearPair) -> None:
    obs = campaign(pair)
    d = prepare_data(obs, fast_config())
    nf = obs[obs["quantity"] == "natural_frequency"]
    assert d.candidates.mask.sum() == len(nf)
    assert d.runs.run_id == tuple(f"R{i}" for i in range(10))
    lo, hi = d.candidates.band_Hz
    assert lo == 1.0
    assert hi == pytest.approx(nf["f_n_Hz"].max() * 1.25)
    assert not d.left_out


def test_the_band_comes_from_the_config_or_the_tables_analysis_settings(pair: GearPair) -> None:
    obs = campaign(pair).copy()
    obs.attrs["rigtools"] = {"campaign": {"analysis": {"f_range_Hz": [200.0, 12000.0]}}}
    assert prepare_data(obs, fast_config()).candidates.band_Hz == (200.0, 12000.0)
    assert prepare_data(obs, fast_config(band_Hz=(100.0, 9000.0))).candidates.band_Hz == \
        (100.0, 9000.0)


def test_runs_are_left_out_with_a_reason(pair: GearPair) -> None:
    obs = campaign(pair).copy()
    run = obs["run_id"]
    obs.loc[(run == "R1") & (obs["quantity"] == "run"), ["status", "message"]] = \
        ["failed", "r1.blf: no such file"]
    obs.loc[run == "R2", "torque_Nm"] = np.nan
    obs.loc[run == "R3", "bulk_temperature_C"] = np.nan
    obs = obs[~((run == "R4") & (obs["quantity"] == "natural_frequency"))]
    obs.loc[(obs["run_id"] == "R5") & (obs["quantity"] == "natural_frequency"), "status"] = \
        "failed"
    obs.loc[obs["run_id"] == "R6", "torque_Nm"] = -3.0
    d = prepare_data(obs, fast_config())
    assert d.left_out == {
        "R1": "the run failed in the observations stage: r1.blf: no such file",
        "R2": "torque_Nm is missing or NaN",
        "R3": "bulk_temperature_C is missing or NaN",
        "R4": "no natural-frequency rows",
        "R5": "no usable natural-frequency row (all failed or without f_n_Hz)",
        "R6": "torque_Nm must be > 0, was -3",
    }
    assert d.runs.run_id == ("R0", "R7", "R8", "R9")


def test_channel_selection(pair: GearPair) -> None:
    obs = campaign(pair)
    d = prepare_data(obs, fast_config(channels=("accel_2",)))
    assert set(d.candidates.channel[d.candidates.mask]) == {"accel_2"}
    d = prepare_data(obs[~((obs["run_id"] == "R0") & (obs["channel"] == "accel_2"))],
                     fast_config(channels=("accel_2",)))
    assert d.left_out["R0"].startswith("no natural-frequency rows on the configured channels")


def test_no_usable_run_is_an_error_listing_every_reason(pair: GearPair) -> None:
    obs = campaign(pair).copy()
    obs["torque_Nm"] = np.nan
    with pytest.raises(CalibrationError, match=r"no run .* can be fitted \(R0: torque_Nm is "
                       r"missing or NaN; R1: torque_Nm"):
        prepare_data(obs, fast_config())


def test_missing_columns_are_named(pair: GearPair) -> None:
    with pytest.raises(CalibrationError, match=r"lacks the column\(s\) f_n_Hz"):
        prepare_data(campaign(pair).drop(columns=["f_n_Hz"]), fast_config())
    with pytest.raises(CalibrationError, match="no rows"):
        prepare_data(pd.DataFrame(columns=list(campaign(pair).columns)), fast_config())


def test_the_housing_mode_is_found_and_the_moving_mesh_mode_is_not(pair: GearPair) -> None:
    d = prepare_data(campaign(pair), fast_config())
    modes = d.candidates.structural_modes
    assert len(modes) == 1
    assert modes[0].frequency_Hz == pytest.approx(HOUSING_HZ, rel=0.005)
    assert modes[0].n_runs == 10
    # two configurations: the group is a structural mode (its peaks narrow and dense) or not
    c = d.candidates
    f, lb = c.f_Hz, c.log_background
    assert lb.shape == (2, *f.shape)
    at_housing = (np.abs(f - HOUSING_HZ) < 100.0) & c.mask
    assert np.array_equal(c.group >= 0, at_housing)
    assert np.ptp(lb[0][c.mask]) == 0.0                   # z = 0: all uniform
    assert lb[1][at_housing].min() > lb[1][~at_housing & c.mask].max()
    none = prepare_data(campaign(pair), fast_config(structural_modes="none"))
    assert none.candidates.structural_modes == () and none.candidates.n_configurations == 1
    assert np.ptp(none.candidates.log_background[0][none.candidates.mask]) == 0.0


def test_repeated_conditions_do_not_make_a_structural_mode(pair: GearPair) -> None:
    """The mesh mode of runs at one condition recurs too, but under one condition only."""
    obs = campaign(pair, torques=(100.0,) * 6, temperatures=(60.0,) * 6,
                   run_ids=[f"S{i}" for i in range(6)], housing_modes_Hz=())
    d = prepare_data(obs, fast_config())
    assert d.candidates.structural_modes == ()
