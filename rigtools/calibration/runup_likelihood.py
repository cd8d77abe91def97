r"""Log-normal likelihood of Arms run-up curves with the channel gains marginalised.

Observation model (issue 20 item 1; :mod:`rigtools.calibration.runup_forward` gives
``mu``): on channel ``c`` at point ``i`` of a run,

.. math:: \log A_{c,i} = g_c + \log \mu_i(\theta) + \varepsilon_{c,i}, \qquad
          \varepsilon_{c,i} \sim N(0, \sigma^2), \qquad g_c = \log G_c \sim N(m_0, s_0^2)

with ``sigma`` the ``model_error`` (a relative error: Arms spans one to two decades) and
``(m_0, s_0) = (log median, sigma)`` of the log-normal ``gain`` prior. Each channel of each
run has its own gain. With ``n`` observed points, residuals ``r_i = log A_i - log mu_i``,
their mean ``rbar`` and the sum of squares about it ``SS``, the gain integrates out in
closed form:

.. math:: \log p(r \mid \theta) = -\tfrac{n}{2}\log(2\pi\sigma^2)
          - \tfrac12 \log\!\left(1 + \frac{n s_0^2}{\sigma^2}\right)
          - \frac{SS}{2\sigma^2} - \frac{n (\bar r - m_0)^2}{2 (\sigma^2 + n s_0^2)}

and the gain's conditional posterior is Normal with precision ``P = 1/s_0^2 + n/sigma^2``
and mean ``(m_0/s_0^2 + n rbar/sigma^2) / P`` (:func:`gain_conditional`).

The densities are those of ``log A`` (the Jacobian ``-sum log A`` is the same for every model
and parameter, so it changes no comparison and is left out).

**Pointwise log-likelihood** for PSIS-LOO: one term per observed (run, channel, point),
``log N(log A_{c,i}; g_c + log mu_i, sigma^2)`` with ``g_c`` drawn from its exact
conditional for each posterior draw (:func:`pointwise_log_likelihood`); the draws of
``(theta, g)`` are then draws of the joint posterior, for which these terms are the
per-observation likelihood. The Bayes identity ``log p(r|theta) = sum_i log p(r_i|g) + log
p(g) - log p(g|r, theta)``, true for every ``g``, ties the two (tested).
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


def _stats(residual: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n``, ``rbar`` and ``SS`` over the last axis (masked points left out)."""
    n = mask.sum(axis=-1).astype(float)
    r = np.where(mask, residual, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rbar = np.where(n > 0, r.sum(axis=-1) / np.maximum(n, 1.0), 0.0)
        ss = np.sum(np.where(mask, (residual - rbar[..., None]) ** 2, 0.0), axis=-1)
    return n, rbar, ss


def marginal_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike, sigma: ArrayLike,
                            prior: GainPrior) -> np.ndarray:
    """Log-likelihood of the curves with every channel gain integrated out (module notes).

    Parameters
    ----------
    log_observed : array_like
        ``log A``, ``(C, N)``; NaN where not observed (left out).
    log_mu : array_like
        ``log mu`` of ``W`` parameter sets, ``(W, N)``; a non-finite value at an observed
        point gives ``-inf``.
    sigma : array_like
        ``model_error``, ``(W,)`` (> 0).
    prior : GainPrior

    Returns
    -------
    numpy.ndarray
        ``(W,)``, summed over channels.

    Examples
    --------
    >>> y = np.log([[1.0, 2.0, 4.0]])
    >>> lp = marginal_log_likelihood(y, y, [0.1], GainPrior(0.0, 1.0))
    >>> bool(np.isfinite(lp[0]))
    True
    """
    y = np.asarray(log_observed, dtype=float)
    mu = np.asarray(log_mu, dtype=float)
    s = np.asarray(sigma, dtype=float)
    if y.ndim != 2 or mu.ndim != 2 or mu.shape[1] != y.shape[1] or s.shape != mu.shape[:1]:
        raise ValueError(f"shapes: log_observed (C, N), log_mu (W, N), sigma (W,); had "
                         f"{y.shape}, {mu.shape}, {s.shape}")
    mask = np.isfinite(y)
    with np.errstate(invalid="ignore"):
        resid = y[None, :, :] - mu[:, None, :]                    # (W, C, N)
    bad = np.any(mask[None] & ~np.isfinite(resid), axis=(1, 2))
    resid = np.where(mask[None], resid, 0.0)
    n, rbar, ss = _stats(resid, np.broadcast_to(mask[None], resid.shape))
    positive = s > 0
    s2 = np.where(positive, s * s, 1.0)[:, None]
    v0 = prior.sd ** 2
    out = (-0.5 * n * (_LOG_2PI + np.log(s2)) - 0.5 * np.log1p(n * v0 / s2)
           - 0.5 * ss / s2 - 0.5 * n * (rbar - prior.mean) ** 2 / (s2 + n * v0))
    total = out.sum(axis=1)
    return np.where(bad | ~positive, -np.inf, total)


def gain_conditional(log_observed: ArrayLike, log_mu: ArrayLike, sigma: ArrayLike,
                     prior: GainPrior) -> tuple[np.ndarray, np.ndarray]:
    """Mean and sd of ``log G_c`` given the parameters and the data (Normal, exact).

    Parameters
    ----------
    log_observed, log_mu, sigma, prior
        As :func:`marginal_log_likelihood`.

    Returns
    -------
    mean, sd : numpy.ndarray
        ``(W, C)`` each (the prior where a channel has no observed point).
    """
    y = np.asarray(log_observed, dtype=float)
    mu = np.asarray(log_mu, dtype=float)
    s = np.asarray(sigma, dtype=float)
    mask = np.isfinite(y)
    resid = np.where(mask[None], y[None, :, :] - mu[:, None, :], 0.0)
    n, rbar, _ = _stats(resid, np.broadcast_to(mask[None], resid.shape))
    s2 = (s * s)[:, None]
    v0 = prior.sd ** 2
    precision = 1.0 / v0 + n / s2
    mean = (prior.mean / v0 + n * rbar / s2) / precision
    return mean, 1.0 / np.sqrt(precision)


def pointwise_log_likelihood(log_observed: ArrayLike, log_mu: ArrayLike, sigma: ArrayLike,
                             log_gain: ArrayLike) -> np.ndarray:
    """Per-point log-likelihood given the gains, ``log N(y; g_c + log mu_i, sigma^2)``.

    Parameters
    ----------
    log_observed : array_like
        ``(C, N)``, NaN where not observed.
    log_mu : array_like
        ``(W, N)``.
    sigma : array_like
        ``(W,)``.
    log_gain : array_like
        ``(W, C)``: e.g. drawn from :func:`gain_conditional`.

    Returns
    -------
    numpy.ndarray
        ``(W, C, N)``; NaN where not observed (the caller keeps the observed points).
    """
    y = np.asarray(log_observed, dtype=float)
    mu = np.asarray(log_mu, dtype=float)
    s = np.asarray(sigma, dtype=float)[:, None, None]
    g = np.asarray(log_gain, dtype=float)[:, :, None]
    r = y[None] - g - mu[:, None, :]
    with np.errstate(invalid="ignore"):
        out = -0.5 * (_LOG_2PI + 2.0 * np.log(s)) - 0.5 * (r / s) ** 2
    out = np.where(np.isfinite(y)[None], out, np.nan)
    return np.where(np.isfinite(y)[None] & ~np.isfinite(out), -np.inf, out)
