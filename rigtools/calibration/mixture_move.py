r"""An independence Metropolis-Hastings move from a mixture fitted to the chain so far.

emcee's ensemble moves (stretch, differential evolution) step from a walker's position along
lines through other walkers: on a near-Gaussian posterior in six dimensions they need 30-50
steps per independent draw, and between two regimes of a posterior (the FVMS run-up
posterior: a backlash of a few um with the back flank closing the gap, and the wide-gap
plateau) a walker crosses only when a line through another walker happens to land in the
other regime's narrow region. An independence proposal does not walk: each walker proposes a
fresh draw ``y`` from a density ``g`` fitted to the chain's draws so far and accepts it with

.. math:: \alpha = \min\{1,\; \frac{p(y)\, g(x)}{p(x)\, g(y)}\}

(Metropolis-Hastings with a proposal independent of the current point; Tierney 1994, "Markov
chains for exploring posterior distributions", Ann. Statist. 22, 1701), exact for any ``g``
whose support covers the posterior's. Where ``g`` is close to ``p`` most proposals are
accepted and successive draws are nearly independent; where a regime is in ``g`` with its own
component, a walker jumps there in one step.

``g`` (:class:`MixtureProposal`) is a mixture of multivariate Student-t densities (4 degrees of
freedom, shape the fitted covariance times 1.2^2: heavier tails than the posterior's, so that
``p / g`` stays bounded in the tails and the chain cannot stick there) on the components of
a Gaussian mixture fitted by :class:`sklearn.mixture.GaussianMixture` (1 to 3 components by
BIC) to the second half of the chain; every component keeps at least a tenth of the mixture's
weight over the number of components, so a regime the walkers rarely visit is proposed often
enough to be reached. Until a mixture is fitted the move is a stretch move.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

import emcee
import numpy as np
from scipy.special import gammaln, logsumexp

__all__ = [
    "MAX_COMPONENTS",
    "MixtureIndependenceMove",
    "MixtureProposal",
    "fit_mixture_proposal",
]

#: Largest number of mixture components tried (chosen by BIC).
MAX_COMPONENTS: Final = 3
#: Degrees of freedom of each Student-t component.
T_DOF: Final = 4.0
#: Scale of each component's shape over the fitted covariance.
INFLATION: Final = 1.2
#: Least weight of a component, as a share of 1 / (number of components).
MIN_WEIGHT_SHARE: Final = 0.1
#: Draws per parameter of each component needed before a mixture is fitted.
MIN_DRAWS_PER_DIM: Final = 20
#: Draws the mixture is fitted to at most (the latest; repeats then count once).
MAX_FIT_DRAWS: Final = 20000


@dataclass(frozen=True, eq=False)
class MixtureProposal:
    """A mixture of multivariate Student-t densities, ``g(u) = sum_k w_k t_nu(u; m_k, S_k)``.

    Attributes
    ----------
    weights : numpy.ndarray
        ``(K,)``, summing to 1.
    means : numpy.ndarray
        ``(K, D)``.
    chols : numpy.ndarray
        ``(K, D, D)`` lower Cholesky factors of the shapes ``S_k``.
    dof : float
        ``nu``.
    """

    weights: np.ndarray
    means: np.ndarray
    chols: np.ndarray
    dof: float

    def log_density(self, u: np.ndarray) -> np.ndarray:
        """``log g(u)``, ``(N, D) -> (N,)``."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        d = u.shape[1]
        nu = self.dof
        parts = []
        for w, m, chol in zip(self.weights, self.means, self.chols, strict=True):
            z = np.linalg.solve(chol, (u - m).T).T
            maha = np.sum(z * z, axis=1)
            log_det = float(np.sum(np.log(np.diag(chol))))
            c = (gammaln((nu + d) / 2) - gammaln(nu / 2) - 0.5 * d * math.log(nu * math.pi)
                 - log_det)
            parts.append(math.log(w) + c - 0.5 * (nu + d) * np.log1p(maha / nu))
        return np.asarray(logsumexp(np.stack(parts), axis=0))

    def sample(self, n: int, random: Any) -> np.ndarray:
        """``n`` draws, with ``random`` a :class:`numpy.random.RandomState` (emcee's)."""
        k = random.choice(self.weights.size, size=n, p=self.weights)
        z = random.standard_normal((n, self.means.shape[1]))
        scale = np.sqrt(self.dof / random.chisquare(self.dof, size=n))
        return self.means[k] + np.einsum("nij,nj->ni", self.chols[k], z) * scale[:, None]


def fit_mixture_proposal(points: np.ndarray, *, seed: int = 0) -> MixtureProposal | None:
    """Fit :class:`MixtureProposal` to draws (module notes).

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, D)`` draws in the walkers' coordinates (repeats count once).
    seed : int
        Seed of the mixture fit's initialisation (the fit is a pure function of its inputs).

    Returns
    -------
    MixtureProposal or None
        None with fewer than ``MIN_DRAWS_PER_DIM * D`` distinct finite draws.
    """
    from sklearn.mixture import GaussianMixture

    pts = np.asarray(points, dtype=float)
    # the latest draws (np.unique sorts its rows: cut before it, not after)
    pts = np.unique(pts[np.all(np.isfinite(pts), axis=1)][-MAX_FIT_DRAWS:], axis=0)
    n, d = pts.shape
    if n < MIN_DRAWS_PER_DIM * d:
        return None
    # whiten first: the parameters' scales differ by orders of magnitude
    mean = pts.mean(axis=0)
    sd = pts.std(axis=0)
    if not np.all(sd > 0):
        return None
    z = (pts - mean) / sd
    best = None
    for k in range(1, MAX_COMPONENTS + 1):
        if n < MIN_DRAWS_PER_DIM * d * k:
            break
        # k-means++ seeding without Lloyd iterations: no threaded k-means, so the fit is
        # the same whatever the thread count (a resumed run refits it)
        gm = GaussianMixture(k, covariance_type="full", reg_covar=1e-6, n_init=1,
                             init_params="k-means++", random_state=seed).fit(z)
        bic = gm.bic(z)
        if best is None or bic < best[0]:
            best = (bic, gm)
    assert best is not None
    gm = best[1]
    k = gm.n_components
    w = np.asarray(gm.weights_, dtype=float)
    w = np.maximum(w, MIN_WEIGHT_SHARE / k)
    w = w / w.sum()
    means = mean + np.asarray(gm.means_) * sd
    covs = np.asarray(gm.covariances_) * np.outer(sd, sd) * INFLATION ** 2
    chols = np.linalg.cholesky(covs)
    return MixtureProposal(w, means, chols, T_DOF)


class MixtureIndependenceMove(emcee.moves.Move):
    """Independence Metropolis-Hastings from :attr:`proposal`; a stretch move until it is set.

    ``counts`` holds ``[proposals, accepted]`` of the independence steps since construction.
    """

    def __init__(self) -> None:
        self.proposal: MixtureProposal | None = None
        self.fallback = emcee.moves.StretchMove()
        self.counts = np.zeros(2, dtype=np.int64)

    def propose(self, model: Any, state: emcee.State) -> tuple[emcee.State, np.ndarray]:
        """Every walker proposes a draw of the mixture and accepts it by the MH ratio."""
        g = self.proposal
        if g is None:
            return self.fallback.propose(model, state)
        if state.blobs is not None:
            raise ValueError("the mixture move does not carry blobs")
        nwalkers = state.coords.shape[0]
        q = g.sample(nwalkers, model.random)
        factors = g.log_density(state.coords) - g.log_density(q)
        new_lp, blobs = model.compute_log_prob_fn(q)
        if blobs is not None:
            raise ValueError("the mixture move does not carry blobs")
        with np.errstate(invalid="ignore"):
            accepted = np.log(model.random.rand(nwalkers)) < new_lp - state.log_prob + factors
        self.counts += (nwalkers, int(accepted.sum()))
        state = self.update(state, emcee.State(q, log_prob=new_lp), accepted)
        return state, accepted
