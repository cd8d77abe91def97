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

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy import signal as sps
from scipy.special import polygamma

from rigtools.analysis.windows import Segments, n_windows, valid_segments
from rigtools.errors import RigtoolsError

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

#: Window length used when neither ``nperseg`` nor ``resolution_Hz`` is given (samples).
DEFAULT_NPERSEG = 4096

Window = str | tuple[Any, ...] | np.ndarray
Detrend = Literal["constant", "linear", False] | Callable[[np.ndarray], np.ndarray]
Average = Literal["mean", "median"]


# --------------------------------------------------------------------------------------------
# errors


class SignalError(RigtoolsError, ValueError):
    """A signal cannot be analysed as asked.

    Parameters
    ----------
    argument : str
        The argument (or array row, ``"x[2]"``) at fault.
    expected, found : str, optional
        What was expected and what was received; the message reads
        ``` `argument` must be <expected>, was <found>```.
    detail : str, optional
        Free text; alone it reads ``` `argument` <detail>```.
    channel : str, optional
        Channel name, prefixed to the message.
    """

    def __init__(self, argument: str, expected: str | None = None, found: str | None = None,
                 detail: str | None = None, channel: str | None = None) -> None:
        self.argument = argument
        self.expected = expected
        self.found = found
        self.detail = detail
        self.channel = channel
        super().__init__(str(self))

    def __str__(self) -> str:
        head = f"channel {self.channel!r}: " if self.channel is not None else ""
        if self.expected is not None:
            msg = f"`{self.argument}` must be {self.expected}, was {self.found}"
            if self.detail:
                msg += f" ({self.detail})"
        else:
            msg = f"`{self.argument}` {self.detail or 'cannot be analysed'}"
        return head + msg

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.argument, self.expected, self.found, self.detail,
                             self.channel))

    def for_channel(self, channel: str) -> SignalError:
        """The same error, naming ``channel``."""
        return type(self)(self.argument, self.expected, self.found, self.detail, channel)


class InsufficientDataError(SignalError):
    """The signal (or its longest valid segment) is too short for the requested resolution."""


class ConstantSignalError(SignalError):
    """Every valid sample has the same value: there is no spectrum to analyse."""


# --------------------------------------------------------------------------------------------
# window properties


@dataclass(frozen=True, eq=False)
class WindowProperties:
    r"""What a window does to a spectrum, in bins of ``fs / nperseg``.

    Attributes
    ----------
    nperseg : int
        Window length (samples).
    enbw_bins : float
        Equivalent noise bandwidth, :math:`N \sum w^2 / (\sum w)^2` (bins): 1.5 for Hann,
        3.77 for scipy's flattop.
    bandwidth_3dB_bins : float
        Full width of the spectral window :math:`|W(f)|^2` at half its peak (bins): the
        half-power bandwidth with which a pure tone appears (1.44 for Hann).
    scalloping_loss : float
        Worst-case amplitude reading of a sine halfway between two bins, as a fraction lost:
        :math:`1 - |W(1/2)| / |W(0)|` (0.151 for Hann, 0.0011 for flattop).
    amplitude_tolerance : float
        :math:`\max_{0 \le \delta \le 1/2} |1 - |W(\delta)| / |W(0)||`: the largest relative
        error of a sine's amplitude read at its nearest bin, wherever it falls (a flat top
        ripples slightly above 1 as well as below).
    mainlobe_half_width_bins : float
        Distance from the centre to the first null of :math:`|W|^2` (bins): 2 for Hann.
    bin_correlation : numpy.ndarray
        :math:`\rho_q^2`, q = 0, 1, ...: correlation of two PSD estimates q bins apart for a
        Gaussian signal, :math:`\rho_q = |\sum w_n^2 e^{-2\pi i q n/N}| / \sum w_n^2`
        (Hann: 1, 0.444, 0.028).
    kernel : numpy.ndarray
        The spectral window :math:`|W|^2` sampled at offsets ``kernel_offsets_bins``,
        normalised to sum 1: the expected Welch estimate is the true PSD convolved with it.
    kernel_offsets_bins : numpy.ndarray
        Offsets of ``kernel`` (bins), symmetric about 0 in steps of 1/8 bin.
    """

    nperseg: int
    enbw_bins: float
    bandwidth_3dB_bins: float
    scalloping_loss: float
    amplitude_tolerance: float
    mainlobe_half_width_bins: float
    bin_correlation: np.ndarray
    kernel: np.ndarray
    kernel_offsets_bins: np.ndarray
    _w: np.ndarray

    def overlap_correlation(self, noverlap: int) -> np.ndarray:
        r""":math:`\rho(mS)^2` for m = 1, 2, ... while windows S = nperseg - noverlap apart overlap.

        Percival and Walden (1993), Eq. (292b): correlation of two periodograms whose windows
        are shifted by m S samples.
        """
        w = self._w
        step = self.nperseg - noverlap
        out = []
        shift = step
        denom = float(np.dot(w, w))
        while shift < self.nperseg:
            out.append((float(np.dot(w[shift:], w[:-shift])) / denom) ** 2)
            shift += step
        return np.asarray(out)


_WINDOW_CACHE: dict[tuple[Any, int], WindowProperties] = {}
_KERNEL_OVERSAMPLING = 8


def _window_array(window: Window, nperseg: int) -> np.ndarray:
    if isinstance(window, np.ndarray):
        w = np.asarray(window, np.float64)
        if w.shape != (nperseg,):
            raise SignalError("window", f"of shape (nperseg,)=({nperseg},)", str(w.shape))
        return w
    try:
        return np.asarray(sps.get_window(window, nperseg), np.float64)
    except (ValueError, TypeError) as e:
        raise SignalError("window", "a window scipy.signal.get_window knows", repr(window),
                          str(e)) from e


def window_properties(window: Window, nperseg: int) -> WindowProperties:
    """Equivalent noise bandwidth, scalloping loss and spectral window of a window.

    Parameters
    ----------
    window : str, tuple or numpy.ndarray
        As for :func:`scipy.signal.get_window` (periodic form), or the samples themselves.
    nperseg : int
        Window length (samples).

    Returns
    -------
    WindowProperties

    References
    ----------
    .. [1] F. J. Harris, "On the use of windows for harmonic analysis with the discrete
           Fourier transform", Proc. IEEE 66(1), 51-83, 1978 (ENBW, scalloping loss).
    .. [2] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
           Cambridge University Press, 1993, Sec. 6.17 (correlation of spectral estimates).

    Examples
    --------
    >>> p = window_properties("hann", 4096)
    >>> round(p.enbw_bins, 3), round(p.scalloping_loss, 3)
    (1.5, 0.151)
    """
    key = (("array", window.tobytes()) if isinstance(window, np.ndarray) else repr(window),
           int(nperseg))
    props = _WINDOW_CACHE.get(key)
    if props is not None:
        return props
    w = _window_array(window, nperseg)
    n = nperseg
    s1, s2 = float(w.sum()), float(np.dot(w, w))
    if s1 == 0.0 or s2 == 0.0:
        raise SignalError("window", "non-zero", "all zeros")
    enbw = n * s2 / s1**2
    idx = np.arange(n)
    offsets_half = np.linspace(0.0, 0.5, 33)[:, None]  # sine between bins: 0 .. 1/2 bin off
    gain = np.abs(np.exp(-2j * np.pi * offsets_half * idx[None, :] / n) @ w) / abs(s1)
    half = float(gain[-1])
    amp_tol = float(np.max(np.abs(1.0 - gain)))
    ov = _KERNEL_OVERSAMPLING
    spec = np.abs(np.fft.fft(w, n * ov)) ** 2
    spec /= spec.sum()
    rel = spec / spec[0]
    # 3 dB width and first null on the fine grid (positive side)
    k = int(np.argmax(rel[: n * ov // 2] < 0.5))
    x0, x1 = (k - 1) / ov, k / ov
    y0, y1 = rel[k - 1], rel[k]
    bw3 = 2 * (x0 + (y0 - 0.5) / (y0 - y1) * (x1 - x0)) if k > 0 else 1.0 / ov
    d = np.diff(rel[: n * ov // 2])
    mins = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
    null = (mins[0] + 1) / ov if mins.size else n / 2
    # spectral window kernel: keep offsets until 1e-4 of the energy is left out, at most 16 bins
    centred = np.fft.fftshift(spec)
    c = n * ov // 2
    L = ov
    while L < 16 * ov and 1.0 - centred[c - L: c + L + 1].sum() > 1e-4:
        L += ov
    kern = centred[c - L: c + L + 1].copy()
    kern /= kern.sum()
    offsets = np.arange(-L, L + 1) / ov
    # correlation of PSD estimates q bins apart
    w2 = w * w
    rho = [1.0]
    q = 1
    while q < n // 2:
        r = abs(np.sum(w2 * np.exp(-2j * np.pi * q * idx / n))) / s2
        if r**2 < 1e-4:
            break
        rho.append(float(r**2))
        q += 1
    props = WindowProperties(
        nperseg=int(n), enbw_bins=float(enbw), bandwidth_3dB_bins=float(bw3),
        scalloping_loss=float(1.0 - half), amplitude_tolerance=amp_tol,
        mainlobe_half_width_bins=float(null),
        bin_correlation=np.asarray(rho), kernel=kern, kernel_offsets_bins=offsets, _w=w)
    if len(_WINDOW_CACHE) > 64:
        _WINDOW_CACHE.clear()
    _WINDOW_CACHE[key] = props
    return props


# --------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True, eq=False)
class WelchAccount:
    r"""How a Welch estimate was made from a (possibly gapped) signal, per channel.

    Every attribute is a numpy array with the batch shape of the input (``()`` for one
    channel; use ``int(...)`` / ``float(...)`` there).

    Attributes
    ----------
    n_windows : numpy.ndarray
        Windows averaged, K.
    dof : numpy.ndarray
        Equivalent degrees of freedom :math:`\nu` of each PSD value: :math:`2K` for
        non-overlapping windows, fewer with overlap (Percival and Walden 1993, Eq. 292b), so
        that :math:`\nu \hat S / S \sim \chi^2_\nu` approximately.
    n_segments : numpy.ndarray
        Valid segments used.
    n_segments_dropped : numpy.ndarray
        Valid segments shorter than one window, dropped.
    n_samples_dropped : numpy.ndarray
        Valid samples in the dropped segments.
    n_invalid : numpy.ndarray
        Samples with ``valid == False`` (gaps, rejected samples).
    n_samples_used : numpy.ndarray
        Samples in the segments used.
    """

    n_windows: np.ndarray
    dof: np.ndarray
    n_segments: np.ndarray
    n_segments_dropped: np.ndarray
    n_samples_dropped: np.ndarray
    n_invalid: np.ndarray
    n_samples_used: np.ndarray


@dataclass(frozen=True, eq=False, kw_only=True)
class _WelchBase:
    freq_Hz: np.ndarray
    unit: str
    fs_Hz: float
    nperseg: int
    noverlap: int
    window: Window
    detrend: Any
    account: WelchAccount

    @property
    def resolution_Hz(self) -> float:  # noqa: N802 (unit in the name)
        """Bin spacing ``fs / nperseg`` (Hz)."""
        return self.fs_Hz / self.nperseg

    @property
    def window_properties(self) -> WindowProperties:
        """ENBW, scalloping loss and spectral window of the window used."""
        return window_properties(self.window, self.nperseg)

    @property
    def enbw_Hz(self) -> float:  # noqa: N802 (unit in the name)
        """Equivalent noise bandwidth of one bin (Hz)."""
        return self.window_properties.enbw_bins * self.resolution_Hz

    @property
    def n_windows(self) -> np.ndarray:
        """Windows averaged (see :class:`WelchAccount`)."""
        return self.account.n_windows

    @property
    def dof(self) -> np.ndarray:
        """Equivalent degrees of freedom (see :class:`WelchAccount`)."""
        return self.account.dof


@dataclass(frozen=True, eq=False, kw_only=True)
class Spectrum(_WelchBase):
    r"""A one-sided power spectral density (Welch).

    Attributes
    ----------
    freq_Hz : numpy.ndarray
        Bin frequencies (Hz), shape ``(n_freq,)``, ``n_freq = nperseg // 2 + 1``.
    psd_per_Hz : numpy.ndarray
        PSD (``unit``^2/Hz), float64, shape ``(..., n_freq)`` (the frequency axis where the
        time axis was). One-sided: :math:`\sum_k S_k \Delta f` is the mean square.
    unit : str
        Unit of the signal; the PSD is in ``(unit)^2/Hz``.
    fs_Hz : float
        Sample rate (Hz).
    nperseg, noverlap : int
        Window length and overlap (samples).
    window : str, tuple or numpy.ndarray
        The window, as given.
    detrend : str, bool or callable
        Detrending of each window, as for :func:`scipy.signal.welch`.
    average : str
        ``"mean"`` or ``"median"`` (bias-corrected) over windows.
    account : WelchAccount
        Window and segment counts and degrees of freedom, per channel.
    """

    psd_per_Hz: np.ndarray
    average: str = "mean"
    #: Axis of ``psd_per_Hz`` holding frequency (the ``axis`` the time axis was on).
    freq_axis: int = -1

    @property
    def psd_unit(self) -> str:
        """Unit of ``psd_per_Hz``."""
        return f"({self.unit})^2/Hz" if self.unit else "1/Hz"


@dataclass(frozen=True, eq=False, kw_only=True)
class AmplitudeSpectrum(_WelchBase):
    r"""A window-corrected amplitude spectrum (RMS average of windowed periodograms).

    Attributes
    ----------
    freq_Hz : numpy.ndarray
        Bin frequencies (Hz).
    amplitude : numpy.ndarray
        Peak amplitude (``unit``), shape ``(..., n_freq)``: a sine :math:`A\sin(2\pi f t)` with
        f on a bin reads A there; off-bin it reads A within ``scalloping_tolerance``
        (relative). At 0 Hz it reads the mean (when not detrended).
    unit, fs_Hz, nperseg, noverlap, window, detrend, account
        As for :class:`Spectrum`.
    """

    amplitude: np.ndarray

    @property
    def scalloping_tolerance(self) -> float:
        """Largest relative error of a sine's amplitude read at its bin, wherever it falls."""
        return self.window_properties.amplitude_tolerance


@dataclass(frozen=True, eq=False)
class BandRMS:
    r"""Band-limited RMS, in the time domain and from the PSD.

    Attributes
    ----------
    band_Hz : tuple of float
        ``(f_lo, f_hi)`` (Hz), both included.
    rms_time : numpy.ndarray or float
        RMS of the signal filtered to the band (``unit``): each valid segment used for the PSD
        is detrended as the windows are, filtered by an ideal (FFT) band-pass and the mean
        square of the filtered samples taken over all those segments. Over the full band no
        filter is applied: plain mean square of the detrended samples.
    rms_parseval : numpy.ndarray or float
        :math:`\sqrt{\sum_{f_{lo} \le f_k \le f_{hi}} S_k \Delta f}` from the Welch PSD
        (``unit``).
    unit : str
    n_samples : numpy.ndarray or int
        Samples the time-domain value was computed from.
    """

    band_Hz: tuple[float, float]
    rms_time: Any
    rms_parseval: Any
    unit: str
    n_samples: Any

    @property
    def ratio(self) -> Any:
        """``rms_parseval / rms_time``: 1 for a stationary signal, to the estimator's scatter."""
        return np.asarray(self.rms_parseval) / np.asarray(self.rms_time)


@dataclass(frozen=True)
class Clipping:
    """Runs of samples stuck at the channel's extreme values.

    Attributes
    ----------
    clipped : bool
        At least one run of ``min_run`` or more identical samples at the channel's maximum or
        minimum (or any sample at or beyond ``full_scale``).
    n_clipped : int
        Samples in such runs.
    n_runs : int
        Number of such runs.
    longest_run : int
        Longest run at an extreme (samples), clipped or not.
    high, low : float
        Largest and smallest valid value (NaN when there is none).
    min_run : int
        Run length taken as clipping (samples).
    """

    clipped: bool
    n_clipped: int
    n_runs: int
    longest_run: int
    high: float
    low: float
    min_run: int


# --------------------------------------------------------------------------------------------
# validation helpers


def _as_signal(x: Any, axis: int) -> np.ndarray:
    """``x`` as float32/float64 with the time axis last."""
    a = np.asarray(x)
    if a.ndim == 0:
        raise SignalError("x", "an array with a time axis", "a scalar")
    if np.iscomplexobj(a):
        raise SignalError("x", "real", f"complex ({a.dtype})")
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    try:
        return np.moveaxis(a, axis, -1)
    except np.exceptions.AxisError as e:
        raise SignalError("axis", f"in [-{a.ndim}, {a.ndim})", str(axis)) from e


def _check_fs(fs: float) -> float:
    fs = float(fs)
    if not np.isfinite(fs) or fs <= 0:
        raise SignalError("fs", "a finite positive sample rate (Hz)", repr(fs))
    return fs


def _check_valid(valid: Any, x: np.ndarray, axis: int) -> np.ndarray | None:
    """The mask, time axis last, shape ``(n,)`` or ``x.shape``; None when every sample is valid.

    Without a mask, the finite samples are the valid ones. With one, samples marked valid must
    be finite.
    """
    n = x.shape[-1]
    if valid is None:
        if np.isfinite(np.sum(x, dtype=np.float64)):
            return None
        v = np.isfinite(x)
        return None if v.all() else v
    v = np.asarray(valid)
    if v.dtype != np.bool_:
        raise SignalError("valid", "a boolean mask", f"dtype {v.dtype}")
    if v.ndim > 1 or v.shape == x.shape:
        v = np.moveaxis(v, axis, -1) if v.ndim > 1 else v
    if v.shape not in ((n,), x.shape):
        raise SignalError("valid", f"of shape ({n},) or {x.shape} (time axis last)",
                          str(v.shape))
    if v.all():
        if not np.isfinite(np.sum(x, dtype=np.float64)) and not np.isfinite(x).all():
            raise SignalError("x", "finite where `valid` is True", "NaN or inf there")
        return None
    if not np.isfinite(np.sum(np.where(v, x, 0.0), dtype=np.float64)) and not np.isfinite(
            np.where(v, x, 0.0)).all():
        raise SignalError("x", "finite where `valid` is True", "NaN or inf there")
    return v


def _resolve_nperseg(nperseg: int | None, resolution_Hz: float | None, fs: float) -> int:
    if nperseg is not None and resolution_Hz is not None:
        raise SignalError("resolution_Hz", "None when `nperseg` is given", repr(resolution_Hz))
    if resolution_Hz is not None:
        r = float(resolution_Hz)
        if not np.isfinite(r) or r <= 0 or r > fs / 2:
            raise SignalError("resolution_Hz", f"in (0, fs/2={fs / 2:g}] Hz", repr(resolution_Hz))
        return int(np.ceil(fs / r - 1e-9))
    if nperseg is None:
        return DEFAULT_NPERSEG
    if int(nperseg) != nperseg or nperseg < 2:
        raise SignalError("nperseg", "an integer >= 2", repr(nperseg))
    return int(nperseg)


def _check_noverlap(noverlap: int | None, nperseg: int) -> int:
    if noverlap is None:
        return nperseg // 2
    if int(noverlap) != noverlap or not 0 <= noverlap < nperseg:
        raise SignalError("noverlap", f"an integer in [0, nperseg={nperseg})", repr(noverlap))
    return int(noverlap)


def _check_detrend(detrend: Any) -> Any:
    if detrend is False or callable(detrend) or detrend in ("constant", "linear"):
        return detrend
    raise SignalError("detrend", "'constant', 'linear', False or a callable", repr(detrend))


def _check_band(band_Hz: Sequence[float] | None, fs: float) -> tuple[float, float]:
    if band_Hz is None:
        return (0.0, fs / 2)
    try:
        lo, hi = (float(b) for b in band_Hz)
    except (TypeError, ValueError) as e:
        raise SignalError("band_Hz", "a pair (f_lo, f_hi) in Hz", repr(band_Hz)) from e
    if not (0.0 <= lo < hi) or np.isnan(hi):
        raise SignalError("band_Hz", "0 <= f_lo < f_hi (Hz)", repr(band_Hz))
    return (lo, min(hi, fs / 2))


def _row_name(i: tuple[Any, ...], batch: tuple[int, ...]) -> str:
    return "x" if not batch else "x[" + ", ".join(str(j) for j in i) + "]"


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


def _welch_core(x: np.ndarray, mask: np.ndarray | None, fs: float, w: np.ndarray,
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
            names = ", ".join(_row_name(np.unravel_index(int(r), batch), batch)
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


def _check_not_constant(x: np.ndarray, mask: np.ndarray | None) -> None:
    batch = x.shape[:-1]
    x2 = x.reshape(-1, x.shape[-1])
    if mask is None:
        hi, lo = x2.max(axis=-1), x2.min(axis=-1)
    else:
        m2 = np.broadcast_to(mask, x.shape).reshape(x2.shape)
        hi = np.where(m2, x2, -np.inf).max(axis=-1)
        lo = np.where(m2, x2, np.inf).min(axis=-1)
    for i in np.flatnonzero(hi == lo):
        idx = np.unravel_index(int(i), batch)
        nv = int(x2.shape[-1] if mask is None else np.count_nonzero(
            np.broadcast_to(mask, x.shape).reshape(x2.shape)[i]))
        raise ConstantSignalError(
            _row_name(idx, batch), detail=f"is constant (all {nv} valid samples equal "
            f"{float(hi[i])!r}): its spectrum is zero, no peak or damping can be estimated")


def _prepare(x: Any, fs: float, valid: Any, nperseg: int | None, resolution_Hz: float | None,
             noverlap: int | None, window: Window, detrend: Any, axis: int
             ) -> tuple[np.ndarray, float, np.ndarray | None, int, int, np.ndarray, Any,
                        WindowProperties]:
    xs = _as_signal(x, axis)
    fs = _check_fs(fs)
    nps = _resolve_nperseg(nperseg, resolution_Hz, fs)
    if nps > xs.shape[-1]:
        raise InsufficientDataError(
            "nperseg", f"<= len(x)={xs.shape[-1]}", str(nps),
            f"resolution {fs / nps:g} Hz needs {nps / fs:g} s of signal, "
            f"there are {xs.shape[-1] / fs:g} s")
    nov = _check_noverlap(noverlap, nps)
    det = _check_detrend(detrend)
    mask = _check_valid(valid, xs, axis)
    w = _window_array(window, nps)
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

    >>> fs = 25600.0
    >>> t = np.arange(int(4 * fs)) / fs
    >>> s = welch_psd(2.0 * np.sin(2 * np.pi * 1000.0 * t), fs, unit="m/s^2")
    >>> round(float(rms_from_psd(s, (990.0, 1010.0)) ** 2), 6)
    2.0
    """
    if average not in ("mean", "median"):
        raise SignalError("average", "'mean' or 'median'", repr(average))
    xs, fs, mask, nps, nov, w, det, props = _prepare(x, fs, valid, nperseg, resolution_Hz,
                                                     noverlap, window, detrend, axis)
    _check_not_constant(xs, mask)
    freq, P, account, _ = _welch_core(xs, mask, fs, w, nps, nov, det, average, "density",
                                      props)
    return Spectrum(freq_Hz=freq, unit=unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                    window=window, detrend=det, account=account,
                    psd_per_Hz=np.moveaxis(P, -1, axis), average=average,
                    freq_axis=_norm_axis(axis, P.ndim))


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
    xs, fs, mask, nps, nov, w, det, props = _prepare(x, fs, valid, nperseg, resolution_Hz,
                                                     noverlap, window, detrend, axis)
    freq, P, account, _ = _welch_core(xs, mask, fs, w, nps, nov, det, "mean", "spectrum",
                                      props)
    amp = np.sqrt(2.0 * P)
    amp[..., 0] = np.sqrt(P[..., 0])
    if nps % 2 == 0:
        amp[..., -1] = np.sqrt(P[..., -1])
    return AmplitudeSpectrum(freq_Hz=freq, unit=unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                             window=window, detrend=det, account=account,
                             amplitude=np.moveaxis(amp, -1, axis))


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
    lo, hi = _check_band(band_Hz, spectrum.fs_Hz)
    f = spectrum.freq_Hz
    sel = (f >= lo) & (f <= hi)
    psd = np.asarray(spectrum.psd_per_Hz)
    if psd.ndim > 1:  # frequency on the axis the time axis was on
        psd = np.moveaxis(psd, _norm_axis(getattr(spectrum, "freq_axis", -1), psd.ndim), -1)
    ms = np.sum(psd[..., sel], axis=-1) * spectrum.resolution_Hz
    return np.sqrt(ms)[()]


def _norm_axis(axis: int, ndim: int) -> int:
    """``axis`` in [0, ndim) (-1 when ndim is 0)."""
    return int(axis) % ndim if ndim else -1


def _detrended(seg: np.ndarray, detrend: Any) -> np.ndarray:
    seg = np.asarray(seg, np.float64)
    if detrend == "constant":
        return seg - seg.mean(axis=-1, keepdims=True)
    if detrend == "linear":
        return sps.detrend(seg, axis=-1, type="linear")
    if detrend is False:
        return seg
    return np.asarray(detrend(seg), np.float64)


def _mean_square_time(x: np.ndarray, segs: Segments, rows: np.ndarray, fs: float,
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
    xs, fs, mask, nps, nov, _, det, _ = _prepare(x, fs, valid, nperseg, resolution_Hz,
                                                 noverlap, window, detrend, axis)
    band = _check_band(band_Hz, fs)
    if spectrum is None:
        _check_not_constant(xs, mask)
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
        tot, cnt = _mean_square_time(x2, segs, np.arange(m), fs, band, det)
        ms[:], counts[:] = tot / max(cnt, 1), cnt
    else:
        m2 = mask.reshape(-1, n)
        for i in range(m):
            segs = valid_segments(m2[i], nps)
            tot, cnt = _mean_square_time(x2, segs, np.array([i]), fs, band, det)
            ms[i], counts[i] = tot[0] / max(cnt, 1), cnt
    rms_p = rms_from_psd(spectrum, band)
    return BandRMS(band_Hz=band, rms_time=np.sqrt(ms).reshape(batch)[()],
                   rms_parseval=np.asarray(rms_p).reshape(batch)[()], unit=unit,
                   n_samples=counts.reshape(batch)[()])


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
