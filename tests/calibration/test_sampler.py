"""The emcee driver: autocorrelation time, convergence rule, reproducibility, flags."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import emcee
import numpy as np
import pytest
from emcee.autocorr import integrated_time as emcee_integrated_time

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.sampler import (
    MapEstimate,
    SamplerSettings,
    find_map,
    is_converged,
    reset_floor,
    reset_stragglers,
    run_sampler,
)

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


# A skewed positive parameter (log-normal, median 0.05, sigma 0.8: its quantiles are known in
# closed form) beside a plain normal one, for the log coordinates of item 5.
LN_MEDIAN, LN_SIGMA = 0.05, 0.8
SKEW_PRIORS = (prior_from_mapping({"dist": "halfnormal", "sd": 1.0}),
               prior_from_mapping({"dist": "uniform", "lower": -20.0, "upper": 20.0}))


def skewed(theta: np.ndarray) -> np.ndarray:
    t = np.atleast_2d(theta)
    x, y = t[:, 0], t[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        lx = np.log(np.where(x > 0, x, 1.0))
        lp = -lx - 0.5 * ((lx - np.log(LN_MEDIAN)) / LN_SIGMA) ** 2 - 0.5 * (y - 1.0) ** 2
    return np.where((x > 0) & (np.abs(y) <= 20.0), lp, -np.inf)


def test_log_coordinates_sample_the_density_in_its_own_units() -> None:
    """Walkers in ``ln x`` must still give draws of ``p(x)``, not of ``p(x(u))``.

    Without the Jacobian the draws of ``x`` would follow ``p(x) / x``: a log-normal with the
    median moved down by ``exp(-sigma^2)`` (0.53 here), which the quantile check rejects.
    """
    run = run_sampler(skewed, SKEW_PRIORS, SamplerSettings(walkers=16, max_steps=20000, seed=4),
                      log_scale=(True, False))
    assert run.converged
    s = run.samples().reshape(-1, 2)
    assert np.all(s[:, 0] > 0)
    z = np.array([-1.6448536269514722, 0.0, 1.6448536269514722])     # normal 5/50/95 %
    want = LN_MEDIAN * np.exp(LN_SIGMA * z)
    got = np.quantile(s[:, 0], [0.05, 0.5, 0.95])
    # draws ~ W * kept / (2 ... ) effective: a 6 % band on each log quantile is > 4 se here
    np.testing.assert_allclose(np.log(got), np.log(want), atol=0.06 * 1.65 * LN_SIGMA + 0.02)
    assert abs(np.median(s[:, 1]) - 1.0) < 0.05
    # the stored log posterior is the caller's, in the parameters' units (no Jacobian)
    flat = run.chain.reshape(-1, 2)
    np.testing.assert_allclose(run.log_prob.reshape(-1), skewed(flat), rtol=0, atol=1e-9)


def test_log_coordinates_shorten_tau_of_a_skewed_parameter() -> None:
    """Log coordinates shorten ``tau`` of a skewed parameter (the point of item 5).

    On the same steps and seed, ``tau`` in ``ln x`` is well under its value in ``x``.
    """
    st = SamplerSettings(walkers=16, max_steps=4000, seed=9)
    lin = run_sampler(skewed, SKEW_PRIORS, st)
    log = run_sampler(skewed, SKEW_PRIORS, st, log_scale=(True, False))
    assert log.tau[0] < 0.8 * lin.tau[0], (log.tau, lin.tau)


# A gap parameter b (uniform on [0, 300]) whose posterior, like the FVMS backlash on a
# VVMS-made run-up, has half its mass in a sliver b <= 3 (density 99 times the plateau's)
# reached along a ridge on which a second parameter z moves by 10 sd (0 below b = 3, 1
# above b = 10). Exact: P(b <= 3) = 3 * 99 / (3 * 99 + 297) = 0.5.
GAP_PRIORS = (prior_from_mapping({"dist": "uniform", "lower": 0.0, "upper": 300.0}),
              prior_from_mapping({"dist": "uniform", "lower": -5.0, "upper": 5.0}))


def gap(theta: np.ndarray) -> np.ndarray:
    th = np.atleast_2d(theta)
    b, z = th[:, 0], th[:, 1]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        mu = 1.0 / (1.0 + np.exp(-(np.log(b) - np.log(5.5)) / 0.15))
        lp = np.where(b <= 3.0, np.log(99.0), 0.0) - 0.5 * ((z - mu) / 0.1) ** 2
    return np.where((b > 0.0) & (b <= 300.0) & (np.abs(z) <= 5.0), lp, -np.inf)


def test_log_coordinates_find_a_sliver_at_the_lower_bound() -> None:
    """Walkers started on the plateau find the b <= 3 sliver in ``ln b``, not in ``b``.

    Why the run-up backlash is moved in ``ln x`` (``RunUpPosterior.log_scale``). In ``b`` no
    seed puts a draw there (every run "converges" on the plateau, P = 0); in ``ln b`` seeds
    2-13 gave P(b <= 3) 0.46-0.52. Seed 1 stopped at 800 steps with the autocorrelation
    rule met before a walker had come down the ridge (P = 0.003): no rule on ``tau`` sees a
    region no walker has visited, hence 3 of 4 seeds here.
    """
    start = np.array([150.0, 1.0])
    plateau = MapEstimate(theta=start, log_prob=float(gap(start)[0]), optima=start[None],
                          optima_log_prob=gap(start))
    found = 0
    for seed in (1, 2, 3, 4):
        st = SamplerSettings(walkers=16, max_steps=10000, seed=seed)
        run = run_sampler(gap, GAP_PRIORS, st, map_estimate=plateau, log_scale=(True, False))
        found += abs(np.mean(run.samples()[..., 0] <= 3.0) - 0.5) < 0.1
        if seed <= 2:
            lin = run_sampler(gap, GAP_PRIORS, st, map_estimate=plateau)
            assert np.mean(lin.samples()[..., 0] <= 3.0) < 0.05
    assert found >= 3


def test_log_coordinates_need_a_positive_support() -> None:
    with pytest.raises(ValueError, match="reaches below 0"):
        run_sampler(gaussian, PRIORS, SamplerSettings(walkers=8, max_steps=10),
                    log_scale=(True, False))
    with pytest.raises(ValueError, match="1 entries for 2"):
        run_sampler(gaussian, PRIORS, SamplerSettings(walkers=8, max_steps=10),
                    log_scale=(True,))


def test_log_coordinates_resume_bit_for_bit(tmp_path: Path) -> None:
    """A checkpointed run in log coordinates stopped early and continued equals one run."""
    st = SamplerSettings(walkers=8, max_steps=400, check_every=50, seed=2)
    whole = run_sampler(skewed, SKEW_PRIORS, st, log_scale=(True, False))
    ck = tmp_path / "c.h5"
    with pytest.raises(_StopError):
        run_sampler(skewed, SKEW_PRIORS, st, checkpoint=ck, log_scale=(True, False),
                    progress=_stop_at(150))
    again = run_sampler(skewed, SKEW_PRIORS, st, checkpoint=ck, log_scale=(True, False))
    assert again.resumed_from == 150
    np.testing.assert_array_equal(again.chain, whole.chain)
    np.testing.assert_array_equal(again.log_prob, whole.log_prob)
    # the same file in natural coordinates is a different chain: it must not resume
    other = run_sampler(skewed, SKEW_PRIORS, st, checkpoint=ck)
    assert other.resumed_from == 0


class _StopError(Exception):
    pass


def _stop_at(step: int) -> Callable[[int, int, float | None], None]:
    def progress(s: int, m: int, tau: float | None) -> None:
        if s >= step:
            raise _StopError
    return progress


def _state(coords: np.ndarray, lp: np.ndarray) -> emcee.State:
    return emcee.State(coords, log_prob=lp, random_state=np.random.RandomState(0).get_state())


def test_a_stranded_walker_is_moved_and_a_tail_walker_is_not() -> None:
    """The reset rule (module notes, 4) tells a slow tail from a stranded walker.

    100-step mean log posteriors of 16 walkers in 6 dimensions, the ensemble within 1 of its
    median: a walker 5 below (a draw from a slow tail: under the chi-square floor of 8.55)
    stays, one 20 below is moved onto the others.
    """
    rng = np.random.default_rng(0)
    d, w = 6, 16
    coords = rng.standard_normal((w, d))
    chain = np.repeat((-3.0 + 0.3 * rng.standard_normal(w))[None, :], 100, axis=0)
    tail = chain.copy()
    tail[:, 3] -= 5.0
    stranded = chain.copy()
    stranded[:, 3] -= 20.0
    coords[3] += 40.0                       # far from the rest

    def lp(theta: np.ndarray) -> np.ndarray:
        return -0.5 * np.sum(np.atleast_2d(theta) ** 2, axis=1)

    _, moved = reset_stragglers(_state(coords, tail[-1]), tail, lp, seed=1, iteration=100)
    assert not moved
    st, moved = reset_stragglers(_state(coords, stranded[-1]), stranded, lp, seed=1,
                                  iteration=100)
    assert moved
    new = np.asarray(st.coords)
    assert np.max(np.abs(new[3])) < 5.0                  # now among the others
    np.testing.assert_array_equal(np.delete(new, 3, axis=0), np.delete(coords, 3, axis=0))
    assert reset_floor(6) == pytest.approx(0.5 * (22.4577 - 5.34812), abs=1e-3)  # chi2 tables


def test_no_walker_of_a_skewed_posterior_is_taken_for_stranded() -> None:
    """A sampler in good health on a skewed posterior moves no walker.

    Six parameters, three of them log-normal (sigma 1.5 in ``ln x``) and correlated (0.9: the
    run-up posterior's error parameters trade like this), moved in their own units. Under the
    former flat floor (3 in log density) the seed-1 run moved one at step 300.
    """
    corr = np.array([[1.0, 0.9, 0.0], [0.9, 1.0, 0.3], [0.0, 0.3, 1.0]])
    prec = np.linalg.inv(corr)

    def lp(theta: np.ndarray) -> np.ndarray:
        t = np.atleast_2d(theta)
        pos = np.all(t[:, :3] > 0, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.log(np.where(t[:, :3] > 0, t[:, :3], 1.0))
        out = (-np.einsum("ij,jk,ik->i", z / 1.5, prec, z / 1.5) / 2 - z.sum(axis=1)
               - 0.5 * np.sum(t[:, 3:] ** 2, axis=1))
        return np.where(pos, out, -np.inf)

    priors = (prior_from_mapping({"dist": "halfnormal", "sd": 10.0}),) * 3 + \
        (prior_from_mapping({"dist": "uniform", "lower": -20.0, "upper": 20.0}),) * 3
    for seed in (1, 2, 3):
        run = run_sampler(lp, priors, SamplerSettings(walkers=16, max_steps=2400, seed=seed))
        assert run.resets == (), seed


def test_the_warm_up_from_a_far_start_is_left_out_of_tau() -> None:
    """From a ball ~16 sd away (a poor MAP) the ensemble first travels to the posterior.

    Over the whole chain ``tau`` measures that travel; over the chain after
    :func:`warm_up_end` it is the mixing time of a run started at the mode, and the draws
    after the burn-in have the posterior's mean and covariance.
    """
    start = np.array([19.0, 19.0])
    far = MapEstimate(theta=start, log_prob=float(gaussian(start)[0]), optima=start[None, :],
                      optima_log_prob=gaussian(start))
    st = SamplerSettings(walkers=16, max_steps=20000, seed=3)
    run = run_sampler(gaussian, PRIORS, st, map_estimate=far)
    near = run_sampler(gaussian, PRIORS, st)
    assert run.converged
    warm = run.tau_history[-1][2]
    assert warm > 0 and run.burn_in >= warm
    whole = integrated_time(run.chain[: run.n_steps])
    assert np.max(whole) > 1.5 * np.max(run.tau), (whole, run.tau)   # the travel, left out
    assert np.max(run.tau) < 1.3 * np.max(near.tau), (run.tau, near.tau)
    s = run.samples().reshape(-1, 2)
    np.testing.assert_allclose(s.mean(axis=0), MEAN, atol=0.1)
    np.testing.assert_allclose(np.cov(s.T), COV, rtol=0.1, atol=0.05)


def test_the_stability_condition_tells_a_growing_tau_from_a_noisy_one() -> None:
    """Module notes, 3: the chain 3000 steps past its warm-up, tau estimated every 100 steps.

    A tau that still grows with the chain, ``tau ~ sqrt(N)`` (40 at 3000: 75 tau, long
    enough by length alone), is not converged: over the last fifth it grew by 11 %. A tau
    of 40 whose estimates scatter by +-3 % from check to check (as the run-up's do) is.
    """
    steps = list(range(1000, 3001, 100))
    growing = [(n, (40.0 * math.sqrt(n / 3000), 10.0), 0) for n in steps]
    assert not is_converged(growing)
    wobble = [(n, (40.0 * (1 + 0.03 * (-1) ** k), 10.0), 0) for k, n in enumerate(steps)]
    assert is_converged(wobble)
    short = [(n, (80.0, 10.0), 0) for n in steps]          # 3000 < 50 * 80
    assert not is_converged(short)
    # counted from the warm-up: 3000 steps of which the first 1200 are travel
    assert not is_converged([(n, t, 1200) for n, t, _ in wobble])
