r"""Log-normal likelihood of Arms run-up curves, with the channel gains marginalised.

A model error shared by the channels at a point, and each channel's own error.

Observation model (issue 20 item 1; :mod:`rigtools.calibration.runup_forward` gives
``mu``): on channel ``c`` at point ``i`` of a run,

.. math:: \log A_{c,i} = g_c + \log \mu_i(\theta) + \delta_i + e_{c,i}, \qquad
          \delta_i \sim N(0, \tau^2), \quad e_{c,i} \sim N(0, \sigma^2), \quad
          g_c = \log G_c \sim N(m_0, s_0^2)

* ``tau`` is the ``model_error``: the model's relative error at a point, **the same on every
  channel** (every channel sees the one DTE through its own gain, so where the model is off
  it is off on all of them). Counting it once per channel would take three channels for
  three independent looks at one discrepancy: on the demo's run-up the residuals about the
  model at the truth agree across the channels to 0.16 % while they scatter by 15 % from point
  to point, and the natural frequency's interval came out a factor ``sqrt(3)`` too narrow.
* ``sigma`` is the ``channel_error``: what each channel adds on its own (sensor noise, the
  order-spectrum floor, a transfer path that is not quite flat).
* ``(m_0, s_0) = (log median, sigma)`` of the log-normal ``gain`` prior; each channel of each
  run has its own gain.

With ``tau = 0`` this is the independent log-normal model, channel by channel.

Marginal (:func:`marginal_log_likelihood`). Per run the residuals ``r = log A - log mu -
m_0`` over the observed (channel, point) pairs are Normal with covariance
``Sigma = Sigma_0 + s_0^2 A A^T``, ``A`` the channel indicator and ``Sigma_0`` block diagonal
over the points with blocks ``sigma^2 I + tau^2 1 1^T`` (the ``n_i`` channels observed at
point ``i``). Each block inverts in closed form (Sherman-Morrison, ``kappa_i = tau^2 /
(sigma^2 + n_i tau^2)``), and the gains by Woodbury with the ``C x C`` matrix
``P = I / s_0^2 + A^T Sigma_0^{-1} A``:

.. math:: \log p(r \mid \theta) = -\tfrac12\Big[n \log 2\pi + \log\det\Sigma_0
          + \log\det(s_0^2 P) + r^T\Sigma_0^{-1} r - b^T P^{-1} b\Big], \qquad
          b = A^T \Sigma_0^{-1} r

with ``log det Sigma_0 = sum_i [n_i log sigma^2 + log(1 + n_i tau^2 / sigma^2)]``. The
gains' conditional posterior is Normal with precision ``P`` and mean ``m_0 + P^{-1} b``
(:func:`gain_conditional`; the gains of one run are correlated through the shared term).

The densities are those of ``log A`` (the Jacobian ``-sum log A`` is the same for every model
and parameter, so it changes no comparison and is left out).

**Pointwise log-likelihood** for PSIS-LOO: one term per observed (run, point), all its
channels together, ``log N(u_i; 0, sigma^2 I + tau^2 1 1^T)`` with ``u_{c,i} = log A_{c,i} -
g_c - log mu_i`` and ``g`` drawn from its exact conditional for each posterior draw
(:func:`pointwise_log_likelihood`); given the gains the points are independent, so these are
the per-observation terms of the joint posterior's likelihood. A point is the unit left out:
its channels share ``delta_i``. The Bayes identity ``log p(r|theta) = sum_i log p(r_i|g) +
log p(g) - log p(g|r, theta)``, true for every ``g``, ties the two (tested, as is the marginal
against the dense multivariate Normal).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "GainPrior",
    "gain_conditional",
    "marginal_log_likelihood",
    "pointwise_log_likelihood",
]

_LOG_2PI: Final = math.log(2.0 * math.pi)


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


def _check(y: np.ndarray, mu: np.ndarray, tau: np.ndarray, sigma: np.ndarray) -> None:
    if (y.ndim != 2 or mu.ndim != 2 or mu.shape[1] != y.shape[1]
            or tau.shape != mu.shape[:1] or sigma.shape != mu.shape[:1]):
        raise ValueError(f"shapes: log_observed (C, N), log_mu (W, N), model_error (W,), "
                         f"channel_error (W,); had {y.shape}, {mu.shape}, {tau.shape}, "
                         f"{sigma.shape}")


@dataclass(frozen=True, eq=False)
class _Blocks:
    """The per-walker pieces of the Woodbury form (module notes); ``s2 = sigma^2``."""

    mask: np.ndarray      # (C, N) observed
    n: np.ndarray         # (N,) channels observed per point
    s2: np.ndarray        # (W,)
    kappa: np.ndarray     # (W, N)
    precision: np.ndarray  # (W, C, C) P
    b: np.ndarray         # (W, C)
    quad0: np.ndarray     # (W,) r' Sigma_0^-1 r
    logdet0: np.ndarray   # (W,)
    bad: np.ndarray       # (W,) a non-finite model value at an observed point


def _blocks(y: np.ndarray, mu: np.ndarray, tau: np.ndarray, sigma: np.ndarray,
            prior: GainPrior) -> _Blocks:
    mask = np.isfinite(y)
    n = mask.sum(axis=0).astype(float)
    with np.errstate(invalid="ignore"):
        r = y[None, :, :] - mu[:, None, :] - prior.mean           # (W, C, N)
    bad = np.any(mask[None] & ~np.isfinite(r), axis=(1, 2))
    r = np.where(mask[None], r, 0.0)
    r = np.where(np.isfinite(r), r, 0.0)
    s2 = np.where(sigma > 0, sigma * sigma, 1.0)
    t2 = tau * tau
    kappa = t2[:, None] / (s2[:, None] + n[None, :] * t2[:, None])
    total = r.sum(axis=1)                                           # (W, N)
    quad0 = (np.sum(r * r, axis=(1, 2)) - np.sum(kappa * total * total, axis=1)) / s2
    logdet0 = (n.sum() * np.log(s2)
               + np.sum(np.log1p(n[None, :] * t2[:, None] / s2[:, None]), axis=1))
    m = mask.astype(float)
    b = (r.sum(axis=2) - np.einsum("wi,ci->wc", kappa * total, m)) / s2[:, None]
    f = (np.diag(m.sum(axis=1))[None] - np.einsum("wi,ci,di->wcd", kappa, m, m)) / s2[:, None,
                                                                                       None]
    precision = f + np.eye(y.shape[0])[None] / prior.sd ** 2
    return _Blocks(mask, n, s2, kappa, precision, b, quad0, logdet0, bad)


def _inputs(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
            channel_error: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    y = np.asarray(log_observed, dtype=float)
    mu = np.asarray(log_mu, dtype=float)
    tau = np.asarray(model_error, dtype=float)
    sigma = np.asarray(channel_error, dtype=float)
    _check(y, mu, tau, sigma)
    return y, mu, tau, sigma


def marginal_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
                            channel_error: ArrayLike, prior: GainPrior) -> np.ndarray:
    """Log-likelihood of one run's curves with its channel gains integrated out (module notes).

    Parameters
    ----------
    log_observed : array_like
        ``log A``, ``(C, N)``; NaN where not observed (left out).
    log_mu : array_like
        ``log mu`` of ``W`` parameter sets, ``(W, N)``; a non-finite value at an observed
        point gives ``-inf``.
    model_error : array_like
        ``tau``, ``(W,)`` (>= 0): the error shared by the channels at a point.
    channel_error : array_like
        ``sigma``, ``(W,)`` (> 0): each channel's own error.
    prior : GainPrior

    Returns
    -------
    numpy.ndarray
        ``(W,)``.

    Examples
    --------
    >>> y = np.log([[1.0, 2.0, 4.0]])
    >>> lp = marginal_log_likelihood(y, y, [0.1], [0.05], GainPrior(0.0, 1.0))
    >>> bool(np.isfinite(lp[0]))
    True
    """
    y, mu, tau, sigma = _inputs(log_observed, log_mu, model_error, channel_error)
    k = _blocks(y, mu, tau, sigma, prior)
    sign, logdet_p = np.linalg.slogdet(k.precision)
    solved = np.linalg.solve(k.precision, k.b[..., None])[..., 0]
    c = y.shape[0]
    out = -0.5 * (k.n.sum() * _LOG_2PI + k.logdet0 + c * math.log(prior.sd ** 2) + logdet_p
                  + k.quad0 - np.sum(k.b * solved, axis=1))
    ok = (sigma > 0) & (tau >= 0) & ~k.bad & (sign > 0)
    return np.where(ok, out, -np.inf)


def gain_conditional(log_observed: ArrayLike, log_mu: ArrayLike, model_error: ArrayLike,
                     channel_error: ArrayLike, prior: GainPrior
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of one run's ``log G_c`` given the parameters and the data.

    Parameters
    ----------
    log_observed, log_mu, model_error, channel_error, prior
        As :func:`marginal_log_likelihood`.

    Returns
    -------
    mean : numpy.ndarray
        ``(W, C)`` (the prior's where a channel has no observed point).
    cov : numpy.ndarray
        ``(W, C, C)``.
    """
    y, mu, tau, sigma = _inputs(log_observed, log_mu, model_error, channel_error)
    k = _blocks(y, mu, tau, sigma, prior)
    cov = np.linalg.inv(k.precision)
    mean = prior.mean + np.einsum("wcd,wd->wc", cov, k.b)
    return mean, cov


def pointwise_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike,
                             model_error: ArrayLike, channel_error: ArrayLike,
                             log_gain: ArrayLike) -> np.ndarray:
    """Per-point log-likelihood given the gains, all channels of a point together.

    ``log N(u_i; 0, sigma^2 I + tau^2 1 1^T)``, ``u_{c,i} = log A_{c,i} - g_c - log mu_i``
    over the channels observed at point ``i``.

    Parameters
    ----------
    log_observed : array_like
        ``(C, N)``, NaN where not observed.
    log_mu : array_like
        ``(W, N)``.
    model_error, channel_error : array_like
        ``(W,)`` each.
    log_gain : array_like
        ``(W, C)``: e.g. drawn from :func:`gain_conditional`.

    Returns
    -------
    numpy.ndarray
        ``(W, N)``; NaN at a point no channel observes (the caller keeps the observed ones).
    """
    y, mu, tau, sigma = _inputs(log_observed, log_mu, model_error, channel_error)
    g = np.asarray(log_gain, dtype=float)[:, :, None]
    mask = np.isfinite(y)
    n = mask.sum(axis=0).astype(float)
    with np.errstate(invalid="ignore"):
        u = y[None] - g - mu[:, None, :]
    bad = np.any(mask[None] & ~np.isfinite(u), axis=1)              # (W, N)
    u = np.where(mask[None] & np.isfinite(u), u, 0.0)
    s2 = (sigma * sigma)[:, None]
    t2 = (tau * tau)[:, None]
    total = u.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = t2 / (s2 + n[None, :] * t2)
        out = -0.5 * (n[None, :] * (_LOG_2PI + np.log(s2)) + np.log1p(n[None, :] * t2 / s2)
                      + (np.sum(u * u, axis=1) - kappa * total * total) / s2)
    out = np.where(bad | ~np.isfinite(out), -np.inf, out)
    return np.where(n[None, :] > 0, out, np.nan)
