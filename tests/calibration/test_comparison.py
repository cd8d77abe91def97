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


def test_the_statement_counts_the_observations_with_a_high_pareto_k() -> None:
    """One observation whose log density is heavy-tailed over the draws: k > 0.7, counted.

    Draws of log densities of 30 observations: Normal(-1, 0.1) for every one, except that the
    first variant's observation 0 is -1 - 20 |t_1| (a Student-t with one degree of freedom:
    importance ratios exp(20 |t|) with an infinite-variance tail).
    """
    import arviz as az
    import numpy as np

    from rigtools.calibration.comparison import compare_variants

    rng = np.random.default_rng(5)
    good = rng.normal(-1.0, 0.1, (4, 500, 30))
    bad = good.copy()
    bad[..., 0] = -1.0 - 20.0 * np.abs(rng.standard_t(1, (4, 500)))
    idata = {name: az.from_dict(posterior={"x": rng.normal(size=(4, 500))},
                                log_likelihood={"arms": ll}, dims={"arms": ["obs"]})
             for name, ll in (("heavy", bad), ("plain", good))}
    res = compare_variants(idata)
    assert res.variants["heavy"]["n_pareto_k_bad"] == 1
    assert res.variants["plain"]["n_pareto_k_bad"] == 0
    assert "Pareto k above 0.7 for heavy (1 of 30) observations" in res.statement
