"""The mixture independence move: exact for any proposal, and it crosses between regimes.

Targets with known answers: a gamma marginal beside a correlated normal pair (moments and
quantiles, as in ``test_delayed_acceptance.py``), and two separated Gaussian regimes with known
weights, between which the stretch and differential-evolution moves alone hardly ever cross.
"""

from __future__ import annotations

import math
from pathlib import Path

import emcee
import numpy as np
import pytest
from scipy import stats
from test_delayed_acceptance import K_GAMMA, Z_LIMIT, target, z_scores

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.mixture_move import (
    MixtureIndependenceMove,
    MixtureProposal,
    fit_mixture_proposal,
)
from rigtools.calibration.priors import prior_from_mapping
from rigtools.calibration.sampler import SamplerSettings, run_sampler


def _proposal(means: np.ndarray, scales: np.ndarray, weights: np.ndarray) -> MixtureProposal:
    chols = np.stack([np.diag(s) for s in scales])
    return MixtureProposal(np.asarray(weights, float), np.asarray(means, float), chols, 4.0)


def test_the_mixture_density_integrates_to_one_and_matches_its_draws() -> None:
    g = _proposal(np.array([[0.0, 0.0], [5.0, -2.0]]), np.array([[1.0, 0.5], [0.3, 2.0]]),
                  np.array([0.3, 0.7]))
    x = np.linspace(-25, 25, 801)
    xx, yy = np.meshgrid(x, x)
    dens = np.exp(g.log_density(np.c_[xx.ravel(), yy.ravel()]))
    assert dens.sum() * (x[1] - x[0]) ** 2 == pytest.approx(1.0, abs=0.01)
    # the first coordinate of a Student-t with a diagonal shape is a scaled t_4: the draws'
    # marginal is 0.3 t_4(0, 1) + 0.7 t_4(5, 0.3)
    draws = g.sample(100_000, np.random.RandomState(0))

    def cdf(v: np.ndarray) -> np.ndarray:
        return 0.3 * stats.t(4).cdf(v) + 0.7 * stats.t(4).cdf((v - 5.0) / 0.3)

    assert stats.kstest(draws[:, 0], cdf).pvalue > 1e-3


@pytest.mark.parametrize("kind", ["good", "shifted"])
def test_independence_steps_sample_the_exact_target(kind: str) -> None:
    """A fitted proposal and a deliberately misplaced one: the same answer within MC error."""
    if kind == "good":
        rng = np.random.default_rng(0)
        pts = np.c_[rng.gamma(K_GAMMA, size=4000),
                    rng.multivariate_normal([0, 0], [[1, 0.9], [0.9, 1]], 4000)]
        g = fit_mixture_proposal(pts, seed=1)
    else:
        g = _proposal(np.array([[5.0, 1.0, -1.0]]), np.array([[3.0, 2.0, 2.0]]),
                      np.array([1.0]))
    assert g is not None
    move = MixtureIndependenceMove()
    move.proposal = g
    sampler = emcee.EnsembleSampler(32, 3, target, vectorize=True,
                                    moves=[(emcee.moves.StretchMove(), 0.5), (move, 0.5)])
    sampler.random_state = np.random.RandomState(7).get_state()
    rng = np.random.default_rng(7)
    sampler.run_mcmc(np.c_[rng.gamma(K_GAMMA, size=32), rng.standard_normal((32, 2))], 5000,
                     skip_initial_state_check=True)
    z = z_scores(sampler.get_chain(discard=500))
    assert max(abs(v) for v in z.values()) < Z_LIMIT, z
    assert move.counts[0] > 0 and 0 < move.counts[1] <= move.counts[0]


# -- two regimes ---------------------------------------------------------------------------------

W_FAR = 0.3     # weight of the far regime
FAR = np.array([2.5, 2.5, 0.0])
BIMODAL_PRIORS = tuple(prior_from_mapping({"dist": "uniform", "lower": -20.0, "upper": 20.0})
                       for _ in range(3))
#: P(x0 > 1.25): 0.7 P(N(0, 1) > 1.25) + 0.3 P(N(2.5, 0.2^2) > 1.25) (the last is 1 - 2e-10)
FAR_SHARE = 0.7 * float(stats.norm.sf(1.25)) + 0.3 * float(stats.norm.sf(-1.25 / 0.2))


def two_regimes(theta: np.ndarray) -> np.ndarray:
    """0.7 N(0, diag(1, 0.2^2, 1)) + 0.3 N(FAR, diag(0.2^2, 1, 1)) in the prior box.

    An L, like FVMS's regimes (a small backlash at one damping, the plateau at another).
    """
    u = np.atleast_2d(theta)
    near = stats.multivariate_normal([0, 0, 0], np.diag([1.0, 0.04, 1.0])).logpdf(u)
    far = stats.multivariate_normal(FAR, np.diag([0.04, 1.0, 1.0])).logpdf(u)
    lp = np.logaddexp(math.log(1 - W_FAR) + near, math.log(W_FAR) + far)
    return np.where(np.all(np.abs(u) < 20.0, axis=1), lp, -np.inf)


def test_the_mixture_move_crosses_between_regimes_several_times_faster() -> None:
    """Independence steps cross the corner of the L faster than the ensemble moves alone.

    Alone, the tau of the regime indicator is ~60 steps; with independence steps from the
    refitted mixture it falls by more than half, and the share of draws past x0 = 1.25 is the
    target's within its Monte Carlo error either way.
    """
    taus = {}
    for mixture in (False, True):
        settings = SamplerSettings(walkers=20, max_steps=6000, check_every=100, seed=3,
                                   map_starts=2, mixture_move=mixture)
        run = run_sampler(two_regimes, BIMODAL_PRIORS, settings)
        assert run.converged
        chain = run.chain[run.burn_in:]
        ind = (chain[..., 0] > 1.25).astype(float)[..., None]
        taus[mixture] = tau = float(integrated_time(ind)[0])
        sd = math.sqrt(FAR_SHARE * (1 - FAR_SHARE) * tau / ind.size)
        assert abs(ind.mean() - FAR_SHARE) < Z_LIMIT * sd, (mixture, ind.mean(), sd)
        assert any(n.startswith("mixture move:") for n in run.notes) == mixture
    assert taus[True] < 0.5 * taus[False], taus


def test_a_run_with_both_adaptive_moves_killed_and_resumed_ends_bit_for_bit(
        tmp_path: Path) -> None:
    settings = SamplerSettings(walkers=20, max_steps=1200, check_every=100, seed=5,
                               map_starts=2, mixture_move=True, delayed_acceptance=True)
    whole = run_sampler(two_regimes, BIMODAL_PRIORS, settings, checkpoint=tmp_path / "a.h5")

    class StopError(Exception):
        pass

    def stop(step: int, max_steps: int, tau: float | None) -> None:
        if step >= 200:
            raise StopError

    with pytest.raises(StopError):
        run_sampler(two_regimes, BIMODAL_PRIORS, settings, checkpoint=tmp_path / "b.h5",
                    progress=stop)
    again = run_sampler(two_regimes, BIMODAL_PRIORS, settings, checkpoint=tmp_path / "b.h5")
    assert again.resumed_from == 200
    np.testing.assert_array_equal(whole.chain, again.chain)
