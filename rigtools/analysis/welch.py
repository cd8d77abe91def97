"""Welch estimation over the valid segments of a gapped signal.

The public :func:`welch_psd` and :func:`amplitude_spectrum`, and the machinery they share with
the RMS and recording analyses: :func:`prepare_welch` (argument checks and the window) and
:func:`welch_core` (the estimate over the valid segments, with its account). Windows are laid
inside each valid segment, never across a gap.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal as sps

from rigtools.analysis.signal_checks import (
    Average,
    Detrend,
    Window,
    as_signal,
    check_detrend,
    check_fs,
    check_not_constant,
    check_noverlap,
    check_valid,
    norm_axis,
    resolve_nperseg,
    row_name,
)
from rigtools.analysis.spectral_window import WindowProperties, window_array, window_properties
from rigtools.analysis.spectrum_results import AmplitudeSpectrum, Spectrum, WelchAccount
from rigtools.analysis.windows import Segments, n_windows, valid_segments
from rigtools.errors import InsufficientDataError, SignalError

__all__ = ["amplitude_spectrum", "prepare_welch", "welch_core", "welch_psd"]

# --------------------------------------------------------------------------------------------
# Welch over valid segments


def _welch_dof(lengths: np.ndarray, nperseg: int, noverlap: int, props: WindowProperties
               ) -> float:
    """Equivalent dof of the mean of all windows over segments of ``lengths`` (Eq. 292b)."""
    k = n_windows(lengths, nperseg, noverlap)
    K = int(k.sum())
    if K == 0:
        return 0.0
    rho2 = props.overlap_correlation(noverlap)
    var = float(k.sum())
    for m, r in enumerate(rho2, start=1):
        var += 2.0 * r * float(np.sum(np.clip(k - m, 0, None)))
    return 2.0 * K * K / var


def _median_bias(n: int) -> float:
    """Bias of the median of n periodograms relative to the mean (Allen et al. 2012, App. B)."""
    ii_2 = 2 * np.arange(1.0, (n - 1) // 2 + 1)
    return float(1 + np.sum(1.0 / (ii_2 + 1) - 1.0 / ii_2))


def _longest_run(mask: np.ndarray | None, n: int) -> int:
    if mask is None:
        return n
    s = valid_segments(mask, 1)
    return int(s.lengths.max()) if s.n_kept else 0


def welch_core(x: np.ndarray, mask: np.ndarray | None, fs: float, w: np.ndarray,
                nperseg: int, noverlap: int, detrend: Any, average: str, scaling: str,
                props: WindowProperties) -> tuple[np.ndarray, np.ndarray, WelchAccount,
                                                  list[Segments]]:
    """Welch over the valid segments; x has the time axis last, mask None, (n,) or x.shape.

    Returns freq, P (float64, batch + (n_freq,)), the account and, per row group, segments.
    """
    batch = x.shape[:-1]
    n = x.shape[-1]
    x2 = x.reshape(-1, n)
    m = x2.shape[0]
    nf = nperseg // 2 + 1
    P = np.empty((m, nf), np.float64)
    acc = {k: np.zeros(m, np.int64) for k in ("n_windows", "n_segments", "n_segments_dropped",
                                              "n_samples_dropped", "n_invalid",
                                              "n_samples_used")}
    dof = np.zeros(m, np.float64)
    # rows sharing a mask are analysed together (one scipy call per segment)
    if mask is None or mask.ndim == 1:
        groups: list[tuple[np.ndarray, np.ndarray | None]] = [(np.arange(m), mask)]
    else:
        m2 = mask.reshape(-1, n)
        by_key: dict[bytes, list[int]] = {}
        for i in range(m):
            row = m2[i]
            key = b"all" if row.all() else row.tobytes()
            by_key.setdefault(key, []).append(i)
        groups = [(np.asarray(rows), None if key == b"all" else m2[rows[0]])
                  for key, rows in by_key.items()]
    seg_list = []
    freq = np.fft.rfftfreq(nperseg, 1.0 / fs)
    kw = dict(fs=fs, window=w, nperseg=nperseg, noverlap=noverlap, detrend=detrend,
              scaling=scaling, axis=-1)
    for rows, gmask in groups:
        segs = valid_segments(gmask if gmask is not None else np.ones(n, bool), nperseg)
        seg_list.append(segs)
        if segs.n_kept == 0:
            names = ", ".join(row_name(np.unravel_index(int(r), batch), batch)
                              for r in rows[:4])
            longest = _longest_run(gmask, n)
            raise InsufficientDataError(
                "nperseg", f"<= the longest valid segment of {names}={longest} samples",
                str(nperseg),
                f"resolution {fs / nperseg:g} Hz needs {nperseg / fs:g} s without a gap; "
                f"{segs.n_found} valid segment(s), {segs.n_invalid} invalid sample(s)")
        xg = x2 if rows.size == m else x2[rows]
        k_seg = n_windows(segs.lengths, nperseg, noverlap)
        K = int(k_seg.sum())
        if segs.is_whole:
            _, p = sps.welch(xg, average=average, **kw)
            Pg = np.asarray(p, np.float64)
        elif average == "mean":
            Pg = np.zeros((rows.size, nf))
            for sl, k in zip(segs.slices(), k_seg, strict=True):
                _, p = sps.welch(xg[:, sl], average="mean", **kw)
                Pg += k * p
            Pg /= K
        else:
            parts = []
            for sl in segs.slices():
                _, _, s = sps.spectrogram(xg[:, sl], mode="psd", **kw)
                parts.append(s)
            allw = np.concatenate(parts, axis=-1)
            Pg = np.asarray(np.median(allw, axis=-1), np.float64) / _median_bias(allw.shape[-1])
        P[rows] = Pg
        acc["n_windows"][rows] = K
        acc["n_segments"][rows] = segs.n_kept
        acc["n_segments_dropped"][rows] = segs.n_dropped
        acc["n_samples_dropped"][rows] = segs.n_samples_dropped
        acc["n_invalid"][rows] = segs.n_invalid
        acc["n_samples_used"][rows] = segs.n_samples_kept
        dof[rows] = _welch_dof(segs.lengths, nperseg, noverlap, props)
    account = WelchAccount(dof=dof.reshape(batch),
                           **{k: v.reshape(batch) for k, v in acc.items()})
    return freq, P.reshape(*batch, nf), account, seg_list


def prepare_welch(x: Any, fs: float, valid: Any, nperseg: int | None,
                  resolution_Hz: float | None, noverlap: int | None, window: Window,
                  detrend: Any, axis: int
                  ) -> tuple[np.ndarray, float, np.ndarray | None, int, int, np.ndarray, Any,
                             WindowProperties]:
    """Check the arguments of a Welch estimate, as :func:`welch_psd` takes them.

    Returns the signal with the time axis last, the sample rate (Hz), the validity mask (None
    when every sample is valid), ``nperseg``, ``noverlap``, the window's samples, the detrend
    and the window's :class:`WindowProperties`.
    """
    xs = as_signal(x, axis)
    fs = check_fs(fs)
    nps = resolve_nperseg(nperseg, resolution_Hz, fs)
    if nps > xs.shape[-1]:
        raise InsufficientDataError(
            "nperseg", f"<= len(x)={xs.shape[-1]}", str(nps),
            f"resolution {fs / nps:g} Hz needs {nps / fs:g} s of signal, "
            f"there are {xs.shape[-1] / fs:g} s")
    nov = check_noverlap(noverlap, nps)
    det = check_detrend(detrend)
    mask = check_valid(valid, xs, axis)
    w = window_array(window, nps)
    props = window_properties(window if not isinstance(window, np.ndarray) else w, nps)
    return xs, fs, mask, nps, nov, w, det, props


def welch_psd(x: Any, fs: float, *, valid: Any = None, unit: str = "",
              nperseg: int | None = None, resolution_Hz: float | None = None,
              noverlap: int | None = None, window: Window = "hann", detrend: Detrend = "constant",
              average: Average = "mean", axis: int = -1) -> Spectrum:
    r"""Welch power spectral density of one or several channels, split at their gaps.

    Parameters
    ----------
    x : array_like
        Samples, float32 or float64 (others are converted to float64), shape ``(..., n)``
        with the time axis at ``axis``.
    fs : float
        Sample rate (Hz).
    valid : array_like of bool, optional
        Validity mask, shape ``(n,)`` (shared) or ``x.shape``. ``False`` samples (gaps,
        rejected samples) are never used; the signal is split into valid segments and no
        window straddles a gap. Default: the finite samples.
    unit : str
        Unit of ``x``; the PSD is in unit^2/Hz.
    nperseg : int, optional
        Window length (samples). Default 4096, or from ``resolution_Hz``.
    resolution_Hz : float, optional
        Requested bin spacing (Hz): ``nperseg = ceil(fs / resolution_Hz)``.
    noverlap : int, optional
        Overlap (samples); default ``nperseg // 2``.
    window : str, tuple or numpy.ndarray
        As for :func:`scipy.signal.get_window`; default ``"hann"``.
    detrend : {'constant', 'linear', False} or callable
        Detrending of each window, as for :func:`scipy.signal.welch`.
    average : {'mean', 'median'}
        Average over windows (the median is corrected for its bias against the mean).
    axis : int
        Time axis of ``x`` (and of a full-shape ``valid``).

    Returns
    -------
    Spectrum
        ``psd_per_Hz`` float64 with the frequency axis at ``axis``; the Welch account (windows,
        segments used and dropped, degrees of freedom) per channel.

    Raises
    ------
    InsufficientDataError
        When no valid segment is as long as ``nperseg`` (the requested resolution).
    ConstantSignalError
        When every valid sample of a channel has the same value.

    Notes
    -----
    Within each valid segment of length L, :func:`scipy.signal.welch` averages
    :math:`k = \lfloor (L - n_o)/(N - n_o) \rfloor` windowed periodograms; the estimate is
    their mean over all segments weighted by k (or the median over all windows):

    .. math:: \hat S(f_k) = \frac{1}{K} \sum_{j=1}^{K} \frac{2 |\sum_n w_n x_{j,n}
              e^{-2\pi i k n / N}|^2}{f_s \sum_n w_n^2}.

    With the one-sided scaling, :math:`\sum_k \hat S(f_k) \Delta f` is the (window-weighted)
    mean square of the detrended signal (Parseval).

    References
    ----------
    .. [1] P. D. Welch, "The use of fast Fourier transform for the estimation of power
           spectra", IEEE Trans. Audio Electroacoust. 15(2), 70-73, 1967.
    .. [2] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
           Cambridge University Press, 1993, Eq. (292b) (equivalent degrees of freedom).

    Examples
    --------
    A sine of amplitude 2 m/s^2: its PSD peak integrates to A^2/2 = 2 (m/s^2)^2.

    >>> from rigtools.analysis.rms import rms_from_psd
    >>> fs = 25600.0
    >>> t = np.arange(int(4 * fs)) / fs
    >>> s = welch_psd(2.0 * np.sin(2 * np.pi * 1000.0 * t), fs, unit="m/s^2")
    >>> round(float(rms_from_psd(s, (990.0, 1010.0)) ** 2), 6)
    2.0
    """
    if average not in ("mean", "median"):
        raise SignalError("average", "'mean' or 'median'", repr(average))
    xs, fs, mask, nps, nov, w, det, props = prepare_welch(x, fs, valid, nperseg, resolution_Hz,
                                                     noverlap, window, detrend, axis)
    check_not_constant(xs, mask)
    freq, P, account, _ = welch_core(xs, mask, fs, w, nps, nov, det, average, "density",
                                      props)
    return Spectrum(freq_Hz=freq, unit=unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                    window=window, detrend=det, account=account,
                    psd_per_Hz=np.moveaxis(P, -1, axis), average=average,
                    freq_axis=norm_axis(axis, P.ndim))


def amplitude_spectrum(x: Any, fs: float, *, valid: Any = None, unit: str = "",
                       nperseg: int | None = None, resolution_Hz: float | None = None,
                       noverlap: int | None = None, window: Window = "flattop",
                       detrend: Detrend = "constant", axis: int = -1) -> AmplitudeSpectrum:
    r"""Peak-amplitude spectrum with window correction, split at gaps like :func:`welch_psd`.

    Parameters
    ----------
    x, fs, valid, unit, nperseg, resolution_Hz, noverlap, detrend, axis
        As for :func:`welch_psd`.
    window : str, tuple or numpy.ndarray
        Default ``"flattop"`` (scipy's, Harris 1978 / D'Antona and Ferrero 2006): scalloping
        loss 0.11 %, so a sine reads its amplitude within 0.11 % wherever it falls. ``"hann"``
        reads within 15.1 % (and on-bin exactly).

    Returns
    -------
    AmplitudeSpectrum
        ``amplitude`` (unit) and ``scalloping_tolerance``.

    Notes
    -----
    The power spectrum (``scaling="spectrum"``, :math:`|\sum w x e^{-i\omega n}|^2/(\sum w)^2`,
    doubled one-sided) is averaged over windows (RMS averaging) and
    :math:`A_k = \sqrt{2 P_k}` (:math:`\sqrt{P_0}` at 0 Hz and at the Nyquist bin).

    References
    ----------
    .. [1] F. J. Harris, "On the use of windows for harmonic analysis with the discrete
           Fourier transform", Proc. IEEE 66(1), 51-83, 1978.

    Examples
    --------
    >>> fs = 10000.0
    >>> t = np.arange(40000) / fs
    >>> a = amplitude_spectrum(3.0 * np.sin(2 * np.pi * 1234.5 * t), fs, nperseg=4096)
    >>> abs(float(a.amplitude.max()) / 3.0 - 1) < a.scalloping_tolerance
    True
    """
    xs, fs, mask, nps, nov, w, det, props = prepare_welch(x, fs, valid, nperseg, resolution_Hz,
                                                     noverlap, window, detrend, axis)
    freq, P, account, _ = welch_core(xs, mask, fs, w, nps, nov, det, "mean", "spectrum",
                                      props)
    amp = np.sqrt(2.0 * P)
    amp[..., 0] = np.sqrt(P[..., 0])
    if nps % 2 == 0:
        amp[..., -1] = np.sqrt(P[..., -1])
    return AmplitudeSpectrum(freq_Hz=freq, unit=unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                             window=window, detrend=det, account=account,
                             amplitude=np.moveaxis(amp, -1, axis))
