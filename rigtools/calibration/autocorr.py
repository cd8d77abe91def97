r"""Integrated autocorrelation time of an ensemble chain, all walkers and parameters at once.

The estimator of :func:`emcee.autocorr.integrated_time` (Goodman and Weare 2010; Sokal's
self-consistent window, ``c = 5``): per parameter, the normalised autocorrelation function of
each walker, averaged over walkers,

.. math::

    \hat\rho(\tau) = \frac{1}{W} \sum_w \frac{\hat c_w(\tau)}{\hat c_w(0)}, \qquad
    \hat\tau(M) = 1 + 2 \sum_{\tau=1}^{M} \hat\rho(\tau),

evaluated at the smallest window ``M >= c tau(M)``. emcee computes the ``W x D``
autocorrelation functions one FFT call at a time; here they are one real FFT over the step
axis of the whole ``(steps, W, D)`` array, which makes the convergence check at every
``check_every`` steps cheap (it otherwise dominates a calibration's time). Same numbers as
emcee's to round-off (``tests/calibration/test_sampler.py``). A walker that never moved (zero
variance) contributes ``rho = 0`` beyond lag 0 instead of emcee's NaN.

References
----------
.. [1] J. Goodman, J. Weare, "Ensemble samplers with affine invariance", Comm. App. Math.
   Comp. Sci. 5 (2010) 65-80.
.. [2] A. Sokal, "Monte Carlo methods in statistical mechanics: foundations and new
   algorithms", lecture notes (1996), p. 16.
"""

from __future__ import annotations

import numpy as np
from emcee.autocorr import auto_window

__all__ = ["integrated_time"]


def _next_pow_two(n: int) -> int:
    i = 1
    while i < n:
        i <<= 1
    return i


def integrated_time(chain: np.ndarray, c: float = 5.0) -> np.ndarray:
    """Integrated autocorrelation time of each parameter (steps).

    Parameters
    ----------
    chain : numpy.ndarray
        ``(steps, W, D)``.
    c : float
        Window constant of Sokal's rule.

    Returns
    -------
    numpy.ndarray
        ``(D,)``.

    Examples
    --------
    An AR(1) series with coefficient 0.9 has ``tau = (1 + 0.9) / (1 - 0.9) = 19``:

    >>> rng = np.random.default_rng(0)
    >>> x = np.zeros((20000, 16, 1))
    >>> e = rng.standard_normal(x.shape)
    >>> for t in range(1, x.shape[0]):
    ...     x[t] = 0.9 * x[t - 1] + e[t]
    >>> bool(abs(integrated_time(x)[0] - 19.0) < 1.5)
    True
    """
    x = np.asarray(chain, dtype=float)
    n_t, _, n_d = x.shape
    n = _next_pow_two(n_t)
    y = x - x.mean(axis=0, keepdims=True)
    f = np.fft.rfft(y, n=2 * n, axis=0)
    acf = np.fft.irfft(f * np.conjugate(f), n=2 * n, axis=0)[:n_t]
    acf0 = acf[0]
    moving = acf0 > 0
    rho = np.where(moving, acf / np.where(moving, acf0, 1.0), 0.0)
    rho[0] = 1.0
    mean_rho = rho.mean(axis=1)                               # (n_t, D)
    taus = 2.0 * np.cumsum(mean_rho, axis=0) - 1.0
    out = np.empty(n_d)
    for d in range(n_d):
        out[d] = taus[auto_window(taus[:, d], c), d]
    return out
