r"""Log-normal likelihood of Arms run-up curves, the channel gains marginalised.

The model error is shared by the channels at a point and correlated along the path.

Observation model (issue 20 item 1; :mod:`rigtools.calibration.runup_forward` gives
``mu``): on channel ``c`` at point ``i`` of a run,

.. math:: \log A_{c,i} = g_c + \log \mu_i(\theta) + \delta_i + e_{c,i}, \qquad
          e_{c,i} \sim N(0, \sigma^2), \quad g_c = \log G_c \sim N(m_0, s_0^2)

* ``delta`` is the **model error**, the same on every channel (every channel sees the one DTE
  through its own gain, so where the model is off it is off on all of them: on the demo's
  run-up the residuals about the model at the truth agree across the channels to 0.16 %
  while they scatter by 15 % from point to point). Its marginal sd is ``tau``
  (``model_error``). Along the run it is a first-order autoregression in ``ln f_m`` within
  each stretch of one direction (along a monotone stretch, an Ornstein-Uhlenbeck process in
  ``ln f_m`` sampled at the points):

  .. math:: \delta_{i+1} = \rho_i \delta_i + \sqrt{1 - \rho_i^2}\,\tau\,\varepsilon_{i+1},
            \qquad \rho_i = \exp(-|\ln f_{i+1} - \ln f_i| / \ell)

  with ``ell`` the ``model_error_length`` (relative frequency), capped at
  :data:`MAX_CORRELATION`; points of different stretches (the up and the down sweep, a hold)
  are independent. A model that is off is off over a band, not point by point: a steady-state
  model against a ramp lags the resonance over its half-power band (``2 zeta``, a few per
  cent of ``f_m``), and a mesh-stiffness model that is wrong in form is wrong over wider
  bands. Counting such a discrepancy as independent at every window makes the intervals too
  narrow (the demo's damping ratio came out 1.5 % high with a 1 % wide interval). ``ell = 0``
  (or ``gaps`` all infinite) is the independent model.
* ``sigma`` is the ``channel_error``: what each channel adds on its own (sensor noise, the
  order-spectrum floor, a transfer path that is not quite flat).
* ``(m_0, s_0) = (log median, sigma)`` of the log-normal ``gain`` prior; each channel of each
  run has its own gain.

Marginal (:func:`marginal_log_likelihood`). Per run the residuals ``r = log A - log mu - m_0``
over the ``n`` observed (channel, point) pairs are Normal with covariance ``Sigma = sigma^2 I
+ U K U^T``, ``U = [Z, X]`` the point and channel indicators and ``K = diag(tau^2 R, s_0^2
I)``, ``R`` the correlation of the autoregression (tridiagonal precision). By Woodbury with
``A = K^{-1} + U^T U / sigma^2`` and ``b = U^T r / sigma^2``:

.. math:: \log p(r \mid \theta) = -\tfrac12\Big[n \log 2\pi + n \log\sigma^2
          + \log\det(\tau^2 R) + C \log s_0^2 + \log\det A + r^T r / \sigma^2
          - b^T A^{-1} b\Big]

``A``'s point block is ``tilde A / tau^2`` with ``tilde A = R^{-1} + diag(n_i) tau^2 /
sigma^2`` tridiagonal (``n_i`` channels at point ``i``), solved by its ``LDL^T``
factorisation in ``O(N)`` per walker; the gains' block enters through its ``C x C`` Schur
complement ``S``. Written with ``tilde A``, nothing divides by ``tau`` (``tau = 0`` is the
independent log-normal model, channel by channel). The gains' conditional posterior is
Normal with precision ``S`` (:func:`gain_conditional`).

The densities are those of ``log A`` (the Jacobian ``-sum log A`` is the same for every model
and parameter, so it changes no comparison and is left out).

**Pointwise log-likelihood** for PSIS-LOO (:func:`pointwise_log_likelihood`): the model is
not factorised (the gains and the correlated error tie the points), so the term of point
``i``, its channels together, is the leave-one-out predictive density
``log p(r_i | r_{-i}, theta)`` of the Gaussian (the non-factorised case of Burkner, Gabry &
Vehtari 2021, "Efficient leave-one-out cross-validation for Bayesian non-factorized normal and
Student-t models", Comput. Stat. 36: 1243-1261), computed as the difference of two marginals,

.. math:: \log p(r_i \mid r_{-i}) = \log p(r) - \log p(r_{-i}),

the second with point ``i`` unobserved (its ``delta_i`` stays in the chain). Their Eq. 9 in
block form (``P = Sigma^{-1}``) is the same number but forms ``P_ii`` as ``I / sigma^2`` less a
term of the same size, which lost 3e-7 in a test with ``tau / sigma = 20``; the difference of
marginals keeps the well-conditioned chain. A block ``B`` of points for ``i`` gives the
left-out density of a block (neighbouring windows together). Tested against dense
conditioning of the full covariance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "MAX_CORRELATION",
    "MIN_CHANNEL_ERROR",
    "GainPrior",
    "error_gaps",
    "gain_conditional",
    "marginal_log_likelihood",
    "pointwise_log_likelihood",
    "sample_model_error",
]

_LOG_2PI: Final = math.log(2.0 * math.pi)
#: Largest correlation of the model error between neighbouring points (windows at one
#: frequency, e.g. of a hold, are the same discrepancy; the cap keeps the chain's precision
#: finite: ``1 / (1 - rho^2)`` at most 5e5).
MAX_CORRELATION: Final = 1.0 - 1e-6
#: Smallest channel error ``sigma`` the likelihood takes (below it: ``-inf``). The Woodbury
#: form divides by ``sigma^2``; where the channels agree exactly (noise-free synthetic data)
#: the likelihood grows without bound as ``sigma -> 0`` and walkers moving in ``ln sigma``
#: follow it until the Schur complement is singular. No Arms estimate from a recording is
#: relatively more precise than this.
MIN_CHANNEL_ERROR: Final = 1e-6


@dataclass(frozen=True)
class GainPrior:
    """Normal prior of ``log G_c`` (from the log-normal ``gain`` prior).

    Attributes
    ----------
    mean : float
        ``log(median)``.
    sd : float
        ``sigma`` of the log-normal (> 0).
    """

    mean: float
    sd: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mean) and math.isfinite(self.sd) and self.sd > 0):
            raise ValueError(f"GainPrior needs a finite mean and sd > 0, had {self.mean!r}, "
                             f"{self.sd!r}")


def error_gaps(mesh_frequency_Hz: ArrayLike, direction: ArrayLike) -> np.ndarray:
    """``|ln f_(i+1) - ln f_i|`` between neighbouring points, ``inf`` between stretches.

    Parameters
    ----------
    mesh_frequency_Hz : array_like
        ``(N,)`` the points in time order (Hz, > 0).
    direction : array_like
        ``(N,)`` ``"up"``, ``"down"`` or ``"hold"``: a change of direction starts a new
        stretch, whose model error is independent of the previous one's.

    Returns
    -------
    numpy.ndarray
        ``(N - 1,)``.

    Examples
    --------
    >>> error_gaps([100.0, 110.0, 110.0], ["up", "up", "down"]).round(4).tolist()
    [0.0953, inf]
    """
    f = np.asarray(mesh_frequency_Hz, dtype=float)
    d = np.asarray(direction, dtype=object)
    if f.ndim != 1 or d.shape != f.shape:
        raise ValueError(f"mesh_frequency_Hz and direction must be (N,), had {f.shape}, "
                         f"{d.shape}")
    gap = np.abs(np.diff(np.log(f)))
    return np.where(d[1:] == d[:-1], gap, np.inf)


def _correlations(gaps: np.ndarray, length: np.ndarray) -> np.ndarray:
    """``rho`` ``(W, N - 1)`` of the autoregression, 0 where ``length <= 0``."""
    ell = length[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rho = np.where(ell > 0, np.exp(-gaps[None, :] / np.where(ell > 0, ell, 1.0)), 0.0)
    return np.minimum(np.nan_to_num(rho, nan=0.0), MAX_CORRELATION)


def sample_model_error(model_error: ArrayLike, error_length: ArrayLike, gaps: ArrayLike,
                       rng: np.random.Generator) -> np.ndarray:
    """Draws of the shared model error ``delta`` along one run (the module's autoregression).

    Parameters
    ----------
    model_error, error_length : array_like
        ``tau`` and ``ell``, ``(W,)``.
    gaps : array_like
        ``(N - 1,)`` from :func:`error_gaps`.
    rng : numpy.random.Generator

    Returns
    -------
    numpy.ndarray
        ``(W, N)``: each row one path, marginal sd ``tau``.
    """
    tau = np.asarray(model_error, dtype=float)
    rho = _correlations(np.asarray(gaps, dtype=float), np.asarray(error_length, dtype=float))
    eps = rng.standard_normal((tau.size, rho.shape[1] + 1))
    out = np.empty_like(eps)
    out[:, 0] = eps[:, 0]
    for j in range(rho.shape[1]):
        out[:, j + 1] = rho[:, j] * out[:, j] + np.sqrt(1.0 - rho[:, j] ** 2) * eps[:, j + 1]
    return tau[:, None] * out


@dataclass(frozen=True, eq=False)
class _Run:
    """One run's inputs, checked and broadcast (module notes' symbols)."""

    r: np.ndarray          # (W, C, N) residual about the prior gain, 0 where not observed
    mask: np.ndarray       # (C, N) float, 1 where observed
    bad: np.ndarray        # (W,) a non-finite model value at an observed point
    s2: np.ndarray         # (W,) sigma^2 (1 where sigma <= 0: those walkers are -inf)
    t2: np.ndarray         # (W,) tau^2
    rho: np.ndarray        # (W, N - 1)
    ok: np.ndarray         # (W,) sigma > 0, tau >= 0, length >= 0


def _run(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
         channel_error: ArrayLike, prior: GainPrior, error_length: ArrayLike | None,
         gaps: ArrayLike | None) -> _Run:
    y = np.asarray(log_observed, dtype=float)
    mu = np.asarray(log_mu, dtype=float)
    tau = np.asarray(model_error, dtype=float)
    sigma = np.asarray(channel_error, dtype=float)
    if (y.ndim != 2 or mu.ndim != 2 or mu.shape[1] != y.shape[1]
            or tau.shape != mu.shape[:1] or sigma.shape != mu.shape[:1]):
        raise ValueError(f"shapes: log_observed (C, N), log_mu (W, N), model_error (W,), "
                         f"channel_error (W,); had {y.shape}, {mu.shape}, {tau.shape}, "
                         f"{sigma.shape}")
    w, n = mu.shape
    ell = np.zeros(w) if error_length is None else np.asarray(error_length, dtype=float)
    gap = np.full(max(n - 1, 0), np.inf) if gaps is None else np.asarray(gaps, dtype=float)
    if ell.shape != (w,) or gap.shape != (max(n - 1, 0),):
        raise ValueError(f"shapes: error_length (W,) = ({w},), gaps (N - 1,) = ({n - 1},); had "
                         f"{ell.shape}, {gap.shape}")
    mask = np.isfinite(y)
    with np.errstate(invalid="ignore"):
        r = y[None, :, :] - mu[:, None, :] - prior.mean
    bad = np.any(mask[None] & ~np.isfinite(r), axis=(1, 2))
    r = np.where(mask[None] & np.isfinite(r), r, 0.0)
    ok = ((sigma >= MIN_CHANNEL_ERROR) & np.isfinite(sigma) & (tau >= 0) & (ell >= 0)
          & np.isfinite(tau) & np.isfinite(ell))
    s2 = np.where(ok, sigma * sigma, 1.0)
    t2 = np.where(ok, tau * tau, 0.0)
    return _Run(r, mask.astype(float), bad, s2, t2,
                _correlations(gap, np.where(ok, ell, 0.0)), ok)


def _chain(run: _Run) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``tilde A`` (diagonal ``(W, N)``, off-diagonal ``(W, N - 1)``) and ``log det R``."""
    rho = run.rho
    one = 1.0 - rho * rho
    w, n = run.r.shape[0], run.r.shape[2]
    diag = np.ones((w, n))
    diag[:, 1:] = 1.0 / one
    diag[:, :-1] += rho * rho / one
    diag += run.mask.sum(axis=0)[None, :] * (run.t2 / run.s2)[:, None]
    return diag, -rho / one, np.sum(np.log(one), axis=1)


def _ldl_solve(diag: np.ndarray, off: np.ndarray, rhs: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Solve the tridiagonal SPD systems ``(W, N, N) x = rhs (W, N, K)``; also ``log det``."""
    n = diag.shape[1]
    piv = np.empty_like(diag)
    low = np.empty_like(off)
    z = np.empty_like(rhs)
    piv[:, 0] = diag[:, 0]
    z[:, 0] = rhs[:, 0]
    for j in range(n - 1):
        low[:, j] = off[:, j] / piv[:, j]
        piv[:, j + 1] = diag[:, j + 1] - low[:, j] * off[:, j]
        z[:, j + 1] = rhs[:, j + 1] - low[:, j, None] * z[:, j]
    x = np.empty_like(rhs)
    x[:, n - 1] = z[:, n - 1] / piv[:, n - 1, None]
    for j in range(n - 2, -1, -1):
        x[:, j] = z[:, j] / piv[:, j, None] - low[:, j, None] * x[:, j + 1]
    return x, np.sum(np.log(piv), axis=1)


@dataclass(frozen=True, eq=False)
class _Woodbury:
    """The solved pieces of one run for ``W`` walkers (module notes)."""

    u: np.ndarray          # (W, N) tilde A^-1 b_delta
    schur: np.ndarray      # (W, C, C) S
    c: np.ndarray          # (W, C) b_g - A_g,delta A_delta^-1 b_delta
    b_delta: np.ndarray    # (W, N)
    logdet: np.ndarray     # (W,) log det(tau^2 R) + log det A_delta (= log det R tilde A)


def _woodbury(run: _Run, prior: GainPrior) -> _Woodbury:
    m = run.mask                                                    # (C, N)
    s2, t2 = run.s2, run.t2
    diag, off, logdet_r = _chain(run)
    b_delta = run.r.sum(axis=1) / s2[:, None]                       # (W, N)
    b_gain = run.r.sum(axis=2) / s2[:, None]                        # (W, C)
    rhs = np.concatenate([b_delta[:, :, None],
                          np.broadcast_to(m.T[None], (s2.size, *m.T.shape)) / s2[:, None, None]],
                         axis=2)
    x, logdet_a = _ldl_solve(diag, off, rhs)
    u, t = x[:, :, 0], x[:, :, 1:]
    cross = np.einsum("cn,wnd->wcd", m, t) / s2[:, None, None]     # X^T Z tilde A^-1 Z^T X / s2^2
    schur = (np.diag(m.sum(axis=1))[None] / s2[:, None, None] + np.eye(m.shape[0])[None]
             / prior.sd ** 2 - t2[:, None, None] * cross)
    c = b_gain - t2[:, None] * np.einsum("cn,wn->wc", m, u) / s2[:, None]
    return _Woodbury(u, schur, c, b_delta, logdet_r + logdet_a)


def marginal_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
                            channel_error: ArrayLike, prior: GainPrior, *,
                            error_length: ArrayLike | None = None,
                            gaps: ArrayLike | None = None) -> np.ndarray:
    """Log-likelihood of one run's curves with its channel gains integrated out (module notes).

    Parameters
    ----------
    log_observed : array_like
        ``log A``, ``(C, N)`` in time order; NaN where not observed (left out).
    log_mu : array_like
        ``log mu`` of ``W`` parameter sets, ``(W, N)``; a non-finite value at an observed
        point gives ``-inf``.
    model_error : array_like
        ``tau``, ``(W,)`` (>= 0): marginal sd of the error shared by the channels at a point.
    channel_error : array_like
        ``sigma``, ``(W,)`` (>= :data:`MIN_CHANNEL_ERROR`, else ``-inf``): each channel's own
        error.
    prior : GainPrior
    error_length : array_like, optional
        ``ell``, ``(W,)`` (>= 0): the model error's correlation length in ``ln f_m``. None:
        0, independent points.
    gaps : array_like, optional
        ``(N - 1,)`` from :func:`error_gaps`. None: every gap infinite (independent points).

    Returns
    -------
    numpy.ndarray
        ``(W,)``.

    Examples
    --------
    >>> y = np.log([[1.0, 2.0, 4.0]])
    >>> lp = marginal_log_likelihood(y, y, [0.1], [0.05], GainPrior(0.0, 1.0),
    ...                              error_length=[0.2], gaps=[0.1, 0.1])
    >>> bool(np.isfinite(lp[0]))
    True
    """
    run = _run(log_observed, log_mu, model_error, channel_error, prior, error_length, gaps)
    k = _woodbury(run, prior)
    sign, logdet_s = np.linalg.slogdet(k.schur)
    usable = np.isfinite(logdet_s) & (sign > 0)   # else -inf below, never a LinAlgError
    schur = np.where(usable[:, None, None], k.schur, np.eye(k.schur.shape[1])[None])
    solved = np.linalg.solve(schur, k.c[..., None])[..., 0]
    c = run.mask.shape[0]
    n = run.mask.sum()
    quad = (np.sum(run.r * run.r, axis=(1, 2)) / run.s2
            - run.t2 * np.sum(k.b_delta * k.u, axis=1) - np.sum(k.c * solved, axis=1))
    out = -0.5 * (n * (_LOG_2PI + np.log(run.s2)) + k.logdet + c * math.log(prior.sd ** 2)
                  + logdet_s + quad)
    good = run.ok & ~run.bad & usable & np.isfinite(out)
    return np.where(good, out, -np.inf)


def gain_conditional(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
                     channel_error: ArrayLike, prior: GainPrior, *,
                     error_length: ArrayLike | None = None, gaps: ArrayLike | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of one run's ``log G_c`` given the parameters and the data.

    Parameters
    ----------
    log_observed, log_mu, model_error, channel_error, prior, error_length, gaps
        As :func:`marginal_log_likelihood`.

    Returns
    -------
    mean : numpy.ndarray
        ``(W, C)`` (the prior's where a channel has no observed point).
    cov : numpy.ndarray
        ``(W, C, C)``: ``S^{-1}``.
    """
    run = _run(log_observed, log_mu, model_error, channel_error, prior, error_length, gaps)
    k = _woodbury(run, prior)
    cov = np.linalg.inv(k.schur)
    return prior.mean + np.einsum("wcd,wd->wc", cov, k.c), cov


def pointwise_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike,
                             model_error: ArrayLike, channel_error: ArrayLike,
                             prior: GainPrior, *, error_length: ArrayLike | None = None,
                             gaps: ArrayLike | None = None,
                             groups: ArrayLike | None = None) -> np.ndarray:
    """Leave-one-out predictive log density per point (or group of points), channels together.

    ``log p(r_B | r_{-B}, theta) = log p(r) - log p(r_{-B})`` with the gains and the correlated
    model error integrated out (module notes, "Pointwise"), for each unit ``B`` left out.

    Parameters
    ----------
    log_observed, log_mu, model_error, channel_error, prior, error_length, gaps
        As :func:`marginal_log_likelihood`.
    groups : array_like, optional
        ``(N,)`` integer label ``0..G-1`` of the unit each point belongs to (e.g. blocks of
        neighbouring points). None: every point is its own unit.

    Returns
    -------
    numpy.ndarray
        ``(W, G)`` (``G = N`` without ``groups``); NaN for a unit no channel observes (the
        caller keeps the observed ones), ``-inf`` for a walker whose marginal is impossible.
    """
    y = np.asarray(log_observed, dtype=float)
    n = y.shape[-1] if y.ndim == 2 else 0
    label = np.arange(n) if groups is None else np.asarray(groups, dtype=np.int64)
    if y.ndim != 2 or label.shape != (n,) or (n and label.min() < 0):
        raise ValueError(f"groups must be (N,) labels >= 0 for log_observed (C, N); had "
                         f"{label.shape}, {y.shape}")
    kw = {"error_length": error_length, "gaps": gaps}
    full = marginal_log_likelihood(y, log_mu, model_error, channel_error, prior, **kw)
    units = int(label.max()) + 1 if n else 0
    out = np.full((full.size, units), np.nan)
    seen = np.isfinite(y).any(axis=0)
    for u in range(units):
        inside = label == u
        if not (inside & seen).any():
            continue
        rest = np.where(inside[None, :], np.nan, y)
        other = marginal_log_likelihood(rest, log_mu, model_error, channel_error, prior, **kw)
        with np.errstate(invalid="ignore"):
            d = full - other
        out[:, u] = np.where(np.isfinite(d), d, -np.inf)
    return out
