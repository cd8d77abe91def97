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


def _case(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, GainPrior]:
    rng = np.random.default_rng(seed)
    log_mu = rng.normal(0.0, 1.0, (4, 9))                      # W = 4 parameter sets
    y = (np.log([[0.01], [0.03], [0.005]]) + log_mu[0][None, :] + rng.normal(0, 0.2, 9)
         + rng.normal(0, 0.05, (3, 9)))
    y[1, [2, 5]] = np.nan                                       # channel 2 misses two points
    y[2, 3] = np.nan
    y[:, 7] = np.nan                                            # a bridging point
    tau = np.array([0.2, 0.0, 0.1, 0.4])                        # W 1: independent channels
    sigma = np.array([0.05, 0.35, 0.1, 0.02])
    return y, log_mu, tau, sigma, GainPrior(math.log(0.02), 1.5)


def _dense(y: np.ndarray, log_mu: np.ndarray, tau: float, sigma: float,
           prior: GainPrior) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The observed log A as one Normal vector: its mean, covariance, and the index maps."""
    c_idx, i_idx = np.nonzero(np.isfinite(y))
    same_point = i_idx[:, None] == i_idx[None, :]
    same_channel = c_idx[:, None] == c_idx[None, :]
    cov = (sigma**2 * np.eye(c_idx.size) + tau**2 * same_point
           + prior.sd**2 * same_channel)
    mean = prior.mean + log_mu[i_idx]
    return mean, cov, c_idx, i_idx


def _quad(y: np.ndarray, log_mu: np.ndarray, sigma: float, prior: GainPrior) -> float:
    """Log of int N(g; m0, s0) prod_i N(y_i; g + log mu_i, sigma) dg, channel by channel."""
    total = 0.0
    for c in range(y.shape[0]):
        ok = np.isfinite(y[c])
        r = y[c, ok] - log_mu[ok]
        shift = float(np.mean(r))

        def logf(g: float, r: np.ndarray = r) -> float:
            return float(stats.norm.logpdf(g, prior.mean, prior.sd)
                         + np.sum(stats.norm.logpdf(r, g, sigma)))

        top = logf(shift)           # scale so the integrand peaks near 1

        def f(g: float, top: float = top, logf=logf) -> float:
            return math.exp(logf(g) - top)

        val, _ = integrate.quad(f, shift - 3.0, shift + 3.0, epsabs=0, epsrel=1e-11,
                                limit=200)
        total += math.log(val) + top
    return total


def test_marginal_matches_the_dense_multivariate_normal() -> None:
    # independent route: the full covariance sigma^2 I + tau^2 (same point) + s0^2 (same
    # channel) of every observed value, and scipy's multivariate Normal
    for seed in range(3):
        y, log_mu, tau, sigma, prior = _case(seed)
        ll = marginal_log_likelihood(y, log_mu, tau, sigma, prior)
        for w in range(4):
            mean, cov, c_idx, i_idx = _dense(y, log_mu[w], tau[w], sigma[w], prior)
            ref = stats.multivariate_normal(mean, cov).logpdf(y[c_idx, i_idx])
            assert ll[w] == pytest.approx(ref, abs=1e-8)


def test_without_the_shared_error_it_is_the_independent_model_by_quadrature() -> None:
    # limiting case tau = 0: each channel's gain integrates out alone (quadrature)
    y, log_mu, _, sigma, prior = _case()
    ll = marginal_log_likelihood(y, log_mu, np.zeros(4), sigma, prior)
    for w in range(4):
        assert ll[w] == pytest.approx(_quad(y, log_mu[w], float(sigma[w]), prior), abs=1e-7)


def _mvn_logpdf(x: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    return np.array([stats.multivariate_normal(m, c).logpdf(v)
                     for v, m, c in zip(x, mean, cov, strict=True)])


def test_bayes_identity_ties_the_pointwise_terms_to_the_marginal() -> None:
    """Log p(y|theta) = sum_i log p(y_i|g) + log p(g) - log p(g|y, theta), for any g."""
    y, log_mu, tau, sigma, prior = _case(1)
    ll = marginal_log_likelihood(y, log_mu, tau, sigma, prior)
    mean, cov = gain_conditional(y, log_mu, tau, sigma, prior)
    rng = np.random.default_rng(3)
    c = y.shape[0]
    for _ in range(3):
        g = mean + rng.normal(0.0, 0.3, mean.shape)             # any gain, not only the mode
        pw = pointwise_log_likelihood(y, log_mu, tau, sigma, g)
        assert pw.shape == (4, 9) and np.isnan(pw[:, 7]).all()
        rhs = (np.nansum(pw, axis=1)
               + _mvn_logpdf(g, np.full_like(g, prior.mean),
                             np.broadcast_to(prior.sd**2 * np.eye(c), cov.shape))
               - _mvn_logpdf(g, mean, cov))
        np.testing.assert_allclose(rhs, ll, rtol=0, atol=1e-8)


def test_pointwise_terms_are_each_points_multivariate_normal() -> None:
    y, log_mu, tau, sigma, _ = _case(5)
    g = np.log([[0.01, 0.03, 0.005]] * 4)
    pw = pointwise_log_likelihood(y, log_mu, tau, sigma, g)
    for w in range(4):
        for i in range(9):
            ok = np.isfinite(y[:, i])
            if not ok.any():
                continue
            cov = sigma[w]**2 * np.eye(ok.sum()) + tau[w]**2
            ref = stats.multivariate_normal(g[w, ok] + log_mu[w, i], cov).logpdf(y[ok, i])
            assert pw[w, i] == pytest.approx(ref, abs=1e-10)


def test_gain_conditional_is_the_exact_posterior_of_the_gains() -> None:
    # independent route: Gaussian conditioning on the joint of (g, observed log A)
    y, log_mu, tau, sigma, prior = _case(2)
    mean, cov = gain_conditional(y, log_mu, tau, sigma, prior)
    for w in range(4):
        m, big, c_idx, _ = _dense(y, log_mu[w], tau[w], sigma[w], prior)
        a = (c_idx[:, None] == np.arange(3)[None, :]).astype(float)     # (n, C)
        cross = prior.sd**2 * a.T                                        # Cov(g, log A)
        gain = cross @ np.linalg.inv(big)
        ref_mean = prior.mean + gain @ (y[np.isfinite(y)] - m)
        ref_cov = prior.sd**2 * np.eye(3) - gain @ cross.T
        np.testing.assert_allclose(mean[w], ref_mean, atol=1e-9)
        np.testing.assert_allclose(cov[w], ref_cov, atol=1e-10)


def test_unobserved_points_drop_out_and_failed_sweeps_are_impossible() -> None:
    y, log_mu, tau, sigma, prior = _case(4)
    keep = np.isfinite(y).any(axis=0)
    a = marginal_log_likelihood(y, log_mu, tau, sigma, prior)
    b = marginal_log_likelihood(y[:, keep], log_mu[:, keep], tau, sigma, prior)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    bad = log_mu.copy()
    bad[0, 7] = np.nan          # at the bridging point: no effect
    bad[1, 0] = -np.inf         # at an observed point: impossible
    out = marginal_log_likelihood(y, bad, tau, sigma, prior)
    assert out[0] == pytest.approx(a[0]) and out[1] == -np.inf and out[2] == a[2]
    zero = marginal_log_likelihood(y, log_mu, tau, np.array([0.1, 0.0, 0.2, 0.1]), prior)
    assert zero[1] == -np.inf and np.isfinite(zero[[0, 2, 3]]).all()
    assert marginal_log_likelihood(y, log_mu, np.array([0.1, -0.1, 0.1, 0.1]), sigma,
                                   prior)[1] == -np.inf
    with pytest.raises(ValueError, match="shapes"):
        marginal_log_likelihood(y, log_mu[:, :3], tau, sigma, prior)
    with pytest.raises(ValueError, match="sd > 0"):
        GainPrior(0.0, 0.0)


def test_the_gains_are_recovered_from_noise_free_curves() -> None:
    log_mu = np.log(np.linspace(1.0, 30.0, 50))[None, :]
    y = np.log([[0.004], [0.02]]) + log_mu
    mean, cov = gain_conditional(y, log_mu, np.array([0.1]), np.array([0.01]),
                                 GainPrior(math.log(0.01), 3.0))
    np.testing.assert_allclose(np.exp(mean[0]), [0.004, 0.02], rtol=1e-3)
    # the shared error moves both gains together: their difference is the better known
    sd = np.sqrt(np.diag(cov[0]))
    sd_diff = math.sqrt(cov[0, 0, 0] + cov[0, 1, 1] - 2 * cov[0, 0, 1])
    assert np.all(sd < 0.03) and sd_diff < 0.5 * sd.min()


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
