r"""The emcee driver: MAP from several starts, a small ball, sampling until converged.

1. **MAP.** 2048 draws from the prior are evaluated in one vectorised call; the
   ``map_starts`` best ones start :func:`scipy.optimize.minimize` (adaptive Nelder-Mead,
   bounded to the prior support; Powell's method stalled on the mixture likelihood's ridges in
   tests) on ``-log p``. The surface can have two modes across ``c = c*`` (the regime flips),
   so every distinct local optimum found is kept, best first
   (:class:`MapEstimate`; :mod:`rigtools.calibration.api` warns when a second one within
   :data:`BIMODAL_LOG_PROB` of the best puts a run on the other side of ``c = c*``). The
   walkers start at the best one.
2. **Walkers** start in a ball of radius ``1e-3`` prior sd around the MAP (redrawn until
   inside the support), ``W = max(32, 2 D + 2)`` by default (even).
3. **Sampling** with :class:`emcee.EnsembleSampler` (``vectorize=True``; an even mix of the
   differential-evolution and stretch moves, which on these posteriors reached a given number
   of autocorrelation times in the least wall time of the moves tried: stretch, DE, DE with
   snooker) in chunks of ``check_every`` steps. After each chunk
   the chain is committed; the integrated autocorrelation time ``tau`` of every parameter is
   estimated (emcee's estimator, :mod:`rigtools.calibration.autocorr`) at every check once
   the chain is 80 % of ``50 max(tau)`` long (before that whenever it has grown by 10 %), and
   the chain is **converged** when it is longer than ``50 max(tau)`` and ``max(tau)`` has
   grown or fallen by less than 5 % since its estimate on the chain when it was at most 80 %
   as long. At ``max_steps`` without that, the result is flagged "not converged" (a warning;
   the caller decides). This is emcee's documented criterion (``N > 50 tau``, ``tau``
   stable) with the stability judged over a fifth of the chain instead of one check: from
   one check to the next (100 steps) the estimates of 16 walkers at 2000 steps moved by 1-17 %
   per parameter (median 3 %) on the run-up posterior, so "every ``tau`` within 1 % of the
   last check" was a rare coincidence (a few per cent of the checks) that held converged
   chains for thousands of steps, while a ``tau`` still growing with the chain (the case the
   condition is for: an estimate proportional to ``N^a`` grows by ``1 - 0.8^a``, 11 % for
   ``a = 1/2``) fails it.
   ``tau`` is estimated, and the length counted, from the end of the **warm-up**
   (:func:`warm_up_end`): the steps in which the ensemble's mean log posterior travels from
   the start to its stationary level. Estimated over them, ``tau`` measures the travel, not
   the mixing: on the demo's run-up posterior the walkers took ~300 steps from the MAP of
   the differential evolution to the posterior's model error, and ``tau`` over the whole
   chain was 91 steps at step 2000, over the chain after step 500 31-38 for every parameter.
4. **Stragglers.** An ensemble can leave a walker stranded in a pocket of low probability
   (a narrow local optimum of the mixture likelihood, the far side of the jam boundary), where
   the affine-invariant moves hardly ever pull it out; it then inflates R-hat and the tails.
   At every check up to a quarter of ``max_steps``, walkers whose mean log posterior over the
   last 100 steps lies more than 5 MADs below the ensemble's median, and more than a
   posterior draw could, are moved next to randomly chosen other walkers
   (``default_rng([seed, 3, step])``); the chain before the last such move is burn-in, and
   ``tau`` and the convergence rule count from it. "More than a posterior draw could": for a
   posterior near a Gaussian in ``D`` dimensions, ``log p_max - log p`` of a draw is
   ``chi^2_D / 2``; a walker further below the median than
   ``(chi^2_D(0.999) - chi^2_D(0.5)) / 2`` (5.2 for ``D = 1``, 8.6 for 6, 10.1 for 10) sits
   where one draw in a thousand would, on average over 100 steps. Without that floor (a flat
   3 before), walkers in the slow tail of skewed, correlated parameters (a long error
   correlation with a large error, 4.7 under the median on the run-up posterior) were taken
   for stranded: their tail was cut and the burn-in restarted, twice in a run.
5. **Log coordinates** (``log_scale``, optional): parameters with a positive, scale-like
   prior (a log-normal or half-normal damping ratio, an error's standard deviation, a
   correlation length) can be moved as ``u = ln x``; the walkers then see the density
   ``p(x) x`` (the Jacobian of ``x = e^u``). Such a parameter's posterior is skewed, its
   spread proportional to its size, and it trades against another one multiplicatively (a
   longer error correlation against a larger error), which the affine-invariant moves follow
   in ``u`` and not in ``x``: on the run-up posterior the error parameters' ``tau`` fell from
   57-86 to 29-45 steps (session 7's measurement). And a region at the bottom of a wide
   prior on ``[0, upper]`` (a backlash of a few um on 0-300 um) is a sliver in ``x`` that
   walkers on the plateau, whose differences are hundreds of um, hardly ever land in; in ``u``
   it is as wide as the plateau (``tests/calibration/test_sampler.py``: half the mass there,
   none of it found in ``x``). ``tau`` and the convergence rule are
   computed in the coordinates the walkers move in; the returned chain, MAP and log posterior
   are in the parameters' own units (the log posterior without the Jacobian).
6. **Burn-in and thinning** from the final ``tau``: discard ``2 max(tau)`` steps after the
   last move (at least), keep every ``max(1, min(tau) / 2)``-th. The mean acceptance
   fraction is reported and checked against the tolerances.
7. **Delayed acceptance** (``SamplerSettings.delayed_acceptance``, optional): both moves
   screen their proposals with a quadratic surrogate of the log posterior and evaluate it only
   where the screen lets a proposal through, then accept with the second-stage probability
   that keeps the chain exact (:mod:`rigtools.calibration.delayed_acceptance`). The
   surrogate is the exact prior plus a quadratic fitted to the log likelihood of the second
   half of the chain so far, refitted at every check from the first at which there are
   enough distinct draws up to ``reset_until`` and fixed after that. For a log posterior that
   costs a sweep per walker, a proposal then costs one with probability about the acceptance
   fraction; the second-stage rejections lengthen ``tau``. Counted in ``screen_counts``.
8. **Mixture move** (``SamplerSettings.mixture_move``, optional): a fifth of the steps
   (:data:`MIXTURE_SHARE`) are independence Metropolis-Hastings steps from a Student-t
   mixture fitted to the second half of the chain so far, refitted as the surrogate of 7
   (:mod:`rigtools.calibration.mixture_move`; a stretch move until the first fit). Every
   walker proposes a fresh draw: on a near-Gaussian posterior most are accepted and the
   draws decorrelate in a few steps instead of tens, and a walker jumps between two regimes
   of a posterior the mixture holds as two components, which the ensemble moves cross only
   rarely. Exact for any fitted mixture (the Metropolis-Hastings ratio carries ``g``).

Reproducibility and resuming
----------------------------
The MAP and the ball use ``numpy.random.default_rng(seed)``; the sampler's own generator (a
``RandomState``, emcee's) is seeded with ``seed`` too. With a checkpoint file
(:mod:`rigtools.calibration.checkpoint`) the chain, the sampler's random state and the
history of ``tau`` are committed at every check; a run killed at any point and started again
recomputes the (deterministic) MAP, resumes from the last commit and continues the same
stream of random numbers, so it ends bit for bit with the numbers of an uninterrupted run
(``tests/calibration/test_resume.py`` kills a run with SIGKILL and compares).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import emcee
import numpy as np
from scipy.optimize import minimize
from scipy.stats import chi2

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.checkpoint import open_checkpoint
from rigtools.calibration.delayed_acceptance import (
    DelayedAcceptanceMove,
    fit_quadratic_surrogate,
)
from rigtools.calibration.mixture_move import MixtureIndependenceMove, fit_mixture_proposal
from rigtools.calibration.priors import Prior

__all__ = [
    "BIMODAL_LOG_PROB",
    "CONVERGENCE_FACTOR",
    "TAU_BASELINE",
    "TAU_RTOL",
    "MapEstimate",
    "Progress",
    "SamplerRun",
    "SamplerSettings",
    "find_map",
    "is_converged",
    "reset_floor",
    "reset_stragglers",
    "run_sampler",
    "start_ball",
    "warm_up_end",
]

#: The chain must be longer than this many autocorrelation times ...
CONVERGENCE_FACTOR: Final = 50.0
#: ... and the largest tau must have moved less than TAU_RTOL (relative) since its estimate
#: on the chain when it was at most TAU_BASELINE times as long (module notes, 3).
TAU_RTOL: Final = 0.05
TAU_BASELINE: Final = 0.8
#: tau is re-estimated at every check once the chain is 80 % of the length the rule needs,
#: before that only when it has grown by this factor since the last estimate (an estimate
#: costs O(N log N); one at every check of a long chain would add up to O(N^2)).
TAU_GROWTH: Final = 1.1
#: A second local optimum within this of the best log posterior is reported.
BIMODAL_LOG_PROB: Final = 3.0
#: Walkers whose mean log posterior over the last RESET_WINDOW steps lies more than
#: RESET_SIGMAS MADs and more than :func:`reset_floor` below the ensemble median are moved
#: onto others (at checks up to ``SamplerSettings.reset_until``).
RESET_WINDOW: Final = 100
RESET_SIGMAS: Final = 5.0
#: The chi-square quantile of :func:`reset_floor`.
RESET_QUANTILE: Final = 0.999
#: Prior draws screened for MAP starting points.
_N_PRIOR_SCREEN: Final = 2048
#: Radius of the starting ball in prior standard deviations.
_BALL: Final = 1e-3

Progress = Callable[[int, int, float | None], None]


@dataclass(frozen=True)
class SamplerSettings:
    """Settings of one emcee run.

    Attributes
    ----------
    walkers : int or None
        None: ``max(32, 2 D + 2)`` rounded up to even.
    max_steps : int
    check_every : int
    seed : int
    map_starts : int
    delayed_acceptance : bool
        Screen the proposals with a quadratic surrogate of the log posterior, refitted to
        the chain at every check up to :attr:`reset_until` (module notes, 7).
    mixture_move : bool
        Add independence Metropolis-Hastings steps from a Student-t mixture fitted to the
        chain, refitted likewise (module notes, 8).
    """

    walkers: int | None = None
    max_steps: int = 20000
    check_every: int = 100
    seed: int = 1
    map_starts: int = 8
    delayed_acceptance: bool = False
    mixture_move: bool = False

    @property
    def reset_until(self) -> int:
        """Last step at which stranded walkers may be moved: a quarter of ``max_steps``."""
        return self.max_steps // 4

    def n_walkers(self, ndim: int) -> int:
        """Walkers for ``ndim`` parameters."""
        if self.walkers is not None:
            return self.walkers
        w = max(32, 2 * ndim + 2)
        return w + (w % 2)


@dataclass(frozen=True, eq=False)
class MapEstimate:
    """The maximum a posteriori from several starts.

    Attributes
    ----------
    theta : numpy.ndarray
        Best parameter vector, ``(D,)``.
    log_prob : float
    optima : numpy.ndarray
        Distinct local optima found, best first, ``(K, D)``.
    optima_log_prob : numpy.ndarray
        Their log posteriors, ``(K,)``.
    """

    theta: np.ndarray
    log_prob: float
    optima: np.ndarray
    optima_log_prob: np.ndarray


@dataclass(frozen=True, eq=False)
class SamplerRun:
    """Result of :func:`run_sampler`.

    Attributes
    ----------
    chain : numpy.ndarray
        Every step, ``(steps, W, D)``.
    log_prob : numpy.ndarray
        ``(steps, W)``.
    acceptance_fraction : numpy.ndarray
        Per walker, ``(W,)``.
    tau : numpy.ndarray
        Final integrated autocorrelation time per parameter (steps), ``(D,)``, in the
        coordinates the walkers move in (``ln x`` where ``log_scale``).
    tau_history : tuple of (int, tuple of float, int)
        ``(iteration, tau, warm)`` at every estimate of ``tau``, ``warm`` the first step the
        estimate used (:func:`warm_up_end`).
    converged : bool
    n_steps, burn_in, thin : int
    map_estimate : MapEstimate
    resumed_from : int
        Committed steps a checkpoint resumed from (0: fresh).
    notes : tuple of str
        Checkpoint events, bimodality, convergence.
    seconds_sampling : float
        Wall time in the sampler (s).
    log_prob_evaluations : int
        Parameter vectors evaluated while sampling.
    resets : tuple of int
        Steps at which stranded walkers were moved (the last one ends the burn-in at least).
    screen_counts : tuple of int
        With delayed acceptance: proposals screened, passed the screen (each one full
        evaluation) and accepted, in this process (a resumed run counts from the resume).
    """

    chain: np.ndarray
    log_prob: np.ndarray
    acceptance_fraction: np.ndarray
    tau: np.ndarray
    tau_history: tuple[tuple[int, tuple[float, ...], int], ...]
    converged: bool
    n_steps: int
    burn_in: int
    thin: int
    map_estimate: MapEstimate
    resumed_from: int = 0
    notes: tuple[str, ...] = field(default=())
    seconds_sampling: float = 0.0
    log_prob_evaluations: int = 0
    resets: tuple[int, ...] = ()
    screen_counts: tuple[int, int, int] = (0, 0, 0)

    def samples(self) -> np.ndarray:
        """Kept draws, ``(W, draws, D)`` (burn-in discarded, thinned)."""
        return np.swapaxes(self.chain[self.burn_in::self.thin], 0, 1)

    def sample_log_prob(self) -> np.ndarray:
        """Log posterior of the kept draws, ``(W, draws)``."""
        return np.swapaxes(self.log_prob[self.burn_in::self.thin], 0, 1)


def _bounds(priors: tuple[Prior, ...]) -> list[tuple[float | None, float | None]]:
    return [(p.lower if math.isfinite(p.lower) else None,
             p.upper if math.isfinite(p.upper) else None) for p in priors]


def find_map(log_prob: Callable[[np.ndarray], np.ndarray], priors: tuple[Prior, ...],
             *, starts: int, seed: int) -> MapEstimate:
    """Maximum a posteriori by Powell's method from the best of many prior draws.

    Parameters
    ----------
    log_prob : callable
        Vectorised log posterior, ``(N, D) -> (N,)``.
    priors : tuple of Prior
        One per dimension (supports bound the search, draws seed it).
    starts : int
        Local optimisations.
    seed : int

    Returns
    -------
    MapEstimate
    """
    rng = np.random.default_rng([seed, 0])
    d = len(priors)
    draws = np.column_stack([p.sample(rng, _N_PRIOR_SCREEN) for p in priors])
    lp = log_prob(draws)
    order = np.argsort(-np.where(np.isfinite(lp), lp, -np.inf), kind="stable")
    bounds = _bounds(priors)
    sd = np.array([max(p.moments()[1], 1e-12) for p in priors])
    results: list[tuple[float, np.ndarray]] = []

    def neg(x: np.ndarray) -> float:
        v = float(log_prob(x[None, :])[0])
        return -v if math.isfinite(v) else 1e300

    for i in order[:starts]:
        x0 = draws[i]
        if not np.isfinite(lp[i]):
            continue
        res = minimize(neg, x0, method="Nelder-Mead", bounds=bounds,
                       options={"xatol": 1e-6, "fatol": 1e-8, "maxfev": 2000 * d,
                                "adaptive": True})
        x = np.asarray(res.x, dtype=float)
        results.append((float(-res.fun), x))
    if not results:
        best = int(order[0])
        results.append((float(lp[best]), draws[best]))
    results.sort(key=lambda t: -t[0])
    optima: list[np.ndarray] = []
    values: list[float] = []
    for v, x in results:
        if all(np.max(np.abs(x - o) / sd) > 0.05 for o in optima):
            optima.append(x)
            values.append(v)
    return MapEstimate(theta=optima[0], log_prob=values[0], optima=np.array(optima),
                       optima_log_prob=np.array(values))


def start_ball(center: np.ndarray, priors: tuple[Prior, ...], walkers: int,
               seed: int) -> np.ndarray:
    """Walkers in a small ball around ``center``, all inside the prior support.

    Parameters
    ----------
    center : numpy.ndarray
        ``(D,)``.
    priors : tuple of Prior
    walkers : int
    seed : int

    Returns
    -------
    numpy.ndarray
        ``(walkers, D)``.
    """
    rng = np.random.default_rng([seed, 1])
    sd = np.array([max(p.moments()[1], 1e-12) for p in priors])
    lo = np.array([p.lower for p in priors])
    hi = np.array([p.upper for p in priors])
    c = np.clip(center, lo + _BALL * sd, hi - _BALL * sd)
    out = c + _BALL * sd * rng.standard_normal((walkers, len(priors)))
    for _ in range(100):
        bad = (out <= lo) | (out >= hi)
        if not bad.any():
            break
        out = np.where(bad, c + _BALL * sd * rng.standard_normal(out.shape), out)
    # strictly inside: a bound is -inf in log coordinates
    return np.where((out <= lo) | (out >= hi), c, out)


@dataclass(frozen=True)
class _Space:
    """The coordinates the walkers move in: per parameter its value or its logarithm."""

    log: np.ndarray   # (D,) bool

    def to_sampling(self, x: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return np.where(self.log, np.log(np.where(self.log, x, 1.0)), x)

    def to_natural(self, u: np.ndarray) -> np.ndarray:
        with np.errstate(over="ignore"):
            return np.where(self.log, np.exp(np.where(self.log, u, 0.0)), u)

    def log_jacobian(self, u: np.ndarray) -> np.ndarray:
        """``ln |dx/du|`` summed over the parameters, ``(..., D) -> (...)``."""
        return np.sum(np.where(self.log, u, 0.0), axis=-1)

    def log_prob(self, log_prob: Callable[[np.ndarray], np.ndarray]
                 ) -> Callable[[np.ndarray], np.ndarray]:
        """The density the walkers see: ``log p(x(u)) + ln |dx/du|``."""
        if not self.log.any():
            return log_prob

        def in_sampling(u: np.ndarray) -> np.ndarray:
            u = np.asarray(u, dtype=float)
            return np.asarray(log_prob(self.to_natural(u)), dtype=float) + \
                self.log_jacobian(u)
        return in_sampling


#: Share of the steps that are independence steps with ``mixture_move`` (module notes, 8).
MIXTURE_SHARE: Final = 0.2


def _moves(delayed: bool = False, mixture: bool = False) -> list[tuple[Any, float]]:
    inner = [emcee.moves.DEMove(), emcee.moves.StretchMove()]
    moves: list[Any] = [DelayedAcceptanceMove(m) for m in inner] if delayed else inner
    if not mixture:
        return [(moves[0], 0.5), (moves[1], 0.5)]
    rest = 0.5 * (1.0 - MIXTURE_SHARE)
    return [(moves[0], rest), (moves[1], rest), (MixtureIndependenceMove(), MIXTURE_SHARE)]


def _adapt(moves: list[tuple[Any, float]], chain: np.ndarray, lp: np.ndarray, t: int,
           space: _Space, priors: tuple[Prior, ...], seed: int) -> float | None:
    """Refit the screen and the mixture (where the moves have them) to steps ``[t // 2, t)``.

    Returns the surrogate's rms (None: no surrogate). A pure function of the chain's first
    ``t`` steps, so a resumed run refits what the uninterrupted one used.
    """
    ndim = chain.shape[-1]
    mixture = [m for m, _ in moves if isinstance(m, MixtureIndependenceMove)]
    if mixture:
        g = fit_mixture_proposal(chain[t // 2 : t].reshape(-1, ndim), seed=seed)
        for m in mixture:
            m.proposal = g
    screened = [m for m, _ in moves if isinstance(m, DelayedAcceptanceMove)]
    if not screened:
        return None
    lower = space.to_sampling(np.array([p.lower for p in priors]))
    upper = space.to_sampling(np.array([p.upper for p in priors]))

    def log_prior(u: np.ndarray) -> np.ndarray:
        x = space.to_natural(u)
        out = space.log_jacobian(u)
        for i, p in enumerate(priors):
            out = out + p.logpdf(x[:, i])
        return np.asarray(out, dtype=float)

    part, part_lp = chain[t // 2 : t], lp[t // 2 : t]
    surrogate = fit_quadratic_surrogate(part.reshape(-1, ndim), part_lp.reshape(-1),
                                        log_prior, lower, upper,
                                        drop_below=0.5 * float(chi2.ppf(1 - 1e-5, ndim)))
    for m in screened:
        m.surrogate = surrogate
    return None if surrogate is None else surrogate.rms


def run_sampler(
    log_prob: Callable[[np.ndarray], np.ndarray],
    priors: tuple[Prior, ...],
    settings: SamplerSettings,
    *,
    checkpoint: Path | None = None,
    checkpoint_name: str = "mcmc",
    fingerprint: str = "",
    progress: Progress | None = None,
    map_estimate: MapEstimate | None = None,
    log_scale: tuple[bool, ...] | None = None,
) -> SamplerRun:
    """MAP, walker ball, emcee until converged or ``max_steps`` (module notes).

    Parameters
    ----------
    log_prob : callable
        Vectorised log posterior, ``(W, D) -> (W,)``.
    priors : tuple of Prior
        One per dimension.
    settings : SamplerSettings
    checkpoint : pathlib.Path, optional
        HDF5 file for the chain; resumed when it holds this chain (same ``fingerprint``).
    checkpoint_name : str
        Group of the chain in the file.
    fingerprint : str
        Identity of configuration and data.
    progress : callable, optional
        ``progress(step, max_steps, tau_max)`` after every check.
    map_estimate : MapEstimate, optional
        A MAP already found by :func:`find_map` with the same settings (not searched again).
    log_scale : tuple of bool, optional
        Per parameter: move the walkers in ``ln x`` (module notes, item 5); only where the
        prior's support is positive. None: every parameter in its own units.

    Returns
    -------
    SamplerRun
    """
    ndim = len(priors)
    walkers = settings.n_walkers(ndim)
    notes: list[str] = []
    space = _Space(np.zeros(ndim, dtype=bool) if log_scale is None
                   else np.array(log_scale, dtype=bool))
    if space.log.shape != (ndim,):
        raise ValueError(f"log_scale has {space.log.size} entries for {ndim} parameters")
    for p, lg in zip(priors, space.log, strict=True):
        if lg and not p.lower >= 0.0:
            raise ValueError(f"log_scale for a prior that reaches below 0: {p.describe()}")
    if space.log.any():
        fingerprint = f"{fingerprint}|log:{''.join('1' if v else '0' for v in space.log)}"
    if settings.delayed_acceptance:
        fingerprint = f"{fingerprint}|delayed-acceptance"
    if settings.mixture_move:
        fingerprint = f"{fingerprint}|mixture-move"
    moves = _moves(settings.delayed_acceptance, settings.mixture_move)
    adaptive = settings.delayed_acceptance or settings.mixture_move
    map_est = (find_map(log_prob, priors, starts=settings.map_starts, seed=settings.seed)
               if map_estimate is None else map_estimate)
    n_evals = [0]
    sampling_log_prob = space.log_prob(log_prob)

    def counted(theta: np.ndarray) -> np.ndarray:
        n_evals[0] += theta.shape[0]
        return sampling_log_prob(theta)

    resumed = 0
    history: list[tuple[int, tuple[float, ...], int]] = []
    resets: list[int] = []
    if checkpoint is not None:
        backend, resumed, note = open_checkpoint(checkpoint, checkpoint_name, fingerprint,
                                                 walkers, ndim)
        if note:
            notes.append(note)
        sampler = emcee.EnsembleSampler(walkers, ndim, counted, vectorize=True,
                                        moves=moves, backend=backend)
        if resumed:
            data = backend.checkpoint_data()
            resets = [int(i) for i in data.get("resets", [])]
            # (iteration, tau[, warm]): a checkpoint written before the warm-up counted from
            # the last reset
            history = [(int(h[0]), tuple(float(t) for t in h[1]),
                        int(h[2]) if len(h) > 2 else (resets[-1] if resets else 0))
                       for h in data.get("tau_history", [])]
            state: Any = backend.get_last_sample()
        else:
            sampler.random_state = np.random.RandomState(settings.seed).get_state()
            state = space.to_sampling(start_ball(map_est.theta, priors, walkers,
                                                 settings.seed))
    else:
        backend = None
        sampler = emcee.EnsembleSampler(walkers, ndim, counted, vectorize=True, moves=moves)
        sampler.random_state = np.random.RandomState(settings.seed).get_state()
        state = space.to_sampling(start_ball(map_est.theta, priors, walkers, settings.seed))
    iteration = resumed
    if backend is not None and resumed:
        chain = np.asarray(backend.get_chain(), dtype=float)
        lp = np.asarray(backend.get_log_prob(), dtype=float)
    else:
        chain = np.empty((0, walkers, ndim))
        lp = np.empty((0, walkers))
    if resets and resets[-1] == resumed:   # killed right after a reset: apply it again
        state, _ = reset_stragglers(state, lp, sampling_log_prob, seed=settings.seed,
                                     iteration=resumed)
    start = resets[-1] if resets else 0
    converged = is_converged(history)
    screen_fits: list[tuple[int, float | None]] = []
    if adaptive and resumed:
        t_fit = min(resumed, settings.reset_until // settings.check_every * settings.check_every)
        screen_fits.append((t_fit, _adapt(moves, chain, lp, t_fit, space, priors,
                                          settings.seed)))
    t0 = time.perf_counter()
    while not converged and iteration < settings.max_steps:
        n = min(settings.check_every - iteration % settings.check_every,
                settings.max_steps - iteration)
        state = sampler.run_mcmc(state, n, skip_initial_state_check=True)
        iteration += n
        if backend is not None:
            new_chain, new_lp = backend.buffered()
        else:
            new_chain, new_lp = sampler.get_chain()[-n:], sampler.get_log_prob()[-n:]
        chain = np.concatenate([chain, new_chain])
        lp = np.concatenate([lp, new_lp])
        if _tau_due(history, iteration, start) or iteration >= settings.max_steps:
            warm = warm_up_end(lp, start)
            tau = integrated_time(chain[warm:])
            history.append((iteration, tuple(float(t) for t in tau), warm))
            converged = is_converged(history)
        if not converged and RESET_WINDOW <= iteration <= settings.reset_until \
                and iteration < settings.max_steps:
            state, moved = reset_stragglers(state, lp, sampling_log_prob, seed=settings.seed,
                                             iteration=iteration)
            if moved:
                resets.append(iteration)
                history, start = [], iteration
        if adaptive and iteration <= settings.reset_until:
            screen_fits.append((iteration, _adapt(moves, chain, lp, iteration, space, priors,
                                                  settings.seed)))
        if backend is not None:
            backend.commit({"tau_history": [[i, list(t), w] for i, t, w in history],
                            "resets": resets})
        if progress is not None:
            progress(iteration, settings.max_steps,
                     max(history[-1][1]) if history else None)
    seconds = time.perf_counter() - t0
    if history and history[-1][0] == chain.shape[0]:
        tau, warm = np.asarray(history[-1][1]), history[-1][2]
    else:
        warm = warm_up_end(lp, start) if chain.shape[0] - start > 1 else 0
        tau = integrated_time(chain[warm:])
    if resets:
        notes.append(f"walkers stranded far below the ensemble (mean log posterior over "
                     f"{RESET_WINDOW} steps more than {RESET_SIGMAS:g} MAD and "
                     f"{reset_floor(ndim):.3g} under the median) "
                     f"were moved onto others at step(s) {', '.join(map(str, resets))}; the "
                     "steps before the last move are burn-in")
    if not converged:
        notes.append(f"not converged: {chain.shape[0]} steps reached max_steps = "
                     f"{settings.max_steps} with max tau = {np.max(tau):.3g} steps "
                     f"({(chain.shape[0] - warm) / np.max(tau):.3g} tau since step {warm}; "
                     f"{CONVERGENCE_FACTOR:g} needed, and max tau stable to "
                     f"{100 * TAU_RTOL:g} % over the last {100 * (1 - TAU_BASELINE):g} % of the "
                     "chain)")
    for m, _ in moves:
        if isinstance(m, MixtureIndependenceMove) and m.counts[0]:
            g = m.proposal
            notes.append(f"mixture move: {m.counts[0]} independence proposals from a "
                         f"{0 if g is None else g.weights.size}-component Student-t mixture "
                         f"fitted to the chain, {100 * m.counts[1] / m.counts[0]:.1f} % "
                         "accepted")
    counts = (0, 0, 0)
    if settings.delayed_acceptance:
        total = np.sum([m.counts for m, _ in moves if isinstance(m, DelayedAcceptanceMove)],
                       axis=0)
        counts = (int(total[0]), int(total[1]), int(total[2]))
        fitted = [(t, r) for t, r in screen_fits if r is not None]
        if fitted and counts[0]:
            notes.append(
                f"delayed acceptance: surrogate refitted at the checks to step {fitted[-1][0]} "
                f"(last rms {fitted[-1][1]:.3g} in log posterior); {counts[0]} proposals "
                f"screened, {100 * counts[1] / counts[0]:.1f} % passed (one full evaluation "
                f"each), {100 * counts[2] / max(counts[1], 1):.1f} % of those accepted")
    burn = max(math.ceil(2.0 * np.max(tau)) + start, warm)
    burn = min(burn, chain.shape[0] - 1)
    thin = max(1, int(0.5 * np.min(tau)))
    acc = np.asarray(sampler.backend.accepted, dtype=float) / max(chain.shape[0], 1)
    if space.log.any():   # back to the parameters' units, the Jacobian taken out
        lp = lp - space.log_jacobian(chain)
        chain = space.to_natural(chain)
    return SamplerRun(
        chain=chain, log_prob=lp, acceptance_fraction=acc, tau=tau,
        tau_history=tuple(history), converged=converged, n_steps=int(chain.shape[0]),
        burn_in=burn, thin=thin, map_estimate=map_est, resumed_from=resumed,
        notes=tuple(notes), seconds_sampling=seconds, log_prob_evaluations=n_evals[0],
        resets=tuple(resets), screen_counts=counts,
    )


def reset_floor(ndim: int) -> float:
    """Least fall below the ensemble median that marks a stranded walker (module notes, 4).

    ``(chi^2_D(q) - chi^2_D(0.5)) / 2`` with ``q =`` :data:`RESET_QUANTILE`: how far below the
    median log posterior a draw of a Gaussian posterior in ``ndim`` dimensions lies with
    probability ``1 - q``.

    >>> round(reset_floor(6), 2)
    8.55
    """
    return 0.5 * float(chi2.ppf(RESET_QUANTILE, ndim) - chi2.ppf(0.5, ndim))


def reset_stragglers(state: Any, lp_chain: np.ndarray,
                      log_prob: Callable[[np.ndarray], np.ndarray], *, seed: int,
                      iteration: int) -> tuple[Any, bool]:
    """Move walkers stranded far below the ensemble onto the others (module notes).

    Parameters
    ----------
    state : emcee.State
        The ensemble after ``iteration`` steps.
    lp_chain : numpy.ndarray
        Log posterior of every step so far, ``(steps, W)``.
    log_prob : callable
    seed, iteration : int
        The moves are drawn from ``default_rng([seed, 3, iteration])``.

    Returns
    -------
    state : emcee.State
    moved : bool
    """
    mean_lp = np.mean(lp_chain[-RESET_WINDOW:], axis=0)
    med = float(np.median(mean_lp))
    mad = 1.4826 * float(np.median(np.abs(mean_lp - med)))
    ndim = np.shape(state.coords)[1]
    bad = mean_lp < med - max(RESET_SIGMAS * mad, reset_floor(ndim))
    if not bad.any():
        return state, False
    rng = np.random.default_rng([seed, 3, iteration])
    coords = np.array(state.coords, dtype=float)
    lp = np.array(state.log_prob, dtype=float)
    good = np.flatnonzero(~bad)
    spread = np.std(coords[good], axis=0)
    for w in np.flatnonzero(bad):
        donor = good[rng.integers(good.size)]
        trial, v = coords[donor].copy(), float(lp[donor])
        for _ in range(100):
            t = coords[donor] + 1e-3 * spread * rng.standard_normal(coords.shape[1])
            tv = float(log_prob(t[None, :])[0])
            if np.isfinite(tv):
                trial, v = t, tv
                break
        coords[w], lp[w] = trial, v
    return emcee.State(coords, log_prob=lp, random_state=state.random_state), True


def warm_up_end(log_prob: np.ndarray, start: int) -> int:
    """First step of the chain after ``start`` that belongs to its stationary part.

    The ensemble's mean log posterior ``m_t`` (over the walkers) starts away from its
    stationary level (above it from a small ball at the MAP, below it from a poor start) and
    ends the transient the first time it reaches the median of ``m_t`` over the second half of
    the chain since ``start``; never later than that half's first step (module notes, 3).

    Parameters
    ----------
    log_prob : numpy.ndarray
        ``(steps, W)``, the whole chain.
    start : int
        The last reset (0: none).

    Returns
    -------
    int
        A step in ``[start, start + (steps - start) // 2]``.

    Examples
    --------
    >>> lp = np.r_[np.linspace(-50.0, -6.0, 10), -5.0 + 0.1 * np.sin(np.arange(90))]
    >>> warm_up_end(lp[:, None], 0)
    10
    """
    m = np.mean(np.asarray(log_prob, dtype=float)[start:], axis=1)
    half = m.size // 2
    if half < 1:
        return start
    level = float(np.median(m[half:]))
    above = m[:half + 1] >= level
    crossed = np.flatnonzero(above != above[0])
    return start + (int(crossed[0]) if crossed.size else half)


def _tau_due(history: list[tuple[int, tuple[float, ...], int]], iteration: int,
             start: int) -> bool:
    """Estimate tau at this check? Always near the length the rule needs, else every 10 %."""
    if not history:
        return True
    last_it, last_tau, last_warm = history[-1]
    near = iteration - last_warm >= 0.8 * CONVERGENCE_FACTOR * max(last_tau)
    return near or iteration - start >= TAU_GROWTH * (last_it - start)


def is_converged(history: Sequence[tuple[int, tuple[float, ...], int]]) -> bool:
    """The rule of module notes, 3, on the chain after the last estimate's warm-up."""
    if len(history) < 2:
        return False
    it, tau, warm = history[-1]
    t = max(tau)
    if it - warm <= CONVERGENCE_FACTOR * t:
        return False
    before = [h for h in history[:-1] if h[0] - warm <= TAU_BASELINE * (it - warm)]
    return bool(before) and abs(t - max(before[-1][1])) < TAU_RTOL * t
