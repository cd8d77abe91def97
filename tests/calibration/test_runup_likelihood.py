"""The run-up likelihood against dense Gaussians and quadrature; leave-one-out terms; jumps.

Independent routes: the full covariance of every observed ``log A`` built entry by entry
(white channel error, the shared model error's correlation as the product of the chain's
``rho`` between two points, the gain prior per channel) with scipy's multivariate Normal and
Gaussian conditioning; quadrature for the ``tau = 0`` limit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, linalg, stats

from rigtools.calibration.runup_forward import acceleration_arms, jump_frequencies
from rigtools.calibration.runup_likelihood import (
    MAX_CORRELATION,
    MIN_CHANNEL_ERROR,
    GainPrior,
    error_gaps,
    gain_conditional,
    marginal_log_likelihood,
    pointwise_log_likelihood,
    sample_model_error,
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


#: Nine points: an up stretch of five, a down stretch of four (point 7 unobserved).
_F = np.array([800.0, 850.0, 930.0, 960.0, 1100.0, 1090.0, 1000.0, 990.0, 870.0])
_DIR = np.array(["up"] * 5 + ["down"] * 4, dtype=object)
_ELL = np.array([0.05, 0.3, 0.0, 2.0])     # W 2: independent points


def _correlation(gaps: np.ndarray, ell: float) -> np.ndarray:
    """Correlation of the shared error between every two points: the product of the links."""
    n = gaps.size + 1
    rho = np.minimum(np.exp(-gaps / ell), MAX_CORRELATION) if ell > 0 else np.zeros(n - 1)
    r = np.eye(n)
    for i in range(n):
        for j in range(i + 1, n):
            r[i, j] = r[j, i] = np.prod(rho[i:j])
    return r


def _dense(y: np.ndarray, log_mu: np.ndarray, tau: float, sigma: float,
           prior: GainPrior, ell: float = 0.0
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The observed log A as one Normal vector: its mean, covariance, and the index maps."""
    c_idx, i_idx = np.nonzero(np.isfinite(y))
    corr = _correlation(error_gaps(_F[:y.shape[1]], _DIR[:y.shape[1]]), ell)
    same_channel = c_idx[:, None] == c_idx[None, :]
    cov = (sigma**2 * np.eye(c_idx.size) + tau**2 * corr[np.ix_(i_idx, i_idx)]
           + prior.sd**2 * same_channel)
    mean = prior.mean + log_mu[i_idx]
    return mean, cov, c_idx, i_idx


def _conditional(mean: np.ndarray, cov: np.ndarray, x: np.ndarray, out: np.ndarray) -> float:
    """The log density of x[out] given x[rest] under N(mean, cov), by conditioning."""
    rest = np.setdiff1d(np.arange(x.size), out)
    fac = linalg.cho_factor(cov[np.ix_(rest, rest)])
    k = linalg.cho_solve(fac, cov[np.ix_(rest, out)]).T
    m = mean[out] + k @ (x[rest] - mean[rest])
    c = cov[np.ix_(out, out)] - k @ cov[np.ix_(rest, out)]
    return float(stats.multivariate_normal(m, c).logpdf(x[out]))


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


@pytest.mark.parametrize("correlated", [False, True])
def test_marginal_matches_the_dense_multivariate_normal(correlated: bool) -> None:
    # independent route: the full covariance of every observed value, scipy's Normal
    gaps = error_gaps(_F, _DIR)
    for seed in range(3):
        y, log_mu, tau, sigma, prior = _case(seed)
        ell = _ELL if correlated else np.zeros(4)
        ll = marginal_log_likelihood(y, log_mu, tau, sigma, prior, error_length=ell, gaps=gaps)
        for w in range(4):
            mean, cov, c_idx, i_idx = _dense(y, log_mu[w], tau[w], sigma[w], prior, ell[w])
            ref = stats.multivariate_normal(mean, cov).logpdf(y[c_idx, i_idx])
            assert ll[w] == pytest.approx(ref, abs=1e-8)
    if not correlated:     # no length, or no gaps: the independent model
        np.testing.assert_array_equal(
            marginal_log_likelihood(y, log_mu, tau, sigma, prior),
            marginal_log_likelihood(y, log_mu, tau, sigma, prior, error_length=_ELL))


def test_without_the_shared_error_it_is_the_independent_model_by_quadrature() -> None:
    # limiting case tau = 0: each channel's gain integrates out alone (quadrature)
    y, log_mu, _, sigma, prior = _case()
    ll = marginal_log_likelihood(y, log_mu, np.zeros(4), sigma, prior)
    for w in range(4):
        assert ll[w] == pytest.approx(_quad(y, log_mu[w], float(sigma[w]), prior), abs=1e-7)


def test_leave_one_out_terms_are_the_dense_gaussian_conditionals() -> None:
    """Per point (channels together) and per block: log p(r_B | r_rest) by conditioning."""
    y, log_mu, tau, sigma, prior = _case(1)
    gaps = error_gaps(_F, _DIR)
    pw = pointwise_log_likelihood(y, log_mu, tau, sigma, prior, error_length=_ELL, gaps=gaps)
    blocks = np.array([0, 0, 0, 1, 1, 2, 2, 3, 3])       # block 3: point 7 unobserved, and 8
    pb = pointwise_log_likelihood(y, log_mu, tau, sigma, prior, error_length=_ELL, gaps=gaps,
                                  groups=blocks)
    assert pw.shape == (4, 9) and np.isnan(pw[:, 7]).all() and pb.shape == (4, 4)
    for w in range(4):
        mean, cov, _, i_idx = _dense(y, log_mu[w], tau[w], sigma[w], prior, _ELL[w])
        x = y[np.isfinite(y)]
        for i in range(9):
            if i != 7:
                ref = _conditional(mean, cov, x, np.flatnonzero(i_idx == i))
                assert pw[w, i] == pytest.approx(ref, abs=1e-8)
        for b in range(4):
            ref = _conditional(mean, cov, x, np.flatnonzero(blocks[i_idx] == b))
            assert pb[w, b] == pytest.approx(ref, abs=1e-8)
    # without a shared error and with gains known (a tight prior at the truth) the points are
    # independent and each term is the point's own Normal
    g = np.log([0.01, 0.03, 0.005])
    yy = np.where(np.isfinite(y), g[:, None] + log_mu[0][None, :] + 0.01 * np.sin(
        np.arange(27).reshape(3, 9)), np.nan)
    tight = GainPrior(0.0, 1e-7)
    shifted = yy - g[:, None]                           # gains folded into the data
    own = pointwise_log_likelihood(shifted, log_mu[:1], np.zeros(1), sigma[:1], tight)
    for i in range(9):
        ok = np.isfinite(yy[:, i])
        if ok.any():
            ref = stats.multivariate_normal(log_mu[0, i] + np.zeros(ok.sum()),
                                            sigma[0]**2 * np.eye(ok.sum())).logpdf(
                shifted[ok, i])
            assert own[0, i] == pytest.approx(ref, abs=1e-6)


def test_gain_conditional_is_the_exact_posterior_of_the_gains() -> None:
    # independent route: Gaussian conditioning on the joint of (g, observed log A)
    y, log_mu, tau, sigma, prior = _case(2)
    mean, cov = gain_conditional(y, log_mu, tau, sigma, prior, error_length=_ELL,
                                 gaps=error_gaps(_F, _DIR))
    for w in range(4):
        m, big, c_idx, _ = _dense(y, log_mu[w], tau[w], sigma[w], prior, _ELL[w])
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
    gaps = error_gaps(_F, _DIR)
    neg = marginal_log_likelihood(y, log_mu, tau, sigma, prior,
                                  error_length=np.array([0.1, -1.0, 0.1, 0.1]), gaps=gaps)
    assert neg[1] == -np.inf and np.isfinite(neg[[0, 2, 3]]).all()
    with pytest.raises(ValueError, match="gaps"):
        marginal_log_likelihood(y, log_mu, tau, sigma, prior, error_length=_ELL,
                                gaps=gaps[:3])
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
    # A softening resonance by hand: up and down on one grid (kHz), both with a steep peak
    # at 2 kHz that has no hysteresis (the largest step of all, 1 -> 20); the down curve
    # stays high at 5 and 4 kHz where the up curve is low (the band), so the up sweep leaves
    # the band between 5 and 6 kHz, the down sweep between 4 and 3 kHz.
    f = np.array([1, 2, 3, 4, 5, 6, 7, 7, 6, 5, 4, 3, 2, 1], dtype=float) * 1000.0
    direction = np.array(["up"] * 7 + ["down"] * 7, dtype=object)
    up = [1.0, 20.0, 1.5, 2.0, 2.5, 8.0, 3.0]
    down = [3.0, 8.0, 9.0, 10.0, 1.55, 20.0, 1.0]   # 7 -> 1 kHz; 1.55 vs 1.5: 3 %, no band
    flat = [1.0, 20.0, 1.5, 2.0, 2.5, 8.0, 3.0]
    y = np.log(np.array([up + down, flat + flat[::-1]]))
    j = jump_frequencies(y, f, direction)
    np.testing.assert_allclose(j["up"][0], math.sqrt(5000.0 * 6000.0))
    np.testing.assert_allclose(j["down"][0], math.sqrt(4000.0 * 3000.0))
    # no hysteresis, no jump, however steep the peak
    assert np.isnan(j["up"][1]) and np.isnan(j["down"][1])
    b = jump_frequencies(y, f, direction, brackets=True)
    np.testing.assert_array_equal(b["up"][0], [5000.0, 6000.0])
    np.testing.assert_array_equal(b["down"][0], [3000.0, 4000.0])
    assert b["up"].shape == (2, 2) and np.isnan(b["up"][1]).all()
    # two bands: a narrow one (20 % apart, at 2 kHz) with the larger step, and the wide one:
    # the jump leaves the widest
    up2 = [1.0, 20.0, 1.5, 2.0, 2.5, 8.0, 3.0]
    down2 = [3.0, 8.0, 9.0, 10.0, 1.55, 24.0, 1.0]  # 24 vs 20 at 2 kHz: 18 % apart
    y2 = np.log(np.array(up2 + down2))
    j2 = jump_frequencies(y2, f, direction)
    assert j2["up"] == pytest.approx(math.sqrt(5000.0 * 6000.0))
    assert j2["down"] == pytest.approx(math.sqrt(4000.0 * 3000.0))
    # measured curves: channels with their own gains (the differences cancel them), steps
    # and differences averaged over the channels observed at both points
    ch = np.stack([y[0], y[0] + math.log(0.3)])
    ch[0, 4] = np.nan                        # channel 1 misses the up point at 5 kHz
    both = jump_frequencies(ch, f, direction, channels_first=True)
    assert both["up"] == pytest.approx(math.sqrt(5000.0 * 6000.0))
    assert both["down"] == pytest.approx(math.sqrt(4000.0 * 3000.0))
    # the other direction interpolated in ln f_m: down points between the up points, its
    # peak at 2.1 kHz (the up one's at 2): one-point bands at the peak (the interpolation cuts
    # its top) lose to the two-point band over the fold
    fd = np.array([6.5, 5.5, 4.5, 3.5, 2.5, 2.1, 1.5]) * 1000.0
    f3 = np.r_[f[:7], fd]
    d3 = np.array(["up"] * 7 + ["down"] * 7, dtype=object)
    y3 = np.log(np.r_[up, [7.2, 9.0, 9.5, 1.7, 1.6, 16.0, 1.2]])
    j3 = jump_frequencies(y3, f3, d3, brackets=True)
    np.testing.assert_array_equal(j3["up"], [5000.0, 6000.0])
    np.testing.assert_array_equal(j3["down"], [3500.0, 4500.0])
    none = jump_frequencies(y[0], f, np.array(["hold"] * 14, dtype=object))
    assert np.isnan(none["up"]) and np.isnan(none["down"])


def test_a_hold_at_one_frequency_is_one_discrepancy() -> None:
    """Points at one frequency are correlated up to the cap, and stay finite and exact."""
    f = np.full(6, 1000.0)
    gaps = error_gaps(f, np.array(["hold"] * 6, dtype=object))
    assert np.all(gaps == 0.0)
    rng = np.random.default_rng(7)
    y = np.log(0.01) + 0.1 * rng.standard_normal((2, 6))
    log_mu = np.zeros((1, 6))
    prior = GainPrior(math.log(0.01), 1.0)
    ll = marginal_log_likelihood(y, log_mu, np.array([0.2]), np.array([0.05]), prior,
                                 error_length=np.array([0.1]), gaps=gaps)
    c_idx, i_idx = np.nonzero(np.isfinite(y))
    corr = np.full((6, 6), MAX_CORRELATION) ** np.abs(np.subtract.outer(range(6), range(6)))
    cov = (0.05**2 * np.eye(12) + 0.04 * corr[np.ix_(i_idx, i_idx)]
           + 1.0 * (c_idx[:, None] == c_idx[None, :]))
    ref = stats.multivariate_normal(prior.mean + np.zeros(12), cov).logpdf(y[c_idx, i_idx])
    assert ll[0] == pytest.approx(ref, abs=1e-6)


def test_error_gaps_break_at_a_change_of_direction() -> None:
    g = error_gaps(_F, _DIR)
    assert g.shape == (8,) and math.isinf(g[4]) and np.isfinite(np.delete(g, 4)).all()
    np.testing.assert_allclose(g[0], math.log(850.0 / 800.0))
    with pytest.raises(ValueError, match="direction"):
        error_gaps(_F, _DIR[:4])


def test_sampled_model_errors_have_the_modelled_covariance() -> None:
    """Draws along the chain: sample covariance against tau^2 times the product correlation."""
    gaps = error_gaps(_F, _DIR)
    m = 40000
    tau, ell = 0.3, 0.08
    d = sample_model_error(np.full(m, tau), np.full(m, ell), gaps, np.random.default_rng(3))
    ref = tau**2 * _correlation(gaps, ell)
    # sd of a sample covariance entry <= tau^2 sqrt(2 / m) = 6e-4; 5 sd
    np.testing.assert_allclose(np.cov(d, rowvar=False), ref, atol=5 * tau**2 * math.sqrt(2 / m))
    assert abs(np.corrcoef(d[:, 4], d[:, 5])[0, 1]) < 0.02      # up and down independent


def test_a_vanishing_channel_error_is_minus_infinity_never_an_exception() -> None:
    """Channels that agree exactly: ``-inf`` below MIN_CHANNEL_ERROR, never a LinAlgError.

    With noise-free synthetic data the likelihood grows as ``sigma -> 0``; no ``sigma`` down
    to 1e-300 may raise (walkers moving in ``ln sigma`` reached 1e-9 in a test before the
    floor, where the Schur complement was singular).
    """
    rng = np.random.default_rng(4)
    mu = np.log(np.linspace(1.0, 3.0, 12))
    delta = 0.05 * rng.standard_normal(12)
    y = np.stack([mu + delta + g for g in (0.1, -0.3, 0.2)])
    sig = np.array([1e-300, 1e-12, 1e-8, MIN_CHANNEL_ERROR, 1e-4, 1e-2])
    w = sig.size
    ll = marginal_log_likelihood(y, np.tile(mu, (w, 1)), np.full(w, 0.05), sig,
                                 GainPrior(0.0, 1.0), error_length=np.full(w, 0.1),
                                 gaps=error_gaps(np.exp(mu), np.array(["up"] * 12)))
    assert np.all(ll[sig < MIN_CHANNEL_ERROR] == -np.inf)
    assert np.all(np.isfinite(ll[sig >= MIN_CHANNEL_ERROR]))
    assert ll[3] > ll[4] > ll[5]          # it grows as sigma falls: the floor is what bounds it
