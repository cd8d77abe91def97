"""Spectra of accelerometer channels: Welch PSD, amplitude spectrum, band-limited RMS, quality.

Plain arrays in (one channel ``(n,)`` or several ``(..., n)``, float32 or float64, with an
optional validity mask), frozen dataclasses out:

* :func:`welch_psd` -> :class:`Spectrum`: power spectral density in unit^2/Hz
  (:func:`scipy.signal.welch` underneath), with the Welch window counts and the equivalent
  degrees of freedom of the estimate;
* :func:`amplitude_spectrum` -> :class:`AmplitudeSpectrum`: peak amplitude in unit, window
  corrected, so that a sine of amplitude A reads A at its bin (to the window's scalloping
  tolerance when the sine falls between bins: 0.11 % for ``"flattop"``, 15.1 % for ``"hann"``);
* :func:`band_rms` -> :class:`BandRMS`: band-limited RMS two ways, in the time domain and by
  Parseval from the PSD, and :func:`rms_from_psd`;
* :func:`detect_clipping` -> :class:`Clipping`, and :func:`window_properties` ->
  :class:`WindowProperties` (equivalent noise bandwidth, scalloping loss, spectral window).

Gaps are never bridged: the mask splits each channel into valid segments
(:mod:`rigtools.analysis.windows`); Welch windows are laid inside each segment, never across a
gap; a segment too short for one window is dropped and counted. The estimate is the mean
(or median) over all windows of all segments.

Errors (all :class:`~rigtools.errors.RigtoolsError`, so the CLI reports them cleanly)::

    RigtoolsError
    └── SignalError (ValueError)           a signal cannot be analysed as asked
        ├── InsufficientDataError          too short for the requested resolution
        └── ConstantSignalError            no variation at all (dead channel)

Clipping is a flag (:func:`detect_clipping`), not an error: the spectrum of a clipped signal
exists but is distorted (harmonics of the clipped waveform), and the caller decides.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.special import polygamma

from rigtools.analysis.rms import band_rms, rms_from_psd
from rigtools.analysis.spectral_window import WindowProperties, window_properties
from rigtools.analysis.spectrum_results import (
    AmplitudeSpectrum,
    BandRMS,
    Clipping,
    Spectrum,
    WelchAccount,
)
from rigtools.analysis.welch import amplitude_spectrum, welch_psd
from rigtools.errors import ConstantSignalError, InsufficientDataError, SignalError

__all__ = [
    "AmplitudeSpectrum",
    "BandRMS",
    "Clipping",
    "ConstantSignalError",
    "InsufficientDataError",
    "SignalError",
    "Spectrum",
    "WelchAccount",
    "WindowProperties",
    "amplitude_spectrum",
    "band_rms",
    "detect_clipping",
    "log_chi2_stats",
    "rms_from_psd",
    "welch_psd",
    "window_properties",
]

# --------------------------------------------------------------------------------------------
# quality


def detect_clipping(x: Any, valid: Any = None, *, min_run: int = 3,
                    full_scale: Sequence[float] | None = None) -> Clipping:
    """Find runs of samples stuck at the channel's extreme values.

    A sensor or logger that saturates holds its extreme code, e.g. the int16 full scale of
    the reference DBC (-491.52 and 491.505 m/s^2), for several samples in a row. This looks
    for runs of identical samples at the largest and the smallest valid value, whatever they
    are; a genuine waveform reaches its extreme once, or for a sample or two when it is
    oversampled and quantised.

    Parameters
    ----------
    x : array_like
        One channel, shape ``(n,)``.
    valid : array_like of bool, optional
        Validity mask; default the finite samples.
    min_run : int
        Identical consecutive samples at an extreme taken as clipping.
    full_scale : (float, float), optional
        ``(low, high)`` full-scale limits of the acquisition, if known: any valid sample at or
        beyond them counts as clipped, whatever the run length.

    Returns
    -------
    Clipping

    Examples
    --------
    >>> x = np.clip(3 * np.sin(np.linspace(0, 20, 1000)), -2.0, 2.0)
    >>> c = detect_clipping(x)
    >>> c.clipped, c.high, c.low
    (True, 2.0, -2.0)
    """
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise SignalError("x", "one channel, shape (n,)", f"shape {a.shape}")
    if int(min_run) != min_run or min_run < 1:
        raise SignalError("min_run", "an integer >= 1", repr(min_run))
    v = np.isfinite(a) if valid is None else np.asarray(valid, bool)
    if v.shape != a.shape:
        raise SignalError("valid", f"of shape {a.shape}", str(v.shape))
    whole = bool(v.all())
    if not whole and not v.any():
        return Clipping(False, 0, 0, 0, float("nan"), float("nan"), int(min_run))
    hi = float(a.max() if whole else a[v].max())
    lo = float(a.min() if whole else a[v].min())
    n_clipped = n_runs = longest = 0
    if hi == lo:
        return Clipping(False, 0, 0, a.size if whole else int(v.sum()), hi, lo, int(min_run))
    for level in (hi, lo):
        idx = np.flatnonzero(a == level)
        if not whole:
            idx = idx[v[idx]]
        breaks = np.flatnonzero(np.diff(idx) != 1)
        run_len = np.diff(np.r_[0, breaks + 1, idx.size])
        longest = max(longest, int(run_len.max()))
        stuck = run_len >= min_run
        n_runs += int(stuck.sum())
        n_clipped += int(run_len[stuck].sum())
    if full_scale is not None:
        fs_lo, fs_hi = (float(b) for b in full_scale)
        beyond = (a >= fs_hi) | (a <= fs_lo)
        if not whole:
            beyond &= v
        nb = int(np.count_nonzero(beyond))
        if nb:
            idx = np.flatnonzero(beyond)
            runs = int(np.count_nonzero(np.diff(idx) != 1)) + 1
            n_clipped = max(n_clipped, nb)
            n_runs = max(n_runs, runs)
    return Clipping(n_runs > 0, n_clipped, n_runs, longest, hi, lo, int(min_run))


def log_chi2_stats(dof: float) -> tuple[float, float]:
    r"""Bias and variance of :math:`\ln(\hat S / S)` for a :math:`\chi^2_\nu/\nu` estimate.

    :math:`E[\ln \hat S/S] = \psi(\nu/2) - \ln(\nu/2)` and
    :math:`\mathrm{Var}[\ln \hat S] = \psi'(\nu/2)` (digamma and trigamma), about
    :math:`-1/\nu` and :math:`2/\nu` for large :math:`\nu`.
    """
    h = 0.5 * float(dof)
    return float(polygamma(0, h) - np.log(h)), float(polygamma(1, h))
