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
   the chain is **converged** when it is longer than ``50 max(tau)`` and no ``tau`` moved by
   1 % or more since the last estimate (emcee's documented criterion). At ``max_steps``
   without that, the result is flagged "not converged" (a warning; the caller decides).
4. **Stragglers.** An ensemble can leave a walker stranded in a pocket of low probability
   (a narrow local optimum of the mixture likelihood, the far side of the jam boundary), where
   the affine-invariant moves hardly ever pull it out; it then inflates R-hat and the tails.
   At every check up to a quarter of ``max_steps``, walkers whose mean log posterior over the
   last 100 steps lies more than 5 MADs (and 3 in log density) below the ensemble's median
   are moved next to randomly chosen other walkers (``default_rng([seed, 3, step])``); the
   chain before the last such move is burn-in, and ``tau`` and the convergence rule count
   from it.
5. **Burn-in and thinning** from the final ``tau``: discard ``2 max(tau)`` steps after the
   last move (at least), keep every ``max(1, min(tau) / 2)``-th. The mean acceptance
   fraction is reported and checked against the tolerances.

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
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import emcee
import numpy as np
from scipy.optimize import minimize

from rigtools.calibration.autocorr import integrated_time
from rigtools.calibration.checkpoint import open_checkpoint
from rigtools.calibration.priors import Prior

__all__ = [
    "BIMODAL_LOG_PROB",
    "CONVERGENCE_FACTOR",
    "TAU_RTOL",
    "MapEstimate",
    "Progress",
    "SamplerRun",
    "SamplerSettings",
    "find_map",
    "run_sampler",
    "start_ball",
]

#: The chain must be longer than this many autocorrelation times.
CONVERGENCE_FACTOR: Final = 50.0
#: ... and tau must have moved less than this (relative) since the last check.
TAU_RTOL: Final = 0.01
#: tau is re-estimated at every check once the chain is 80 % of the length the rule needs,
#: before that only when it has grown by this factor since the last estimate (an estimate
#: costs O(N log N); one at every check of a long chain would add up to O(N^2)).
TAU_GROWTH: Final = 1.1
#: A second local optimum within this of the best log posterior is reported.
BIMODAL_LOG_PROB: Final = 3.0
#: Walkers whose mean log posterior over the last RESET_WINDOW steps lies more than
#: RESET_SIGMAS MADs (and RESET_MIN_LOG_PROB) below the ensemble median are moved onto
#: others (at checks up to ``SamplerSettings.reset_until``).
RESET_WINDOW: Final = 100
RESET_SIGMAS: Final = 5.0
RESET_MIN_LOG_PROB: Final = 3.0
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
    """

    walkers: int | None = None
    max_steps: int = 20000
    check_every: int = 100
    seed: int = 1
    map_starts: int = 8

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
        Final integrated autocorrelation time per parameter (steps), ``(D,)``.
    tau_history : tuple of (int, tuple of float)
        ``(iteration, tau)`` at every check.
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
    """

    chain: np.ndarray
    log_prob: np.ndarray
    acceptance_fraction: np.ndarray
    tau: np.ndarray
    tau_history: tuple[tuple[int, tuple[float, ...]], ...]
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
        bad = (out < lo) | (out > hi)
        if not bad.any():
            break
        out = np.where(bad, c + _BALL * sd * rng.standard_normal(out.shape), out)
    return np.clip(out, lo, hi)


def _moves() -> list[tuple[Any, float]]:
    return [(emcee.moves.DEMove(), 0.5), (emcee.moves.StretchMove(), 0.5)]


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

    Returns
    -------
    SamplerRun
    """
    ndim = len(priors)
    walkers = settings.n_walkers(ndim)
    notes: list[str] = []
    map_est = (find_map(log_prob, priors, starts=settings.map_starts, seed=settings.seed)
               if map_estimate is None else map_estimate)
    n_evals = [0]

    def counted(theta: np.ndarray) -> np.ndarray:
        n_evals[0] += theta.shape[0]
        return log_prob(theta)

    resumed = 0
    history: list[tuple[int, tuple[float, ...]]] = []
    resets: list[int] = []
    if checkpoint is not None:
        backend, resumed, note = open_checkpoint(checkpoint, checkpoint_name, fingerprint,
                                                 walkers, ndim)
        if note:
            notes.append(note)
        sampler = emcee.EnsembleSampler(walkers, ndim, counted, vectorize=True,
                                        moves=_moves(), backend=backend)
        if resumed:
            data = backend.checkpoint_data()
            history = [(int(i), tuple(float(t) for t in tau))
                       for i, tau in data.get("tau_history", [])]
            resets = [int(i) for i in data.get("resets", [])]
            state: Any = backend.get_last_sample()
        else:
            sampler.random_state = np.random.RandomState(settings.seed).get_state()
            state = start_ball(map_est.theta, priors, walkers, settings.seed)
    else:
        backend = None
        sampler = emcee.EnsembleSampler(walkers, ndim, counted, vectorize=True, moves=_moves())
        sampler.random_state = np.random.RandomState(settings.seed).get_state()
        state = start_ball(map_est.theta, priors, walkers, settings.seed)
    iteration = resumed
    if backend is not None and resumed:
        chain = np.asarray(backend.get_chain(), dtype=float)
        lp = np.asarray(backend.get_log_prob(), dtype=float)
    else:
        chain = np.empty((0, walkers, ndim))
        lp = np.empty((0, walkers))
    if resets and resets[-1] == resumed:   # killed right after a reset: apply it again
        state, _ = _reset_stragglers(state, lp, log_prob, seed=settings.seed,
                                     iteration=resumed)
    start = resets[-1] if resets else 0
    converged = _is_converged(history, start)
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
            tau = integrated_time(chain[start:])
            history.append((iteration, tuple(float(t) for t in tau)))
            converged = _is_converged(history, start)
        if not converged and RESET_WINDOW <= iteration <= settings.reset_until \
                and iteration < settings.max_steps:
            state, moved = _reset_stragglers(state, lp, log_prob, seed=settings.seed,
                                             iteration=iteration)
            if moved:
                resets.append(iteration)
                history, start = [], iteration
        if backend is not None:
            backend.commit({"tau_history": [[i, list(t)] for i, t in history],
                            "resets": resets})
        if progress is not None:
            progress(iteration, settings.max_steps,
                     max(history[-1][1]) if history else None)
    seconds = time.perf_counter() - t0
    if history and history[-1][0] == chain.shape[0]:
        tau = np.asarray(history[-1][1])
    else:
        tau = integrated_time(chain[start:]) if chain.shape[0] - start > 1 else \
            integrated_time(chain)
    if resets:
        notes.append(f"walkers stranded far below the ensemble (mean log posterior over "
                     f"{RESET_WINDOW} steps more than {RESET_SIGMAS:g} MAD under the median) "
                     f"were moved onto others at step(s) {', '.join(map(str, resets))}; the "
                     "steps before the last move are burn-in")
    if not converged:
        notes.append(f"not converged: {chain.shape[0]} steps reached max_steps = "
                     f"{settings.max_steps} with max tau = {np.max(tau):.3g} steps "
                     f"({(chain.shape[0] - start) / np.max(tau):.3g} tau since step {start}; "
                     f"{CONVERGENCE_FACTOR:g} needed, and tau stable to 1 %)")
    burn = math.ceil(2.0 * np.max(tau)) + start
    burn = min(burn, chain.shape[0] - 1)
    thin = max(1, int(0.5 * np.min(tau)))
    acc = np.asarray(sampler.backend.accepted, dtype=float) / max(chain.shape[0], 1)
    return SamplerRun(
        chain=chain, log_prob=lp, acceptance_fraction=acc, tau=tau,
        tau_history=tuple(history), converged=converged, n_steps=int(chain.shape[0]),
        burn_in=burn, thin=thin, map_estimate=map_est, resumed_from=resumed,
        notes=tuple(notes), seconds_sampling=seconds, log_prob_evaluations=n_evals[0],
        resets=tuple(resets),
    )


def _reset_stragglers(state: Any, lp_chain: np.ndarray,
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
    bad = mean_lp < med - max(RESET_SIGMAS * mad, RESET_MIN_LOG_PROB)
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


def _tau_due(history: list[tuple[int, tuple[float, ...]]], iteration: int, start: int) -> bool:
    """Estimate tau at this check? Always near the length the rule needs, else every 10 %."""
    if not history:
        return True
    last_it, last_tau = history[-1]
    near = iteration - start >= 0.8 * CONVERGENCE_FACTOR * max(last_tau)
    return near or iteration - start >= TAU_GROWTH * (last_it - start)


def _is_converged(history: list[tuple[int, tuple[float, ...]]], start: int) -> bool:
    if len(history) < 2:
        return False
    (it, tau), (_, prev) = history[-1], history[-2]
    t = np.asarray(tau)
    p = np.asarray(prev)
    return bool(it - start > CONVERGENCE_FACTOR * np.max(t)
                and np.all(np.abs(t - p) / t < TAU_RTOL))
