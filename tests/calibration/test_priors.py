"""Priors: densities, quantiles and moments against scipy.stats (the reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import integrate, stats

from rigtools.calibration.priors import Prior, prior_from_mapping

CASES = [
    ({"dist": "uniform", "lower": 0.0, "upper": 100.0}, stats.uniform(0.0, 100.0)),
    ({"dist": "normal", "mu": 1.0, "sd": 2.0}, stats.norm(1.0, 2.0)),
    ({"dist": "truncated_normal", "mu": 1.0, "sd": 2.0, "lower": 0.0, "upper": 3.0},
     stats.truncnorm(-0.5, 1.0, loc=1.0, scale=2.0)),
    ({"dist": "lognormal", "median": 1.0, "sigma": 0.3}, stats.lognorm(0.3)),
    ({"dist": "lognormal", "median": 2.0, "sigma": 0.5, "upper": 3.0}, None),
    ({"dist": "halfnormal", "sd": 0.05}, stats.halfnorm(scale=0.05)),
    ({"dist": "halfnormal", "sd": 1.0, "upper": 1.5}, None),
]


@pytest.mark.parametrize(("spec", "ref"), CASES)
def test_density_matches_scipy_and_integrates_to_one(spec: dict, ref: object) -> None:
    p = prior_from_mapping(spec)
    lo = p.lower if math.isfinite(p.lower) else -50.0
    hi = p.upper if math.isfinite(p.upper) else 50.0
    x = np.linspace(lo, hi, 401)[1:-1]
    if ref is not None:
        np.testing.assert_allclose(p.logpdf(x), ref.logpdf(x), rtol=1e-10, atol=1e-10,
                                   err_msg=f"{spec}: log density vs scipy.stats")
    total, _ = integrate.quad(lambda v: math.exp(p.logpdf(v)), lo, hi, limit=400,
                              points=[1e-6] if lo == 0.0 else None)
    assert total == pytest.approx(1.0, abs=1e-6), f"{spec} integrates to {total}"


@pytest.mark.parametrize(("spec", "ref"), [c for c in CASES if c[1] is not None])
def test_quantiles_and_moments_match_scipy(spec: dict, ref: object) -> None:
    p = prior_from_mapping(spec)
    u = np.array([0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99])
    np.testing.assert_allclose(p.ppf(u), ref.ppf(u), rtol=1e-9, err_msg=str(spec))
    mean, sd = p.moments()
    assert mean == pytest.approx(ref.mean(), rel=1e-3, abs=1e-6)
    assert sd == pytest.approx(ref.std(), rel=1e-3)


def test_outside_the_support_is_minus_infinity_never_nan() -> None:
    for spec, _ in CASES:
        p = prior_from_mapping(spec)
        vals = p.logpdf([p.lower - 1.0, p.upper + 1.0, -1e300, 1e300])
        assert not np.any(np.isnan(vals))
        assert np.all(vals[:2] == -np.inf) or not (math.isfinite(p.lower)
                                                    and math.isfinite(p.upper))


@given(st.floats(0.0, 1.0))
def test_ppf_stays_in_the_support_and_is_monotone(u: float) -> None:
    for spec, _ in CASES:
        p = prior_from_mapping(spec)
        x = float(p.ppf(u))
        assert p.lower <= x <= p.upper
        assert float(p.ppf(min(u + 1e-3, 1.0))) >= x


@pytest.mark.parametrize("spec", [
    {"dist": "uniform", "lower": 1.0, "upper": 1.0},
    {"dist": "normal", "mu": 0.0, "sd": 0.0},
    {"dist": "lognormal", "median": 1.0, "sigma": -1.0},
    {"dist": "halfnormal", "sd": -2.0},
    {"dist": "gamma", "shape": 2.0},
])
def test_invalid_specifications_are_refused_naming_the_key(spec: dict) -> None:
    with pytest.raises(ValueError, match=r"`(lower|sd|sigma|dist)`"):
        prior_from_mapping(spec)


def test_describe_and_round_trip() -> None:
    for spec, _ in CASES:
        p = prior_from_mapping(spec)
        q = prior_from_mapping(p.to_dict())
        assert q == p, p.describe()
    assert isinstance(prior_from_mapping(CASES[0][0]), Prior)
