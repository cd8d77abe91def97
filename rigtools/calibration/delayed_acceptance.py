r"""Delayed acceptance for emcee's ensemble moves: a cheap surrogate screens each proposal.

A log posterior that needs a sweep per walker (the SDOF run-up calibration) spends most of a
step on proposals that are then rejected. Delayed acceptance (Christen and Fox 2005, "Markov
chain Monte Carlo using an approximation", J. Comput. Graph. Stat. 14, 795) screens each
proposal ``y`` of a walker at ``x`` with a cheap approximation ``s`` of the log posterior
``p`` first, and evaluates ``p`` only where the screen lets the proposal through:

.. math::

    \alpha_1 = \min\{1,\; f\, e^{s(y) - s(x)}\}, \qquad
    \alpha_2 = \min\{1,\; e^{[p(y) - p(x)] - [s(y) - s(x)]}\}

with ``f`` the move's proposal ratio (``z^{D-1}`` for the stretch move, 1 for differential
evolution). The product :math:`\alpha_1 \alpha_2` satisfies detailed balance with respect to
``p`` for any ``s`` (a short derivation: for :math:`\alpha_1(x, y) < 1`,
:math:`\alpha_1(y, x) = 1`, and the second-stage ratio
:math:`p(y) q_2(y, x) / (p(x) q_2(x, y))` with :math:`q_2 = \alpha_1 q` reduces to
:math:`e^{[p(y) - p(x)] - [s(y) - s(x)]}`; the same for :math:`\alpha_1(x, y) = 1`). So the
chain samples the exact posterior whatever the surrogate's error: a poor surrogate costs
mixing (second-stage rejections), never bias. Within emcee's red-blue scheme the update of a
half of the walkers against the other half fixed is an ordinary Metropolis-Hastings step per
walker, so the argument holds move by move (``tests/calibration/test_delayed_acceptance.py``
samples known targets with deliberately wrong surrogates).

The surrogate (:class:`QuadraticSurrogate`) is the exact log prior (with the Jacobian of the
walkers' coordinates) plus a quadratic in whitened coordinates fitted by least squares to
``log p - log prior`` of posterior draws already made (their exact values), its curvature
made negative semi-definite (a direction the data leave flat gets no rising bowl towards the
bounds). Outside the prior's support it is ``-inf``, so those proposals never cost a sweep.

What it saves: a proposal costs a full evaluation only with probability ``alpha_1``, about the
acceptance fraction; what it loses: the second-stage rejections, which lengthen ``tau``.
:class:`DelayedAcceptanceMove` counts both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

import emcee
import numpy as np

__all__ = [
    "MIN_POINTS_PER_FEATURE",
    "DelayedAcceptanceMove",
    "QuadraticSurrogate",
    "fit_quadratic_surrogate",
]

#: Distinct training draws required per coefficient of the quadratic before it is fitted.
MIN_POINTS_PER_FEATURE: Final = 5


def _features(z: np.ndarray) -> np.ndarray:
    """``[1, z_i, z_i z_j (i <= j)]`` per row, ``(N, D) -> (N, 1 + D + D (D + 1) / 2)``."""
    n, d = z.shape
    iu = np.triu_indices(d)
    return np.hstack([np.ones((n, 1)), z, z[:, iu[0]] * z[:, iu[1]]])


@dataclass(frozen=True, eq=False)
class QuadraticSurrogate:
    """``s(u) = log_prior(u) + c + g.z + z.H.z / 2`` with ``z = W (u - m)``; ``-inf`` outside.

    Attributes
    ----------
    mean : numpy.ndarray
        ``m``, ``(D,)``, the centre of the training draws (walkers' coordinates).
    whiten : numpy.ndarray
        ``W``, ``(D, D)``, the inverse Cholesky factor of their covariance.
    constant, gradient, hessian :
        ``c``, ``g (D,)`` and ``H (D, D)`` (negative semi-definite) in ``z``.
    lower, upper : numpy.ndarray
        Support of the walkers' coordinates, ``(D,)``.
    log_prior : callable
        Exact log prior in the walkers' coordinates, ``(N, D) -> (N,)``.
    rms : float
        Root-mean-square residual of the log likelihood over the training draws.
    n_points : int
        Distinct draws it was fitted to.
    """

    mean: np.ndarray
    whiten: np.ndarray
    constant: float
    gradient: np.ndarray
    hessian: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    log_prior: Callable[[np.ndarray], np.ndarray]
    rms: float
    n_points: int

    def log_likelihood(self, u: np.ndarray) -> np.ndarray:
        """The quadratic part alone, ``(N, D) -> (N,)``."""
        z = (np.atleast_2d(np.asarray(u, dtype=float)) - self.mean) @ self.whiten.T
        return self.constant + z @ self.gradient + 0.5 * np.einsum("ni,ij,nj->n", z,
                                                                  self.hessian, z)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """The surrogate log posterior, ``(N, D) -> (N,)``."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        inside = np.all((u > self.lower) & (u < self.upper), axis=1)
        out = np.full(u.shape[0], -np.inf)
        if inside.any():
            with np.errstate(divide="ignore", invalid="ignore"):
                lp = np.asarray(self.log_prior(u[inside]), dtype=float)
            out[inside] = np.where(np.isfinite(lp), lp + self.log_likelihood(u[inside]),
                                   -np.inf)
        return out


def fit_quadratic_surrogate(
    points: np.ndarray, log_prob: np.ndarray, log_prior: Callable[[np.ndarray], np.ndarray],
    lower: np.ndarray, upper: np.ndarray, *, drop_below: float = np.inf,
) -> QuadraticSurrogate | None:
    """Fit :class:`QuadraticSurrogate` to exact log posteriors of draws.

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, D)`` draws in the walkers' coordinates (repeats allowed: a rejected step repeats
        a walker's position; each distinct draw counts once).
    log_prob : numpy.ndarray
        ``(N,)`` their exact log posteriors.
    log_prior : callable
        Exact log prior in the same coordinates.
    lower, upper : numpy.ndarray
        Support, ``(D,)``.
    drop_below : float
        Draws more than this below the best log posterior are left out (walkers stranded
        far below the ensemble would otherwise bend the fit).

    Returns
    -------
    QuadraticSurrogate or None
        None with fewer than :data:`MIN_POINTS_PER_FEATURE` distinct finite draws per
        coefficient, or when the draws span fewer than ``D`` dimensions.
    """
    pts = np.asarray(points, dtype=float)
    lp = np.asarray(log_prob, dtype=float)
    ok = np.isfinite(lp) & np.all(np.isfinite(pts), axis=1)
    pts, lp = pts[ok], lp[ok]
    if pts.size == 0:
        return None
    pts, first = np.unique(pts, axis=0, return_index=True)
    lp = lp[first]
    keep = lp >= lp.max() - drop_below
    pts, lp = pts[keep], lp[keep]
    n, d = pts.shape
    n_features = 1 + d + d * (d + 1) // 2
    if n < MIN_POINTS_PER_FEATURE * n_features:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        prior = np.asarray(log_prior(pts), dtype=float)
    y = lp - prior
    good = np.isfinite(y)
    pts, y = pts[good], y[good]
    if pts.shape[0] < MIN_POINTS_PER_FEATURE * n_features:
        return None
    mean = pts.mean(axis=0)
    cov = np.cov(pts, rowvar=False).reshape(d, d)
    try:
        chol = np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        return None
    whiten = np.linalg.inv(chol)
    z = (pts - mean) @ whiten.T
    coef = np.linalg.lstsq(_features(z), y, rcond=None)[0]
    iu = np.triu_indices(d)
    h = np.zeros((d, d))
    h[iu] = coef[1 + d:]
    hessian = h + h.T  # z_i z_j (i < j) appears once, z_i^2 once: H = U + U^T
    vals, vecs = np.linalg.eigh(hessian)
    if np.any(vals > 0.0):
        # Clip the rising directions, then refit the constant and the gradient beneath the
        # fixed curvature.
        hessian = (vecs * np.minimum(vals, 0.0)) @ vecs.T
        rest = y - 0.5 * np.einsum("ni,ij,nj->n", z, hessian, z)
        lin = np.linalg.lstsq(np.hstack([np.ones((z.shape[0], 1)), z]), rest, rcond=None)[0]
        constant, gradient = float(lin[0]), lin[1:]
    else:
        constant, gradient = float(coef[0]), coef[1 : 1 + d]
    fitted = constant + z @ gradient + 0.5 * np.einsum("ni,ij,nj->n", z, hessian, z)
    rms = float(np.sqrt(np.mean((fitted - y) ** 2)))
    return QuadraticSurrogate(mean, whiten, constant, np.asarray(gradient), hessian,
                              np.asarray(lower, dtype=float), np.asarray(upper, dtype=float),
                              log_prior, rms, int(pts.shape[0]))


class DelayedAcceptanceMove(emcee.moves.RedBlueMove):
    """An emcee red-blue move (stretch, differential evolution) with a first-stage screen.

    Without a surrogate (``surrogate = None``) it is the wrapped move itself. With one, each
    half-ensemble update draws the wrapped move's proposals, screens them with the surrogate
    and evaluates the log posterior only for those that pass (module notes). ``counts`` holds
    ``[proposals, passed the screen, accepted]`` since construction (screened steps only).

    Parameters
    ----------
    inner : emcee.moves.RedBlueMove
        The move whose proposals are screened.
    """

    def __init__(self, inner: emcee.moves.RedBlueMove) -> None:
        super().__init__(nsplits=inner.nsplits, randomize_split=inner.randomize_split,
                         live_dangerously=inner.live_dangerously)
        self.inner = inner
        self.surrogate: Callable[[np.ndarray], np.ndarray] | None = None
        self.counts = np.zeros(3, dtype=np.int64)

    def setup(self, coords: np.ndarray) -> None:
        """The wrapped move's setup (differential evolution draws its step scale here)."""
        self.inner.setup(coords)

    def get_proposal(self, sample: np.ndarray, complement: list[np.ndarray],
                     random: Any) -> tuple[np.ndarray, np.ndarray]:
        """The wrapped move's proposals and their log proposal ratios."""
        return self.inner.get_proposal(sample, complement, random)

    def propose(self, model: Any, state: emcee.State) -> tuple[emcee.State, np.ndarray]:
        """One update of each half of the walkers against the other (emcee's red-blue loop)."""
        surrogate = self.surrogate
        if surrogate is None:
            return super().propose(model, state)
        nwalkers, ndim = state.coords.shape
        if nwalkers < 2 * ndim and not self.live_dangerously:
            raise RuntimeError("It is unadvisable to use a red-blue move with fewer walkers "
                               "than twice the number of dimensions.")
        if state.blobs is not None:
            raise ValueError("delayed acceptance does not carry blobs")
        self.setup(state.coords)
        accepted = np.zeros(nwalkers, dtype=bool)
        all_inds = np.arange(nwalkers)
        inds = all_inds % self.nsplits
        if self.randomize_split:
            model.random.shuffle(inds)
        for split in range(self.nsplits):
            s1 = inds == split
            sets = [state.coords[inds == j] for j in range(self.nsplits)]
            c = sets[:split] + sets[split + 1:]
            q, factors = self.get_proposal(sets[split], c, model.random)
            walkers = all_inds[s1]
            ds = surrogate(q) - surrogate(state.coords[s1])
            u1 = np.log(model.random.rand(walkers.size))
            u2 = np.log(model.random.rand(walkers.size))
            with np.errstate(invalid="ignore"):
                screen = np.asarray(factors) + ds > u1
            new_lp = np.full(walkers.size, -np.inf)
            if screen.any():
                lp, blobs = model.compute_log_prob_fn(q[screen])
                if blobs is not None:
                    raise ValueError("delayed acceptance does not carry blobs")
                new_lp[screen] = lp
            with np.errstate(invalid="ignore"):
                take = screen & (new_lp - state.log_prob[walkers] - ds > u2)
            accepted[walkers[take]] = True
            self.counts += (walkers.size, int(screen.sum()), int(take.sum()))
            state = self.update(state, emcee.State(q, log_prob=new_lp), accepted, s1)
        return state, accepted
