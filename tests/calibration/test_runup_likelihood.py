"""The run-up likelihood: gain marginalisation against quadrature, the pointwise terms, jumps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from rigtools.calibration.runup_forward import acceleration_arms, jump_frequencies
from rigtools.calibration.runup_likelihood import (
    GainPrior,
    gain_conditional,
    marginal_log_likelihood,
    pointwise_log_likelihood,
)


def _case(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, GainPrior]:
    rng = np.random.default_rng(seed)
    log_mu = rng.normal(0.0, 1.0, (3, 9))                      # W = 3 parameter sets
    y = np.log(0.01) + log_mu[0][None, :] + rng.normal(0, 0.2, (2, 9))
    y[1, [2, 5]] = np.nan                                       # channel 2 misses two points
    y[:, 7] = np.nan                                            # a bridging point
    sigma = np.array([0.2, 0.35, 0.1])
    return y, log_mu, sigma, GainPrior(math.log(0.02), 1.5)


def _quad(y: np.ndarray, log_mu: np.ndarray, sigma: float, prior: GainPrior) -> float:
    """Log of int N(g; m0, s0) prod_i N(y_i; g + log mu_i, sigma) dg, channel by channel."""
    total = 0.0
    for c in range(y.shape[0]):
        ok = np.isfinite(y[c])
        r = y[c, ok] - log_mu[ok]
        shift = float(np.mean(r))

        def f(g: float, r: np.ndarray = r, shift: float = shift) -> float:
            return float(np.exp(stats.norm.logpdf(g, prior.mean, prior.sd)
                                + np.sum(stats.norm.logpdf(r, g, sigma)) + 40.0))

        val, _ = integrate.quad(f, shift - 3.0, shift + 3.0, epsabs=0, epsrel=1e-11,
                                limit=200)
        total += math.log(val) - 40.0
    return total


def test_marginalised_gain_matches_numerical_integration() -> None:
    y, log_mu, sigma, prior = _case()
    ll = marginal_log_likelihood(y, log_mu, sigma, prior)
    for w in range(3):
        assert ll[w] == pytest.approx(_quad(y, log_mu[w], float(sigma[w]), prior), abs=1e-7)


def test_bayes_identity_ties_the_pointwise_terms_to_the_marginal() -> None:
    """Log p(y|theta) = sum_i log p(y_i|g) + log p(g) - log p(g|y, theta), for any g."""
    y, log_mu, sigma, prior = _case(1)
    ll = marginal_log_likelihood(y, log_mu, sigma, prior)
    mean, sd = gain_conditional(y, log_mu, sigma, prior)
    rng = np.random.default_rng(3)
    for _ in range(3):
        g = mean + sd * rng.normal(0.0, 2.0, mean.shape)      # any gain, not only the mode
        pw = pointwise_log_likelihood(y, log_mu, sigma, g)
        assert np.isnan(pw[:, 1, 2]).all() and np.isnan(pw[:, :, 7]).all()
        rhs = (np.nansum(pw, axis=(1, 2))
               + stats.norm.logpdf(g, prior.mean, prior.sd).sum(axis=1)
               - stats.norm.logpdf(g, mean, sd).sum(axis=1))
        np.testing.assert_allclose(rhs, ll, rtol=0, atol=1e-9)


def test_gain_conditional_is_the_exact_posterior_of_the_gain() -> None:
    y, log_mu, sigma, prior = _case(2)
    mean, sd = gain_conditional(y, log_mu, sigma, prior)
    for c in range(2):
        ok = np.isfinite(y[c])
        r = y[c, ok] - log_mu[1, ok]

        def dens(g: float, k: int, r: np.ndarray = r) -> float:
            lp = stats.norm.logpdf(g, prior.mean, prior.sd) + np.sum(
                stats.norm.logpdf(r, g, sigma[1]))
            return float(g**k * np.exp(lp + 30.0))

        lo, hi = float(np.mean(r)) - 2.0, float(np.mean(r)) + 2.0
        z = integrate.quad(dens, lo, hi, args=(0,), epsrel=1e-12)[0]
        m1 = integrate.quad(dens, lo, hi, args=(1,), epsrel=1e-12)[0] / z
        m2 = integrate.quad(dens, lo, hi, args=(2,), epsrel=1e-12)[0] / z
        assert mean[1, c] == pytest.approx(m1, abs=1e-8)
        assert sd[1, c] == pytest.approx(math.sqrt(m2 - m1 * m1), rel=1e-6)


def test_unobserved_points_drop_out_and_failed_sweeps_are_impossible() -> None:
    y, log_mu, sigma, prior = _case(4)
    keep = np.isfinite(y).any(axis=0)
    a = marginal_log_likelihood(y, log_mu, sigma, prior)
    b = marginal_log_likelihood(y[:, keep], log_mu[:, keep], sigma, prior)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    bad = log_mu.copy()
    bad[0, 7] = np.nan          # at the bridging point: no effect
    bad[1, 0] = -np.inf         # at an observed point: impossible
    out = marginal_log_likelihood(y, bad, sigma, prior)
    assert out[0] == pytest.approx(a[0]) and out[1] == -np.inf and out[2] == a[2]
    assert marginal_log_likelihood(y, log_mu, np.array([0.1, 0.0, 0.2]), prior)[1] == -np.inf
    with pytest.raises(ValueError, match="shapes"):
        marginal_log_likelihood(y, log_mu[:, :3], sigma, prior)
    with pytest.raises(ValueError, match="sd > 0"):
        GainPrior(0.0, 0.0)


def test_the_gain_is_recovered_from_noise_free_curves() -> None:
    log_mu = np.log(np.linspace(1.0, 30.0, 50))[None, :]
    y = np.log([[0.004], [0.02]]) + log_mu
    mean, sd = gain_conditional(y, log_mu, np.array([0.05]), GainPrior(math.log(0.01), 3.0))
    np.testing.assert_allclose(np.exp(mean[0]), [0.004, 0.02], rtol=1e-3)
    assert np.all(sd < 0.01)


def test_acceleration_arms_weights_harmonic_h_by_h_to_the_fourth() -> None:
    f = np.array([1000.0, 2000.0])
    d = np.array([[1e-6, 2e-7, 1e-7], [3e-6, 0.0, 0.0]])
    expect = (2 * np.pi * f) ** 2 * np.sqrt(np.array(
        [1e-12 + 16 * 4e-14 + 81 * 1e-14, 9e-12]))
    np.testing.assert_allclose(acceleration_arms(d, f), expect, rtol=1e-12)


def test_jump_frequencies_per_direction() -> None:
    f = np.array([1.0, 2.0, 3.0, 4.0, 4.0, 3.0, 2.0, 1.0]) * 1000.0
    direction = np.array(["up"] * 4 + ["down"] * 4, dtype=object)
    y = np.log(np.array([[1.0, 1.2, 5.0, 1.1, 1.0, 3.0, 0.9, 0.8],
                         [1.0, 4.0, 4.1, 4.2, 4.0, 3.0, 2.9, 0.5]]))
    j = jump_frequencies(y, f, direction)
    # row 0 up: |log(1.1 / 5)| beats log(5 / 1.2); row 1 up: 1 -> 4
    np.testing.assert_allclose(j["up"], [math.sqrt(3000.0 * 4000.0),
                                         math.sqrt(1000.0 * 2000.0)])
    np.testing.assert_allclose(j["down"], [math.sqrt(3000.0 * 2000.0),
                                           math.sqrt(2000.0 * 1000.0)])
    # measured curves: steps averaged over the channels observed at both points
    y2 = y.copy()
    y2[1, 1] = np.nan        # channel 2's 1 -> 4 step is gone; 2 -> 3 kHz is channel 1's
    both = jump_frequencies(y2, f, direction, channels_first=True)   # 1.43, 3 -> 4 kHz 0.75
    assert both["up"] == pytest.approx(math.sqrt(2000.0 * 3000.0))
    assert both["down"] == pytest.approx(math.sqrt(2000.0 * 1000.0))
    none = jump_frequencies(y[0], f, np.array(["hold"] * 8, dtype=object))
    assert np.isnan(none["up"]) and np.isnan(none["down"])
