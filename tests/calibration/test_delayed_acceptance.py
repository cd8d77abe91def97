"""Delayed acceptance: exact sampling whatever the surrogate, fewer evaluations with a good one.

The targets have known moments and quantiles (a gamma marginal beside a correlated normal pair);
the chains' estimates are compared with them within their Monte Carlo error (effective sample
size from the integrated autocorrelation time), so a bias of the screen (a missing or wrong
second stage) fails the tests, while an honest chain passes at the stated z.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path

import emcee
import numpy as np
import pytest
from scipy import stats

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.delayed_acceptance import (
    DelayedAcceptanceMove,
    QuadraticSurrogate,
    fit_quadratic_surrogate,
)
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.sampler import SamplerSettings, run_sampler

K_GAMMA = 3.0           # shape of the gamma marginal of x0 (scale 1): mean 3, variance 3
RHO = 0.9               # correlation of the normal pair (x1, x2), unit variances
PAIR_PREC = np.linalg.inv(np.array([[1.0, RHO], [RHO, 1.0]]))
LOWER = np.array([0.0, -30.0, -30.0])
UPPER = np.array([60.0, 30.0, 30.0])
Z_LIMIT = 4.5           # |estimate - truth| / Monte Carlo sd; a correct chain passes w.p. ~1


def target(u: np.ndarray) -> np.ndarray:
    """Gamma(3) on x0 times a correlated standard normal pair on (x1, x2); -inf outside."""
    u = np.atleast_2d(u)
    inside = np.all((u > LOWER) & (u < UPPER), axis=1)
    x0 = np.where(inside, u[:, 0], 1.0)
    pair = u[:, 1:]
    lp = (K_GAMMA - 1.0) * np.log(x0) - x0 - 0.5 * np.einsum("ni,ij,nj->n", pair, PAIR_PREC,
                                                            pair)
    return np.where(inside, lp, -np.inf)


def flat_prior(u: np.ndarray) -> np.ndarray:
    u = np.atleast_2d(u)
    return np.where(np.all((u > LOWER) & (u < UPPER), axis=1), 0.0, -np.inf)


def _sample(surrogate: object, steps: int, seed: int, walkers: int = 32
            ) -> tuple[np.ndarray, list[DelayedAcceptanceMove], int]:
    evaluations = [0]

    def counted(u: np.ndarray) -> np.ndarray:
        evaluations[0] += u.shape[0]
        return target(u)

    moves = [DelayedAcceptanceMove(emcee.moves.DEMove()),
             DelayedAcceptanceMove(emcee.moves.StretchMove())]
    for m in moves:
        m.surrogate = surrogate  # type: ignore[assignment]
    sampler = emcee.EnsembleSampler(walkers, 3, counted, vectorize=True,
                                    moves=[(moves[0], 0.5), (moves[1], 0.5)])
    sampler.random_state = np.random.RandomState(seed).get_state()
    rng = np.random.default_rng(seed)
    start = np.c_[rng.gamma(K_GAMMA, size=walkers), rng.standard_normal((walkers, 2))]
    sampler.run_mcmc(start, steps, skip_initial_state_check=True)
    return sampler.get_chain(discard=steps // 10), moves, evaluations[0]


def z_scores(chain: np.ndarray) -> dict[str, float]:
    """Standardised errors of the mean, variance and quantiles of each coordinate."""
    tau = integrated_time(chain)
    flat = chain.reshape(-1, chain.shape[-1])
    n_eff = flat.shape[0] / tau
    truth_mean = np.array([K_GAMMA, 0.0, 0.0])
    truth_var = np.array([K_GAMMA, 1.0, 1.0])
    out = {}
    for i in range(3):
        out[f"mean{i}"] = (flat[:, i].mean() - truth_mean[i]) / math.sqrt(truth_var[i] / n_eff[i])
    # variance of x0: var(x0^2-ish) via the gamma's fourth central moment, 3 k (k + 2)
    m4 = 3.0 * K_GAMMA * (K_GAMMA + 2.0)
    out["var0"] = (flat[:, 0].var() - K_GAMMA) / math.sqrt((m4 - K_GAMMA ** 2) / n_eff[0])
    for q in (0.1, 0.5, 0.9):
        # P(x0 <= the true q-quantile) is a mean of indicators: sd sqrt(q (1 - q) / n_eff)
        hit = np.mean(flat[:, 0] <= stats.gamma.ppf(q, K_GAMMA))
        out[f"q{q}"] = (hit - q) / math.sqrt(q * (1 - q) / n_eff[0])
    return out


@pytest.mark.parametrize("surrogate_kind", ["shifted", "too_narrow", "flat"])
def test_a_wrong_surrogate_still_samples_the_exact_target(surrogate_kind: str) -> None:
    """Three bad screens (a Gaussian with the wrong centre, one 3x too narrow, a flat one)."""
    if surrogate_kind == "flat":
        def surrogate(u: np.ndarray) -> np.ndarray:
            return flat_prior(u)
    else:
        centre = np.array([6.0, 1.5, -1.5]) if surrogate_kind == "shifted" else \
            np.array([3.0, 0.0, 0.0])
        width = 1.0 if surrogate_kind == "shifted" else 1.0 / 3.0

        def surrogate(u: np.ndarray) -> np.ndarray:
            d = (np.atleast_2d(u) - centre) / width
            return flat_prior(u) - 0.5 * np.sum(d * d, axis=1)
    chain, moves, _ = _sample(surrogate, 6000, seed=11)
    z = z_scores(chain)
    assert max(abs(v) for v in z.values()) < Z_LIMIT, z
    proposals, screened, accepted = sum(m.counts for m in moves)
    assert proposals == 6000 * 32 and accepted <= screened <= proposals


def test_without_a_screen_the_second_stage_would_bias_the_chain() -> None:
    """The check above can fail: acceptance by the surrogate alone samples the surrogate.

    A move that accepts on the first stage and never looks at the target (``p := s``) must
    fail the same z-scores, so the test is sharp enough to see a missing second stage.
    """
    centre, width = np.array([6.0, 1.5, -1.5]), 1.0

    def surrogate(u: np.ndarray) -> np.ndarray:
        d = (np.atleast_2d(u) - centre) / width
        return flat_prior(u) - 0.5 * np.sum(d * d, axis=1)

    sampler = emcee.EnsembleSampler(32, 3, surrogate, vectorize=True,
                                    moves=[(emcee.moves.DEMove(), 0.5),
                                           (emcee.moves.StretchMove(), 0.5)])
    sampler.random_state = np.random.RandomState(11).get_state()
    rng = np.random.default_rng(11)
    sampler.run_mcmc(np.c_[rng.gamma(K_GAMMA, size=32), rng.standard_normal((32, 2))], 3000,
                     skip_initial_state_check=True)
    z = z_scores(sampler.get_chain(discard=300))
    assert max(abs(v) for v in z.values()) > 10 * Z_LIMIT


def test_the_exact_target_as_screen_accepts_every_screened_proposal_and_saves_evaluations(
) -> None:
    chain, moves, evaluations = _sample(target, 2000, seed=5)
    proposals, screened, accepted = sum(m.counts for m in moves)
    assert accepted == screened                      # alpha_2 = 1 when s = p
    # only screened proposals cost (and the start, which emcee evaluates once)
    assert evaluations - 32 == screened < 0.7 * proposals
    assert max(abs(v) for v in z_scores(chain).values()) < Z_LIMIT


def test_with_no_surrogate_it_is_the_wrapped_move_draw_for_draw() -> None:
    def run(wrap: bool) -> np.ndarray:
        inner = [emcee.moves.DEMove(), emcee.moves.StretchMove()]
        moves = [DelayedAcceptanceMove(m) for m in inner] if wrap else inner
        s = emcee.EnsembleSampler(16, 3, target, vectorize=True,
                                  moves=[(moves[0], 0.5), (moves[1], 0.5)])
        s.random_state = np.random.RandomState(3).get_state()
        start = np.c_[np.random.default_rng(3).gamma(K_GAMMA, size=16),
                      np.random.default_rng(4).standard_normal((16, 2))]
        s.run_mcmc(start, 200, skip_initial_state_check=True)
        return s.get_chain()
    np.testing.assert_array_equal(run(True), run(False))


def test_the_quadratic_fit_recovers_a_quadratic_log_likelihood_under_a_prior() -> None:
    """A Gaussian likelihood under a non-flat prior: the fit returns the likelihood exactly."""
    rng = np.random.default_rng(0)
    mean = np.array([1.0, -2.0, 0.5])
    prec = np.array([[2.0, 0.5, 0.0], [0.5, 1.0, 0.3], [0.0, 0.3, 4.0]])
    lower, upper = np.full(3, -50.0), np.full(3, 50.0)

    def prior(u: np.ndarray) -> np.ndarray:
        return -0.05 * np.sum(np.atleast_2d(u) ** 2, axis=1)

    def loglike(u: np.ndarray) -> np.ndarray:
        d = np.atleast_2d(u) - mean
        return 7.0 - 0.5 * np.einsum("ni,ij,nj->n", d, prec, d)

    pts = mean + rng.standard_normal((400, 3)) @ np.diag([0.7, 1.1, 0.5])
    s = fit_quadratic_surrogate(pts, loglike(pts) + prior(pts), prior, lower, upper)
    assert isinstance(s, QuadraticSurrogate) and s.rms < 1e-9
    test = mean + 2.0 * rng.standard_normal((50, 3))
    np.testing.assert_allclose(s(test), loglike(test) + prior(test), rtol=1e-9, atol=1e-8)
    assert s(np.array([[60.0, 0.0, 0.0]]))[0] == -np.inf


def test_a_flat_direction_gets_no_rising_bowl() -> None:
    """Data flat in x1 with noise: the fitted curvature along x1 is clipped to <= 0."""
    rng = np.random.default_rng(1)
    pts = rng.standard_normal((500, 2))
    lp = -0.5 * pts[:, 0] ** 2 + 0.01 * rng.standard_normal(500) + 0.02 * pts[:, 1] ** 2
    s = fit_quadratic_surrogate(pts, lp, lambda u: np.zeros(len(np.atleast_2d(u))),
                                np.full(2, -100.0), np.full(2, 100.0))
    assert s is not None
    assert np.all(np.linalg.eigvalsh(s.hessian) <= 1e-12)
    far = s(np.array([[0.0, 40.0]]))[0]
    assert far <= s(np.array([[0.0, 0.0]]))[0] + 40.0 * abs(s.gradient[1]) * 2 + 1e-9


def test_too_few_draws_give_no_surrogate() -> None:
    pts = np.random.default_rng(2).standard_normal((20, 3))
    assert fit_quadratic_surrogate(pts, -np.sum(pts ** 2, axis=1), lambda u: np.zeros(len(u)),
                                   np.full(3, -9.0), np.full(3, 9.0)) is None


# -- in the sampler -----------------------------------------------------------------------------

GAUSS_MEAN = np.array([1.0, -2.0, 0.5, 3.0])
GAUSS_COV = np.array([[1.0, 0.6, 0.0, 0.2], [0.6, 2.0, 0.3, 0.0],
                      [0.0, 0.3, 0.5, 0.1], [0.2, 0.0, 0.1, 1.5]])
GAUSS_PREC = np.linalg.inv(GAUSS_COV)
GAUSS_PRIORS = tuple(prior_from_mapping({"dist": "uniform", "lower": -30.0, "upper": 30.0})
                     for _ in range(4))


def gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - GAUSS_MEAN
    inside = np.all(np.abs(np.atleast_2d(theta)) < 30.0, axis=1)
    return np.where(inside, -0.5 * np.einsum("ni,ij,nj->n", d, GAUSS_PREC, d), -np.inf)


def test_the_sampler_screens_after_its_first_checks_and_keeps_the_posterior() -> None:
    settings = SamplerSettings(walkers=16, max_steps=4000, check_every=100, seed=4,
                               map_starts=2, delayed_acceptance=True)
    run = run_sampler(gaussian, GAUSS_PRIORS, settings)
    plain = run_sampler(gaussian, GAUSS_PRIORS, dataclasses.replace(
        settings, delayed_acceptance=False))
    proposals, screened, accepted = run.screen_counts
    assert proposals > 0.5 * 16 * run.n_steps and accepted <= screened < 0.7 * proposals
    assert any(n.startswith("delayed acceptance:") for n in run.notes)
    # a quadratic surrogate of a Gaussian is exact: the second stage accepts all it sees
    assert accepted == screened
    assert run.log_prob_evaluations / run.n_steps < 0.75 * (plain.log_prob_evaluations
                                                             / plain.n_steps)
    draws = run.samples().reshape(-1, 4)
    n_eff = draws.shape[0] / (max(run.tau) / max(1, run.thin))
    z = (draws.mean(axis=0) - GAUSS_MEAN) / np.sqrt(np.diag(GAUSS_COV) / n_eff)
    assert np.all(np.abs(z) < Z_LIMIT), z
    np.testing.assert_allclose(np.cov(draws, rowvar=False), GAUSS_COV, atol=0.25)


def test_a_screened_run_killed_and_resumed_ends_bit_for_bit(tmp_path: Path) -> None:
    """Killed inside the refitting window and after it: the surrogate is refitted as it was."""
    settings = SamplerSettings(walkers=16, max_steps=1600, check_every=100, seed=2,
                               map_starts=2, delayed_acceptance=True)
    whole = run_sampler(gaussian, GAUSS_PRIORS, settings, checkpoint=tmp_path / "a.h5")

    class StopError(Exception):
        pass

    def stop_at(n: int) -> Callable[[int, int, float | None], None]:
        def progress(step: int, max_steps: int, tau: float | None) -> None:
            if step >= n:
                raise StopError
        return progress

    for n in (300, 700):  # reset_until = 400
        with pytest.raises(StopError):
            run_sampler(gaussian, GAUSS_PRIORS, settings, checkpoint=tmp_path / "b.h5",
                        progress=stop_at(n))
    again = run_sampler(gaussian, GAUSS_PRIORS, settings, checkpoint=tmp_path / "b.h5")
    assert again.resumed_from == 700
    np.testing.assert_array_equal(whole.chain, again.chain)
    np.testing.assert_array_equal(whole.log_prob, again.log_prob)
