"""Band-limited RMS: :func:`band_rms` and :func:`rms_from_psd`.

RMS in the time domain (band-passed, detrended valid segments) and by Parseval from the PSD;
:func:`mean_square_time`, the time-domain sum of squares, is shared with
:mod:`rigtools.analysis.recording`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import signal as sps

from rigtools.analysis.signal_checks import (
    Detrend,
    Window,
    check_band,
    check_not_constant,
    norm_axis,
)
from rigtools.analysis.spectrum_results import BandRMS, Spectrum
from rigtools.analysis.welch import prepare_welch, welch_psd
from rigtools.analysis.windows import Segments, valid_segments
from rigtools.errors import SignalError

__all__ = ["band_rms", "mean_square_time", "rms_from_psd"]

# --------------------------------------------------------------------------------------------
# RMS


def rms_from_psd(spectrum: Spectrum, band_Hz: Sequence[float] | None = None) -> Any:
    r"""RMS in a band by Parseval: :math:`\sqrt{\sum_{f_{lo} \le f_k \le f_{hi}} S_k \Delta f}`.

    Parameters
    ----------
    spectrum : Spectrum
        A PSD (frequency on the last axis).
    band_Hz : (float, float), optional
        ``(f_lo, f_hi)`` (Hz), both included; default the full band ``[0, fs/2]``.

    Returns
    -------
    numpy.float64 or numpy.ndarray
        RMS (``spectrum.unit``), with the batch shape of the spectrum.
    """
    lo, hi = check_band(band_Hz, spectrum.fs_Hz)
    f = spectrum.freq_Hz
    sel = (f >= lo) & (f <= hi)
    psd = np.asarray(spectrum.psd_per_Hz)
    if psd.ndim > 1:  # frequency on the axis the time axis was on
        psd = np.moveaxis(psd, norm_axis(getattr(spectrum, "freq_axis", -1), psd.ndim), -1)
    ms = np.sum(psd[..., sel], axis=-1) * spectrum.resolution_Hz
    return np.sqrt(ms)[()]


def _detrended(seg: np.ndarray, detrend: Any) -> np.ndarray:
    seg = np.asarray(seg, np.float64)
    if detrend == "constant":
        return seg - seg.mean(axis=-1, keepdims=True)
    if detrend == "linear":
        return sps.detrend(seg, axis=-1, type="linear")
    if detrend is False:
        return seg
    return np.asarray(detrend(seg), np.float64)


def mean_square_time(x: np.ndarray, segs: Segments, rows: np.ndarray, fs: float,
                     band: tuple[float, float], detrend: Any) -> tuple[np.ndarray, int]:
    """Sum over segments of the squares of the band-passed, detrended samples; sample count."""
    total = np.zeros(rows.size)
    full = band[0] <= 0.0 and band[1] >= fs / 2
    for sl in segs.slices():
        seg = x[rows, sl] if rows.size != x.shape[0] else x[:, sl]
        L = seg.shape[-1]
        if full and detrend == "constant":
            # one pass: sum x^2 - (sum x)^2 / L, two-pass when cancellation would bite
            s1 = np.sum(seg, axis=-1, dtype=np.float64)
            s2 = np.einsum("ij,ij->i", seg, seg, dtype=np.float64)
            ss = s2 - s1 * s1 / L
            if np.any(ss <= 1e-6 * s2):
                d = _detrended(seg, detrend)
                ss = np.einsum("ij,ij->i", d, d)
            total += ss
            continue
        d = _detrended(seg, detrend)
        if not full:
            X = np.fft.rfft(d, axis=-1)
            f = np.fft.rfftfreq(L, 1.0 / fs)
            X[:, (f < band[0]) | (f > band[1])] = 0.0
            d = np.fft.irfft(X, n=L, axis=-1)
        total += np.einsum("ij,ij->i", d, d)
    return total, segs.n_samples_kept


def band_rms(x: Any, fs: float, band_Hz: Sequence[float] | None = None, *, valid: Any = None,
             unit: str = "", spectrum: Spectrum | None = None, nperseg: int | None = None,
             resolution_Hz: float | None = None, noverlap: int | None = None,
             window: Window = "hann", detrend: Detrend = "constant", axis: int = -1) -> BandRMS:
    r"""Band-limited RMS in the time domain and by Parseval from the Welch PSD.

    Parameters
    ----------
    x, fs, valid, unit, nperseg, resolution_Hz, noverlap, window, detrend, axis
        As for :func:`welch_psd`.
    band_Hz : (float, float), optional
        ``(f_lo, f_hi)`` (Hz), both included; default the full band ``[0, fs/2]``.
    spectrum : Spectrum, optional
        The Welch PSD of ``x`` if already computed (its settings are then used).

    Returns
    -------
    BandRMS
        ``rms_time`` and ``rms_parseval`` (unit), which agree to the Welch estimator's scatter
        for a stationary signal: within 1 % for broadband noise over a few seconds.

    Notes
    -----
    Time domain: each valid segment long enough for one window (the segments the PSD used)
    is detrended as the windows are (``"constant"``: its mean removed), band-passed by zeroing
    its DFT outside ``[f_lo, f_hi]``, and :math:`\text{RMS}^2 = \sum x_f^2 / n` over all those
    segments. Parseval: see :func:`rms_from_psd`. The two differ by the window weighting
    (each Welch window weights its middle most), by detrending per window instead of per
    segment (which removes a little power below :math:`f_s/N`) and by leakage across the band
    edges.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> r = band_rms(rng.normal(0.0, 1.0, 200_000), 10000.0, (100.0, 2000.0))
    >>> abs(float(r.ratio) - 1) < 0.01
    True
    """
    if spectrum is not None:
        if float(fs) != spectrum.fs_Hz:
            raise SignalError("fs", f"the sample rate of `spectrum`={spectrum.fs_Hz:g} Hz",
                              repr(fs))
        nperseg, noverlap = spectrum.nperseg, spectrum.noverlap
        window, detrend, resolution_Hz = spectrum.window, spectrum.detrend, None
    xs, fs, mask, nps, nov, _, det, _ = prepare_welch(x, fs, valid, nperseg, resolution_Hz,
                                                 noverlap, window, detrend, axis)
    band = check_band(band_Hz, fs)
    if spectrum is None:
        check_not_constant(xs, mask)
        spectrum = welch_psd(xs, fs, valid=None if mask is None else mask, unit=unit,
                             nperseg=nps, noverlap=nov, window=window, detrend=det)
    batch = xs.shape[:-1]
    n = xs.shape[-1]
    x2 = xs.reshape(-1, n)
    m = x2.shape[0]
    ms = np.zeros(m)
    counts = np.zeros(m, np.int64)
    if mask is None or mask.ndim == 1:
        segs = valid_segments(mask if mask is not None else np.ones(n, bool), nps)
        tot, cnt = mean_square_time(x2, segs, np.arange(m), fs, band, det)
        ms[:], counts[:] = tot / max(cnt, 1), cnt
    else:
        m2 = mask.reshape(-1, n)
        for i in range(m):
            segs = valid_segments(m2[i], nps)
            tot, cnt = mean_square_time(x2, segs, np.array([i]), fs, band, det)
            ms[i], counts[i] = tot[0] / max(cnt, 1), cnt
    rms_p = rms_from_psd(spectrum, band)
    return BandRMS(band_Hz=band, rms_time=np.sqrt(ms).reshape(batch)[()],
                   rms_parseval=np.asarray(rms_p).reshape(batch)[()], unit=unit,
                   n_samples=counts.reshape(batch)[()])
