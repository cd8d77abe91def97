"""The emcee driver: autocorrelation time, convergence rule, reproducibility, flags."""

from __future__ import annotations

import numpy as np
import pytest
from emcee.autocorr import integrated_time as emcee_integrated_time

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.sampler import SamplerSettings, find_map, run_sampler

PRIORS = (prior_from_mapping({"dist": "uniform", "lower": -20.0, "upper": 20.0}),
          prior_from_mapping({"dist": "uniform", "lower": -20.0, "upper": 20.0}))
MEAN = np.array([1.0, -2.0])
COV = np.array([[1.0, 0.8], [0.8, 2.0]])
PREC = np.linalg.inv(COV)


def gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MEAN
    lp = -0.5 * np.einsum("ij,jk,ik->i", d, PREC, d)
    inside = np.all(np.abs(np.atleast_2d(theta)) <= 20.0, axis=1)
    return np.where(inside, lp, -np.inf)


def test_integrated_time_equals_emcee() -> None:
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.standard_normal((3000, 16, 3)), axis=0) * 0.05 \
        + rng.standard_normal((3000, 16, 3))
    np.testing.assert_allclose(integrated_time(x),
                               emcee_integrated_time(x, tol=0, quiet=True), rtol=1e-10)


def test_integrated_time_of_ar1_is_19() -> None:
    """AR(1) with coefficient 0.9: tau = (1 + 0.9) / (1 - 0.9) = 19 (emcee's test case)."""
    rng = np.random.default_rng(2)
    x = np.zeros((40000, 8, 1))
    e = rng.standard_normal(x.shape)
    for t in range(1, x.shape[0]):
        x[t] = 0.9 * x[t - 1] + e[t]
    assert integrated_time(x)[0] == pytest.approx(19.0, rel=0.06)


def test_map_of_a_gaussian() -> None:
    m = find_map(gaussian, PRIORS, starts=3, seed=1)
    np.testing.assert_allclose(m.theta, MEAN, atol=1e-4)


def test_a_gaussian_posterior_is_recovered_and_converged() -> None:
    run = run_sampler(gaussian, PRIORS, SamplerSettings(walkers=16, max_steps=20000, seed=3))
    assert run.converged
    assert run.n_steps > 50 * run.tau.max()
    s = run.samples().reshape(-1, 2)
    n_eff = s.shape[0] / 1.0
    assert n_eff > 1000
    # 5 standard errors of the mean with ESS ~ draws * 16 walkers / tau (thinned to tau / 2)
    se = np.sqrt(np.diag(COV) / (run.samples().shape[0] * run.samples().shape[1] / 2.0))
    np.testing.assert_array_less(np.abs(s.mean(axis=0) - MEAN), 5 * se + 0.02)
    np.testing.assert_allclose(np.cov(s.T), COV, rtol=0.1, atol=0.05)
    assert 0.15 < run.acceptance_fraction.mean() < 0.8
    assert run.burn_in >= 2 * run.tau.max() and run.thin >= 1


def test_seeded_runs_are_identical_and_seeds_matter() -> None:
    st = SamplerSettings(walkers=8, max_steps=300, seed=5)
    a = run_sampler(gaussian, PRIORS, st)
    b = run_sampler(gaussian, PRIORS, st)
    c = run_sampler(gaussian, PRIORS, SamplerSettings(walkers=8, max_steps=300, seed=6))
    assert np.array_equal(a.chain, b.chain)
    assert not np.array_equal(a.chain, c.chain)


def test_the_step_cap_flags_a_chain_that_did_not_converge() -> None:
    run = run_sampler(gaussian, PRIORS, SamplerSettings(walkers=8, max_steps=200, seed=1))
    assert not run.converged and run.n_steps == 200
    assert any(n.startswith("not converged: 200 steps reached max_steps = 200") for n in
               run.notes)


def test_progress_is_reported_at_every_check() -> None:
    seen: list[tuple[int, int, float | None]] = []
    run_sampler(gaussian, PRIORS, SamplerSettings(walkers=8, max_steps=350, check_every=100,
                                                   seed=1),
                progress=lambda s, m, tau: seen.append((s, m, tau)))
    assert [s for s, _, _ in seen] == [100, 200, 300, 350]
    assert all(m == 350 and tau is not None and tau > 0 for _, m, tau in seen)
