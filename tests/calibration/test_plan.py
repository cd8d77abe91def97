"""What to run next: on a one-temperature campaign the plan proposes another temperature."""

from __future__ import annotations

import numpy as np
import pytest
from calibration_cases import campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import calibrate_observations
from rigtools.calibration.plan import plan_next_runs


@pytest.fixture(scope="module")
def one_temperature(pair: GearPair) -> object:
    obs = campaign(pair, seed=10, torques=(20.0, 50.0, 100.0, 183.4, 302.0),
                   temperatures=(40.0,) * 5, run_ids=[f"R{i}" for i in range(5)])
    return calibrate_observations(obs, pair,
                                  fast_config(operating_temperature_C=90.0, max_steps=4000))


def test_a_one_temperature_campaign_is_told_to_run_at_another_temperature(
        one_temperature: object) -> None:
    plan = plan_next_runs(one_temperature)
    assert plan.operating_temperature_C == 90.0
    best = plan.best(3)
    assert all(b["temperature_C"] > 60.0 for b in best), best
    assert plan.predicted_sd_um[0] < 0.7 * plan.current_sd_um
    # the candidates at the campaign's own temperature help the operating margin least
    at_40 = plan.temperature_C == 40.0
    assert plan.predicted_sd_um[at_40].min() > plan.predicted_sd_um[0]


def test_plan_respects_the_stated_ranges(one_temperature: object) -> None:
    plan = plan_next_runs(one_temperature, torque_range_Nm=(50.0, 100.0),
                          temperature_range_C=(40.0, 70.0))
    assert plan.torque_Nm.min() >= 50.0 - 1e-9 and plan.torque_Nm.max() <= 100.0 + 1e-9
    assert plan.temperature_C.max() <= 70.0 + 1e-9
    assert np.all(np.diff(plan.predicted_sd_um) >= 0)
