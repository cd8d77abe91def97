"""PSIS-LOO over the variants: the data-generating reading is not ranked below another."""

from __future__ import annotations

import pytest
from calibration_cases import campaign, fast_config

from models.geometry import GearPair
from rigtools.calibration import calibrate_observations


@pytest.mark.slow
def test_a_load_independent_mesh_mode_is_not_credited_to_the_secant_reading(
        pair: GearPair) -> None:
    """Data from the tangent reading (plus the housing mode): the tangent must not lose."""
    obs = campaign(pair, seed=9, variant="tangent")
    res = calibrate_observations(obs, pair,
                                 fast_config(compare_variants=("secant_path", "tangent")))
    assert res.comparison is not None
    assert res.comparison.favoured in (None, "tangent"), res.comparison.statement


@pytest.mark.slow
def test_the_secant_reading_is_favoured_when_the_mode_moves_with_load(pair: GearPair) -> None:
    obs = campaign(pair, seed=12)
    res = calibrate_observations(obs, pair, fast_config(
        compare_variants=("secant_path", "secant_mesh", "tangent")))
    v = res.summary["model_comparison"]["variants"]
    assert v["tangent"]["rank"] == 2, res.comparison.statement
    assert res.comparison.favoured in ("secant_path", "secant_mesh", None)
    for name in ("secant_path", "secant_mesh", "tangent"):
        assert set(v[name]["runs"]) == {f"R{i}" for i in range(10)}
