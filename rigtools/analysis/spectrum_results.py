"""Frozen result types of the spectral analyses.

:class:`WelchAccount` (how a Welch estimate was made over a gapped signal), :class:`Spectrum`
(PSD), :class:`AmplitudeSpectrum`, :class:`BandRMS` and :class:`Clipping`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.analysis.signal_checks import Window
from rigtools.analysis.spectral_window import WindowProperties, window_properties

__all__ = ["AmplitudeSpectrum", "BandRMS", "Clipping", "Spectrum", "WelchAccount"]

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
