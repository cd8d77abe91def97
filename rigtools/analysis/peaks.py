r"""Natural frequencies with damping from a PSD, told apart from mesh harmonics and sidebands.

For each peak of a Welch PSD (:class:`~rigtools.analysis.spectra.Spectrum`):

1. **Detection** by prominence on the log PSD (:func:`scipy.signal.find_peaks`): a peak must
   stand ``prominence_dB`` above its surroundings, and at least ``min_sigma`` standard
   deviations of the estimator's own log scatter; and it must be *significant* against
   the look-elsewhere effect: above the local background (a wide running median) by the
   chi-square quantile of the Welch estimate (:math:`\nu` equivalent dof) that pure noise
   exceeds with probability ``false_alarm`` (1 %) anywhere in the searched band (Sidak over
   its bins), or, for a broad feature that lifts the median, more prominent than the
   spread between the upper and lower such quantiles.
2. **Frequency** finer than a bin: Gaussian interpolation (a parabola through the log PSD of
   the three bins around the maximum).
3. **Location class**: a peak within tolerance of :math:`k f_\text{mesh}`,
   :math:`k f_\text{mesh} \pm j f_\text{shaft}` or :math:`k f_\text{shaft}` is a mesh
   harmonic, a mesh sideband or a shaft harmonic (in that order of precedence).
4. **Damping**, two ways, each with a standard uncertainty:

   * half-power bandwidth, :math:`\zeta = (f_2 - f_1) / (2 f_\text{peak})` where the PSD has
     fallen to half its peak, with the uncertainty propagated from the chi-square scatter
     of the Welch estimates (:math:`\nu` equivalent degrees of freedom,
     :math:`\mathrm{Var}\ln\hat S = \psi'(\nu/2)`) through the local slopes;
   * a single-DOF fit: :math:`|H|^2` of a SDOF plus a white background, convolved with the
     window's spectral window (the expected value of a Welch estimate), fitted to the log PSD
     around the peak by :func:`scipy.optimize.least_squares`; covariance from the Jacobian,
     :math:`(J^TJ)^{-1} J^T \Sigma J (J^TJ)^{-1}` with :math:`\Sigma = \psi'(\nu/2) R`,
     R the correlation of neighbouring Welch bins (sandwich form), scaled up by the reduced
     chi-square when the model fits worse than the estimator's scatter.

   The fit starts from the half-power damping of the raw PSD and of the PSD smoothed over
   3, 7 and 15 bins (the best fit is kept), over a band of at least
   ``max(MIN_FIT_HALF_BINS, MIN_FIT_HALF_RES x B_3dB)`` bins each side, so that a noise
   spike on a short record cannot shrink it to a few bins; the covariance is further
   inflated when the band covers fewer than 3 half-power half-widths or few bins.

5. **Kind**: ``"structural"`` for a peak not at those frequencies whose fitted damping is
   wider than the spectral resolution can show beyond doubt (:math:`\zeta - 2\sigma_\zeta >
   \zeta_\text{res} = B_\text{3dB} / (2 f)`, with :math:`B_\text{3dB}` the window's
   half-power bandwidth: a pure tone appears that wide, and at least ``MIN_RESOLVED_BINS``
   bins across :math:`2\zeta f_n`), ``"tonal"`` for a narrow peak at none of them (fitted
   damping at or below that, or, when too few bins are free to fit, half-power damping
   below it), ``"unresolved"`` when the fit fails or its damping cannot be told apart from
   the resolution limit. Estimates from a PSD with fewer than ``LOW_DOF`` equivalent dof
   are flagged ``ModalEstimate.low_dof``. A broad peak within tolerance of a sideband or shaft
   line (lines as narrow as a tone) is ``"structural"``; one on a mesh harmonic stays
   ``"mesh_harmonic"`` with ``possible_resonance`` set.

:func:`analyse_recording` runs spectra, RMS, quality checks and peaks over the channels of a
:class:`~rigtools.ingest.recording.Recording` and returns one :class:`ChannelAnalysis` each.

References
----------
.. [1] J. S. Bendat and A. G. Piersol, *Random Data: Analysis and Measurement Procedures*,
       4th ed., Wiley, 2010, Sec. 8.5 (bias and random errors of PSD estimates).
.. [2] D. J. Ewins, *Modal Testing: Theory, Practice and Application*, 2nd ed., Research
       Studies Press, 2000, Sec. 4.3 (half-power point method).
.. [3] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
       Cambridge University Press, 1993, Sec. 6.17.
.. [4] M. Gasior and J. L. Gonzalez, "Improving FFT frequency measurement resolution by
       parabolic and Gaussian spectrum interpolation", AIP Conf. Proc. 732, 276-285, 2004.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from scipy import signal as sps
from scipy.ndimage import median_filter
from scipy.optimize import least_squares
from scipy.stats import chi2

from rigtools.analysis.spectra import (
    Average,
    BandRMS,
    Clipping,
    ConstantSignalError,
    Detrend,
    InsufficientDataError,
    SignalError,
    Spectrum,
    WelchAccount,
    Window,
    _check_band,
    _check_detrend,
    _check_fs,
    _check_noverlap,
    _mean_square_time,
    _resolve_nperseg,
    _welch_core,
    _window_array,
    detect_clipping,
    log_chi2_stats,
    rms_from_psd,
    window_properties,
)

__all__ = [
    "ChannelAnalysis",
    "HalfPower",
    "LocationClass",
    "ModalEstimate",
    "Peak",
    "PeakAnalysis",
    "QualityFlags",
    "RecordingAnalysis",
    "SDOFFit",
    "analyse_peaks",
    "analyse_recording",
    "classify_frequency",
    "fit_sdof",
    "half_power_damping",
    "natural_frequencies",
]

PeakKind = Literal["structural", "mesh_harmonic", "mesh_sideband", "shaft_harmonic", "tonal",
                   "unresolved"]
Response = Literal["displacement", "velocity", "acceleration"]
_RESPONSE_POWER = {"displacement": 0, "velocity": 1, "acceleration": 2}
#: The half-power crossings are found on the PSD averaged over (half-power bandwidth / this)
#: bins: enough to tame the chi-square scatter that biases the raw maximum high and the
#: crossings inward, little enough to widen a SDOF peak by under 1 %.
HALF_POWER_SMOOTHING = 8.0
#: Lower bound of the fitted damping, as a fraction of the resolution equivalent.
ZETA_MIN_FRACTION = 0.2
#: Mesh and shaft lines are fitted only when their half-power damping exceeds this multiple of
#: the resolution equivalent (a resonance may coincide with them).
LINE_FIT_FACTOR = 2.0
MAX_FIT_EVALUATIONS = 100
#: Default false-alarm probability per spectrum of the detection threshold (a noise bin
#: anywhere in the searched band exceeding it).
FALSE_ALARM = 0.01
#: A structural peak's fitted damping must exceed the resolution equivalent by this many of
#: its standard uncertainties.
ZETA_MARGIN_SIGMA = 2.0
#: ... and its half-power band (2 zeta f_n) must span at least this many bins.
MIN_RESOLVED_BINS = 4.0
#: Least half-width of the fitted band: bins, and multiples of the window's 3 dB bandwidth.
MIN_FIT_HALF_BINS = 16
MIN_FIT_HALF_RES = 8.0
#: Below this many equivalent degrees of freedom a modal estimate is flagged ``low_dof``.
LOW_DOF = 35.0


# --------------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class HalfPower:
    r"""Half-power bandwidth damping.

    Attributes
    ----------
    zeta : float
        :math:`(f_2 - f_1) / (2 f_\text{peak})` (NaN when a crossing is not found).
    zeta_std : float
        Standard uncertainty of ``zeta`` from the Welch chi-square scatter (see module notes).
    f_lo_Hz, f_hi_Hz : float
        Half-power frequencies (Hz), interpolated log-linearly between bins.
    smoothing_bins : int
        Width of the moving average the crossings were found on (bins, 1: none).
    message : str
        Empty, or why the estimate is missing.
    """

    zeta: float
    zeta_std: float
    f_lo_Hz: float
    f_hi_Hz: float
    smoothing_bins: int = 1
    message: str = ""


@dataclass(frozen=True)
class SDOFFit:
    r"""A single-DOF response fitted to the PSD around a peak.

    Model, with :math:`r = f/f_n` and p = 0, 1, 2 for displacement, velocity, acceleration:

    .. math:: E[\hat S(f_k)] = \sum_m K_m\, S_0 \frac{(2\zeta)^2 r_m^{2p}}
              {(1 - r_m^2)^2 + (2\zeta r_m)^2} + B, \qquad r_m = (f_k - m\delta)/f_n,

    :math:`K_m` the window's spectral window (:attr:`WindowProperties.kernel`).

    Attributes
    ----------
    f_n_Hz, f_n_std_Hz : float
        Natural frequency (Hz) and its standard uncertainty (Hz).
    zeta, zeta_std : float
        Damping ratio and its standard uncertainty.
    peak_psd_per_Hz : float
        :math:`S_0`, the SDOF PSD at :math:`f_n` (unit^2/Hz), free of window smoothing
        (fitted as :math:`\ln W`, :math:`W = \pi \zeta f_n S_0` the mean square under
        the peak, which stays well conditioned down to a tone).
    background_per_Hz : float
        B (unit^2/Hz).
    band_Hz : tuple of float
        Frequencies fitted (Hz).
    n_bins : int
        Bins fitted (masked bins of nearby mesh lines excluded).
    redchi2 : float
        Residual variance over the estimator's log variance :math:`\psi'(\nu/2)` (about 1
        when the model fits to the scatter; the covariance is scaled up by it when > 1).
    success : bool
    at_lower_bound : bool
        ``zeta`` hit its lower bound (a fifth of the resolution equivalent): narrower than
        the resolution can show, a tone.
    message : str
    """

    f_n_Hz: float
    f_n_std_Hz: float
    zeta: float
    zeta_std: float
    peak_psd_per_Hz: float
    background_per_Hz: float
    band_Hz: tuple[float, float]
    n_bins: int
    redchi2: float
    success: bool
    at_lower_bound: bool
    message: str = ""


@dataclass(frozen=True)
class ModalEstimate:
    r"""Natural frequency and damping of one PSD peak, two ways, with uncertainties.

    Attributes
    ----------
    f_n_Hz, f_n_std_Hz : float
        Natural frequency from the SDOF fit (Hz) and its standard uncertainty.
    zeta, zeta_std : float
        Damping ratio from the SDOF fit and its standard uncertainty.
    zeta_half_power, zeta_half_power_std : float
        Damping ratio by the half-power bandwidth and its standard uncertainty.
    f_peak_Hz, f_peak_std_Hz : float
        Interpolated peak frequency (Hz, Gaussian interpolation) and its standard uncertainty.
    psd_peak_per_Hz : float
        Interpolated PSD at the peak (unit^2/Hz).
    zeta_resolution : float
        :math:`B_\text{3dB}/(2 f_\text{peak})`: the damping a pure tone appears to have.
    fit : SDOFFit
    half_power : HalfPower
    response : str
        SDOF response fitted: ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    dof : float
        Equivalent degrees of freedom of the PSD (``low_dof`` below ``LOW_DOF``).
    resolution_Hz : float
        Bin spacing of the PSD (Hz).
    """

    f_n_Hz: float
    f_n_std_Hz: float
    zeta: float
    zeta_std: float
    zeta_half_power: float
    zeta_half_power_std: float
    f_peak_Hz: float
    f_peak_std_Hz: float
    psd_peak_per_Hz: float
    zeta_resolution: float
    fit: SDOFFit
    half_power: HalfPower
    response: str = "displacement"

    #: Equivalent degrees of freedom of the PSD the estimate comes from.
    dof: float = float("nan")
    #: Bin spacing of the PSD (Hz).
    resolution_Hz: float = float("nan")

    @property
    def broad(self) -> bool:
        r"""Fit succeeded and its damping exceeds the resolution equivalent beyond doubt.

        :math:`\zeta - 2\sigma_\zeta > \zeta_\text{res}` (``ZETA_MARGIN_SIGMA``) and the
        half-power band :math:`2\zeta f_n` spans at least ``MIN_RESOLVED_BINS`` bins: a
        noise spike fitted with a damping just above the resolution limit is not broad.
        """
        f = self.fit
        if not (f.success and not f.at_lower_bound and np.isfinite(self.zeta)
                and np.isfinite(self.zeta_std)):
            return False
        return bool(self.zeta - ZETA_MARGIN_SIGMA * self.zeta_std > self.zeta_resolution
                    and self.resolved_bins >= MIN_RESOLVED_BINS)

    @property
    def resolved_bins(self) -> float:
        r"""Bins across the fitted half-power band, :math:`2\zeta f_n / \Delta f`."""
        if not (np.isfinite(self.zeta) and self.resolution_Hz > 0):
            return 0.0
        return float(2 * self.zeta * self.f_n_Hz / self.resolution_Hz)

    @property
    def low_dof(self) -> bool:
        """The PSD has few averages (dof < ``LOW_DOF``): damping less reliable."""
        return bool(self.dof < LOW_DOF)


@dataclass(frozen=True)
class LocationClass:
    """Where a frequency sits relative to the mesh and shaft frequencies.

    Attributes
    ----------
    kind : str or None
        ``"mesh_harmonic"``, ``"mesh_sideband"``, ``"shaft_harmonic"``, or None.
    harmonic : int or None
        k, the mesh (or shaft) harmonic order.
    sideband : int or None
        j, signed sideband order (``-1`` is the lower first sideband).
    shaft_Hz : float or None
        The shaft frequency of the sideband or shaft harmonic (Hz).
    expected_Hz : float or None
        The frequency matched (Hz).
    """

    kind: str | None = None
    harmonic: int | None = None
    sideband: int | None = None
    shaft_Hz: float | None = None
    expected_Hz: float | None = None


@dataclass(frozen=True)
class Peak:
    """One PSD peak, its location class and (unless it is a mesh or shaft line) its mode.

    Attributes
    ----------
    index : int
        Bin of the maximum.
    f_Hz, f_std_Hz : float
        Interpolated frequency (Hz) and standard uncertainty.
    psd_per_Hz : float
        Interpolated PSD at the peak (unit^2/Hz).
    prominence_dB : float
        Prominence on the log PSD (dB).
    kind : str
        ``"structural"``, ``"mesh_harmonic"``, ``"mesh_sideband"``, ``"shaft_harmonic"``,
        ``"tonal"`` or ``"unresolved"``.
    location : LocationClass
    mode : ModalEstimate or None
        Damping estimates (also for mesh and shaft lines, to tell a resonance that coincides
        with one: ``mode.broad``).
    """

    index: int
    f_Hz: float
    f_std_Hz: float
    psd_per_Hz: float
    prominence_dB: float
    kind: str
    location: LocationClass
    mode: ModalEstimate | None

    @property
    def possible_resonance(self) -> bool:
        """A mesh or shaft line that is broad: a resonance may coincide with it."""
        return bool(self.location.kind is not None and self.mode is not None
                    and self.mode.broad)


@dataclass(frozen=True)
class PeakAnalysis:
    """The peaks of one PSD.

    Attributes
    ----------
    peaks : tuple of Peak
        In order of frequency.
    mesh_frequency_Hz : float or None
    shaft_frequencies_Hz : tuple of float
    tolerance_Hz : float
        Absolute part of the matching tolerance (Hz); the tolerance at f is
        ``tolerance_Hz + rtol * f``.
    rtol : float
    threshold_dB : float
        Prominence threshold used (dB).
    detection_threshold_dB : float
        Least height of a peak above the local background (running median, dB): the
        chi-square quantile of the Welch estimate with the equivalent dof, Sidak-corrected
        for the bins searched so that pure noise gives a peak with probability
        ``false_alarm`` per spectrum. A peak below it is still kept when its prominence
        exceeds the spread between the upper and lower such quantiles (a broad feature that
        lifts the running median).
    false_alarm : float
    """

    peaks: tuple[Peak, ...]
    mesh_frequency_Hz: float | None
    shaft_frequencies_Hz: tuple[float, ...]
    tolerance_Hz: float
    rtol: float
    threshold_dB: float
    detection_threshold_dB: float = 0.0
    false_alarm: float = FALSE_ALARM

    @property
    def structural(self) -> tuple[Peak, ...]:
        """Peaks classified as structural resonances."""
        return tuple(p for p in self.peaks if p.kind == "structural")

    @property
    def modes(self) -> tuple[ModalEstimate, ...]:
        """Modal estimates of the structural peaks."""
        return tuple(p.mode for p in self.structural if p.mode is not None)

    def of_kind(self, kind: str) -> tuple[Peak, ...]:
        """Peaks of one kind."""
        return tuple(p for p in self.peaks if p.kind == kind)


# --------------------------------------------------------------------------------------------
# location classes


def classify_frequency(f_Hz: float, *, mesh_frequency_Hz: float | None,
                       shaft_frequencies_Hz: Sequence[float] = (), tolerance_Hz: float = 0.0,
                       rtol: float = 0.002, max_sideband: int = 3,
                       max_shaft_harmonic: int = 10) -> LocationClass:
    r"""Match a frequency to mesh harmonics, their sidebands and shaft harmonics.

    Parameters
    ----------
    f_Hz : float
        Frequency (Hz).
    mesh_frequency_Hz : float or None
        Mesh frequency :math:`f_m = z_1 n_1 / 60` (Hz).
    shaft_frequencies_Hz : sequence of float
        Shaft rotation frequencies (Hz), e.g. pinion and wheel.
    tolerance_Hz, rtol : float
        Matching tolerance at f: ``tolerance_Hz + rtol * f`` (Hz).
    max_sideband : int
        Largest sideband order j.
    max_shaft_harmonic : int
        Largest shaft harmonic order.

    Returns
    -------
    LocationClass
        The first match in the order mesh harmonic (any k >= 1), mesh sideband
        (:math:`k f_m \pm j f_s`, k >= 1, 1 <= j <= max_sideband), shaft harmonic
        (:math:`k f_s`, 1 <= k <= max_shaft_harmonic); the nearest within a class.

    Examples
    --------
    >>> classify_frequency(1225.0, mesh_frequency_Hz=400.0, shaft_frequencies_Hz=[25.0],
    ...                    tolerance_Hz=2.0).sideband
    1
    """
    f = float(f_Hz)
    tol = float(tolerance_Hz) + float(rtol) * abs(f)
    shafts = [float(s) for s in shaft_frequencies_Hz if s is not None and s > 0]
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        fm = float(mesh_frequency_Hz)
        k = round(f / fm)
        if k >= 1 and abs(f - k * fm) <= tol:
            return LocationClass("mesh_harmonic", k, None, None, k * fm)
        best: tuple[float, LocationClass] | None = None
        for fs_ in shafts:
            for j in range(1, max_sideband + 1):
                for sign in (-1, 1):
                    kk = round((f - sign * j * fs_) / fm)
                    if kk < 1:
                        continue
                    expected = kk * fm + sign * j * fs_
                    d = abs(f - expected)
                    if d <= tol and (best is None or d < best[0]):
                        best = (d, LocationClass("mesh_sideband", kk, sign * j, fs_, expected))
        if best is not None:
            return best[1]
    best = None
    for fs_ in shafts:
        k = round(f / fs_)
        if 1 <= k <= max_shaft_harmonic:
            d = abs(f - k * fs_)
            if d <= tol and (best is None or d < best[0]):
                best = (d, LocationClass("shaft_harmonic", k, None, fs_, k * fs_))
    return best[1] if best is not None else LocationClass()


# --------------------------------------------------------------------------------------------
# peak estimators


class _PSDContext:
    """The log PSD of one channel and the statistics of its estimate."""

    def __init__(self, spectrum: Spectrum) -> None:
        psd = np.asarray(spectrum.psd_per_Hz, np.float64)
        if psd.ndim != 1:
            raise SignalError("spectrum", "one channel (psd_per_Hz of shape (n_freq,))",
                              f"shape {psd.shape}")
        if not np.any(psd > 0):
            raise SignalError("spectrum", "a PSD with positive values", "all zero")
        self.spectrum = spectrum
        self.f = spectrum.freq_Hz
        self.df = spectrum.resolution_Hz
        tiny = np.max(psd) * 1e-30
        self.psd = np.maximum(psd, tiny)
        self.lnP = np.log(self.psd)
        self.props = spectrum.window_properties
        self.dof = float(np.asarray(spectrum.dof))
        self.bias, self.eps2 = log_chi2_stats(max(self.dof, 1.0))
        self.rho2 = self.props.bin_correlation

    def rho(self, lag: int) -> float:
        """Correlation of the PSD estimates ``lag`` bins apart."""
        lag = abs(int(lag))
        return float(self.rho2[lag]) if lag < self.rho2.size else 0.0

    def smoothing_stats(self, m: int) -> tuple[float, float]:
        """Log variance of an m-bin moving average and correlation of neighbouring averages."""
        if m <= 1:
            return self.eps2, self.rho(1)
        i = np.arange(m)
        lag = np.abs(i[:, None] - i[None, :])
        same = sum(self.rho(q) for q in lag.ravel())
        shifted = sum(self.rho(q) for q in np.abs(lag + 1).ravel())
        nu = self.dof * m * m / same
        return log_chi2_stats(max(nu, 1.0))[1], min(shifted / same, 1.0)

    def interpolate(self, k: int, lnP: np.ndarray | None = None, eps2: float | None = None,
                    rho1: float | None = None) -> tuple[float, float, float]:
        """Gaussian interpolation at bin k: frequency, its std (Hz), ln PSD at the vertex."""
        lnP = self.lnP if lnP is None else lnP
        eps2 = self.eps2 if eps2 is None else eps2
        r1 = self.rho(1) if rho1 is None else rho1
        r2 = self.rho(2) if rho1 is None else rho1 * rho1
        f, df = self.f, self.df
        if k <= 0 or k >= lnP.size - 1:
            return float(f[k]), df / np.sqrt(12.0), float(lnP[k])
        a, b, c = lnP[k - 1], lnP[k], lnP[k + 1]
        if not (np.isfinite(a) and np.isfinite(b) and np.isfinite(c)):
            return float(f[k]), df / np.sqrt(12.0), float(b)
        den = a - 2 * b + c
        if not den < 0:
            return float(f[k]), df / np.sqrt(12.0), float(b)
        delta = float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))
        peak = b - 0.25 * (a - c) * delta
        # delta method: gradient of delta wrt (a, b, c), correlated log bins
        g = np.array([(0.5 - delta) / den, 2 * delta / den, (-0.5 - delta) / den])
        C = np.array([[1, r1, r2], [r1, 1, r1], [r2, r1, 1]]) * eps2
        std = float(np.sqrt(max(g @ C @ g, 0.0))) * df
        return float(f[k] + delta * df), min(std, df), float(peak)


def _smoothed_log(ctx: _PSDContext, mask: np.ndarray, m: int) -> np.ndarray:
    """Natural log of the m-bin moving average of the PSD over unmasked bins (NaN where none)."""
    if m <= 1:
        return np.where(mask, np.nan, ctx.lnP)
    w = (~mask).astype(np.float64)
    box = np.ones(m)
    num = np.convolve(ctx.psd * w, box, mode="same")
    den = np.convolve(w, box, mode="same")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.log(num / den)
    out[mask | (den < 0.5 * m)] = np.nan
    return out


def _half_power_pass(ctx: _PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray, m: int
                     ) -> HalfPower:
    f = ctx.f
    L = _smoothed_log(ctx, mask, m)
    eps2, rho1 = ctx.smoothing_stats(m)
    if m > 1:  # the smoothed maximum near the raw one
        a, b = max(lo, k0 - m), min(hi, k0 + m)
        seg = L[a: b + 1]
        if np.all(np.isnan(seg)):
            return _hp_missing("the peak is masked")
        k0 = a + int(np.nanargmax(seg))
    f_pk, _, ln_pk = ctx.interpolate(k0, np.nan_to_num(L, nan=-np.inf), eps2, rho1)
    thr = ln_pk - np.log(2.0)
    out = []
    for step, limit in ((-1, lo), (1, hi)):
        a = k0
        i = k0 + step
        found = None
        while (i >= limit) if step < 0 else (i <= limit):
            if np.isnan(L[i]):
                i += step
                continue
            if L[i] < thr:
                found = (a, i)
                break
            a = i
            i += step
        if found is None:
            return _hp_missing("the PSD does not fall to half its peak on the "
                               + ("low" if step < 0 else "high")
                               + " side before the next peak or the end of the band")
        a, i = found
        dl = L[a] - L[i]
        u = (thr - L[i]) / dl
        fc = f[i] + u * (f[a] - f[i])
        slope = dl / abs(f[a] - f[i])
        r = rho1 if abs(a - i) == 1 else 0.0
        var_bins = eps2 * ((1 - u) ** 2 + u**2 + 2 * r * u * (1 - u))
        out.append((fc, slope, var_bins))
    (f1, s1, v1), (f2, s2, v2) = out
    var_bw = v1 / s1**2 + v2 / s2**2 + eps2 * (1 / s1 + 1 / s2) ** 2
    return HalfPower(float((f2 - f1) / (2 * f_pk)), float(np.sqrt(var_bw) / (2 * f_pk)),
                     float(f1), float(f2), smoothing_bins=m)


def _hp_missing(why: str) -> HalfPower:
    nan = float("nan")
    return HalfPower(nan, nan, nan, nan, message=why)


def _half_power(ctx: _PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray) -> HalfPower:
    """Half-power bandwidth, on the PSD smoothed over about a sixth of the bandwidth."""
    raw = _half_power_pass(ctx, k0, lo, hi, mask, 1)
    if not np.isfinite(raw.zeta):
        return raw
    m = round((raw.f_hi_Hz - raw.f_lo_Hz) / ctx.df / HALF_POWER_SMOOTHING)
    m = min(m + 1 - m % 2, 31)  # odd, at most 31 bins
    if m <= 1:
        return raw
    smooth = _half_power_pass(ctx, k0, lo, hi, mask, m)
    return smooth if np.isfinite(smooth.zeta) else raw


def _sdof_shape(fe: np.ndarray, f_n: float, zeta: float, p: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """SDOF PSD shape s (1 at f_n) and its derivatives with respect to ln f_n and ln zeta."""
    r2 = (fe / f_n) ** 2
    z2 = zeta * zeta
    D = (1 - r2) ** 2 + 4 * z2 * r2
    s = 4 * z2 * (r2**p if p else 1.0) / D
    ds_f = s * (-2 * p - (4 * r2 * (1 - r2) - 8 * z2 * r2) / D)
    ds_z = s * (2 - 8 * z2 * r2 / D)
    return s, ds_f, ds_z


def _fit_sdof(ctx: _PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray, zeta0: float,
              zeta_res: float, p: int, fit_span: float) -> SDOFFit:
    f, lnP, df = ctx.f, ctx.lnP, ctx.df
    f_pk, _, ln_pk = ctx.interpolate(k0)
    z0 = zeta0 if np.isfinite(zeta0) and zeta0 > 0 else zeta_res
    z_starts = _start_zetas(ctx, k0, lo, hi, mask)
    z_span = max([z0, *z_starts])  # the band holds the widest candidate
    span = int(np.ceil(max(fit_span * z_span * f_pk / df, MIN_FIT_HALF_BINS,
                           MIN_FIT_HALF_RES * ctx.props.bandwidth_3dB_bins)))
    a, b = max(lo, k0 - span, 1), min(hi, k0 + span, f.size - 2)
    idx = np.arange(a, b + 1)
    idx = idx[~mask[idx]]
    band = (float(f[a]), float(f[b]))
    nan = float("nan")
    if idx.size < 8:
        return SDOFFit(nan, nan, nan, nan, nan, nan, band, int(idx.size), nan, False, False,
                       f"{idx.size} bins around the peak: too few to fit (need 8)")
    y = lnP[idx] - ctx.bias
    kern = ctx.props.kernel
    fe = np.abs(f[idx][:, None] - ctx.props.kernel_offsets_bins[None, :] * df)
    zmin = ZETA_MIN_FRACTION * zeta_res
    z0 = float(np.clip(z0, zmin * 1.5, 0.4))
    # parameters: ln f_n, ln zeta, ln W (W = pi zeta f_n S_0, the power under the peak), ln B
    lnW0 = ln_pk + np.log(np.pi * z0 * f_pk)
    lnB0 = min(float(np.percentile(lnP[idx], 5)), ln_pk - 0.7)
    theta0 = np.array([np.log(f_pk), np.log(z0), lnW0, lnB0])
    lnW_pk = ln_pk + np.log(ctx.props.enbw_bins * df)  # a tone's power
    lower = np.array([np.log(max(f[a], 1e-12)), np.log(zmin), lnW_pk - 8, ln_pk - 60])
    upper = np.array([np.log(f[b]), np.log(0.5), lnW_pk + 12, ln_pk])
    theta0 = np.clip(theta0, lower + 1e-6, upper - 1e-6)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = th.tobytes()
        hit = cache.get(key)
        if hit is not None:
            return hit
        f_n, zeta, W, B = np.exp(th)
        c = W / (np.pi * zeta * f_n)
        s, ds_f, ds_z = _sdof_shape(fe, f_n, zeta, p)
        Sk, Sf, Sz = s @ kern, ds_f @ kern, ds_z @ kern
        M = c * Sk + B
        dM = np.column_stack([c * (Sf - Sk), c * (Sz - Sk), c * Sk, np.full_like(Sk, B)])
        cache.clear()
        cache[key] = (M, dM)
        return M, dM

    def resid(th: np.ndarray) -> np.ndarray:
        return y - np.log(evaluate(th)[0])

    def jac(th: np.ndarray) -> np.ndarray:
        M, dM = evaluate(th)
        return -dM / M[:, None]

    # start from the half-power damping and from the peak's width on the smoothed PSD (the
    # raw width of a noisy peak can be a spike's); keep the better fit
    starts = [theta0]
    for zs in z_starts:
        th0 = theta0.copy()
        th0[1] = np.log(np.clip(zs, zmin * 1.5, 0.4))
        th0[2] = ln_pk + np.log(np.pi * np.exp(th0[1]) * f_pk)
        starts.append(np.clip(th0, lower + 1e-6, upper - 1e-6))
    res = None
    err: Exception | None = None
    for th0 in starts:
        try:
            r = least_squares(resid, th0, jac=jac, bounds=(lower, upper), method="trf",
                              x_scale=1.0, max_nfev=MAX_FIT_EVALUATIONS)
        except (ValueError, np.linalg.LinAlgError) as e:
            err = e
            continue
        if res is None or (r.status > 0) > (res.status > 0) or (
                (r.status > 0) == (res.status > 0) and r.cost < res.cost):
            res = r
    if res is None:
        return SDOFFit(nan, nan, nan, nan, nan, nan, band, int(idx.size), nan, False, False,
                       f"fit failed: {err}")
    th = res.x
    J = res.jac
    n, npar = J.shape
    lag = np.abs(idx[:, None] - idx[None, :])
    R = np.where(lag < ctx.rho2.size, ctx.rho2[np.minimum(lag, ctx.rho2.size - 1)], 0.0)
    A = np.linalg.pinv(J.T @ J)
    cov = ctx.eps2 * (A @ (J.T @ R @ J) @ A)
    redchi2 = float(np.sum(res.fun**2) / max(n - npar, 1) / ctx.eps2)
    cov *= max(1.0, redchi2)
    f_n, zeta = float(np.exp(th[0])), float(np.exp(th[1]))
    # inflate when the band fitted spans few half-power widths (the background and the
    # skirts are then poorly held, the linearised covariance optimistic) or few bins
    hw = max(zeta * f_n / df, 0.5)  # half-power half-width (bins)
    cover = min(k0 - a, b - k0) / hw
    if cover < 3.0:
        cov *= (3.0 / max(cover, 0.5)) ** 2
    cov *= max(1.0, 2.0 * MIN_FIT_HALF_BINS / max(n, 1))
    at_low = bool(th[1] <= lower[1] + 0.05)  # within 5 % of the bound
    ok = bool(res.status > 0)
    msg = ("damping at its lower bound: narrower than the resolution shows (a tone)"
           if at_low else ("" if ok else str(res.message)))
    return SDOFFit(
        f_n_Hz=f_n, f_n_std_Hz=f_n * float(np.sqrt(max(cov[0, 0], 0.0))),
        zeta=zeta, zeta_std=zeta * float(np.sqrt(max(cov[1, 1], 0.0))),
        peak_psd_per_Hz=float(np.exp(th[2]) / (np.pi * zeta * f_n)),
        background_per_Hz=float(np.exp(th[3])), band_Hz=band, n_bins=int(n),
        redchi2=redchi2, success=ok, at_lower_bound=at_low, message=msg)


def _start_zetas(ctx: _PSDContext, k0: int, a: int, b: int, mask: np.ndarray
                 ) -> list[float]:
    """Starting dampings from the half-power width of the PSD smoothed over 3, 7, 15 bins."""
    out = []
    for m in (3, 7, 15):
        hp = _half_power_pass(ctx, k0, a, b, mask, m)
        if np.isfinite(hp.zeta) and hp.zeta > 0:
            out.append(float(hp.zeta))
    return out


def _not_fitted(why: str) -> SDOFFit:
    nan = float("nan")
    return SDOFFit(nan, nan, nan, nan, nan, nan, (nan, nan), 0, nan, False, False, why)


def _zeta_resolution(ctx: _PSDContext, f_Hz: float) -> float:
    return ctx.props.bandwidth_3dB_bins * ctx.df / (2 * max(f_Hz, ctx.df))


def _estimate(ctx: _PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray, p: int,
              fit_span: float, response: str, line: bool = False) -> ModalEstimate:
    f_pk, f_std, ln_pk = ctx.interpolate(k0)
    zres = _zeta_resolution(ctx, f_pk)
    hp = _half_power(ctx, k0, lo, hi, mask)
    if line and not (hp.zeta > LINE_FIT_FACTOR * zres):
        fit = _not_fitted("not fitted: a mesh or shaft line no wider than the window "
                          f"(half-power zeta <= {LINE_FIT_FACTOR:g} x resolution equivalent)")
    else:
        fit = _fit_sdof(ctx, k0, lo, hi, mask, hp.zeta, zres, p, fit_span)
    return ModalEstimate(
        f_n_Hz=fit.f_n_Hz, f_n_std_Hz=fit.f_n_std_Hz, zeta=fit.zeta, zeta_std=fit.zeta_std,
        zeta_half_power=hp.zeta, zeta_half_power_std=hp.zeta_std, f_peak_Hz=f_pk,
        f_peak_std_Hz=f_std, psd_peak_per_Hz=float(np.exp(ln_pk)), zeta_resolution=zres,
        fit=fit, half_power=hp, response=response, dof=ctx.dof, resolution_Hz=ctx.df)


def _check_response(response: str) -> int:
    if response not in _RESPONSE_POWER:
        raise SignalError("response", "'displacement', 'velocity' or 'acceleration'",
                          repr(response))
    return _RESPONSE_POWER[response]


def half_power_damping(spectrum: Spectrum, f_Hz: float) -> HalfPower:
    """Damping of the peak nearest ``f_Hz`` by the half-power bandwidth.

    Parameters
    ----------
    spectrum : Spectrum
        One channel's PSD.
    f_Hz : float
        Frequency near the peak (Hz); the local maximum within two bins is used.

    Returns
    -------
    HalfPower
    """
    ctx = _PSDContext(spectrum)
    k0 = _local_max(ctx, f_Hz)
    return _half_power(ctx, k0, 1, ctx.f.size - 2, np.zeros(ctx.f.size, bool))


def fit_sdof(spectrum: Spectrum, f_Hz: float, *, response: Response = "displacement",
             fit_span: float = 5.0, exclude_Hz: Iterable[float] = ()) -> SDOFFit:
    r"""Fit a single-DOF response to the PSD around the peak nearest ``f_Hz``.

    Parameters
    ----------
    spectrum : Spectrum
        One channel's PSD.
    f_Hz : float
        Frequency near the peak (Hz).
    response : {'displacement', 'velocity', 'acceleration'}
        SDOF response measured: the PSD shape :math:`r^{2p}/((1-r^2)^2+(2\zeta r)^2)`,
        p = 0, 1, 2. The peak of the displacement form lies at :math:`f_n\sqrt{1-2\zeta^2}`,
        of the acceleration form at :math:`f_n/\sqrt{1-2\zeta^2}`.
    fit_span : float
        Half-width of the fitted band in half-power half-bandwidths (at least 8 bins).
    exclude_Hz : iterable of float
        Frequencies of lines to mask out of the fit (a few bins each side).

    Returns
    -------
    SDOFFit
    """
    p = _check_response(response)
    ctx = _PSDContext(spectrum)
    k0 = _local_max(ctx, f_Hz)
    mask = np.zeros(ctx.f.size, bool)
    for fx in exclude_Hz:
        _mask_line(ctx, round(fx / ctx.df), mask)
    mask[k0] = False
    hp = _half_power(ctx, k0, 1, ctx.f.size - 2, mask)
    zres = _zeta_resolution(ctx, ctx.f[k0])
    return _fit_sdof(ctx, k0, 1, ctx.f.size - 2, mask, hp.zeta, zres, p, fit_span)


def _local_max(ctx: _PSDContext, f_Hz: float) -> int:
    k = round(float(f_Hz) / ctx.df)
    if not 1 <= k <= ctx.f.size - 2:
        raise SignalError("f_Hz", f"inside (0, {ctx.f[-1]:g}) Hz", repr(f_Hz))
    a, b = max(1, k - 2), min(ctx.f.size - 2, k + 2)
    return a + int(np.argmax(ctx.lnP[a: b + 1]))


def _mask_line(ctx: _PSDContext, k: int, mask: np.ndarray) -> None:
    """Mask a line at bin k: its main lobe and one bin more, further while the PSD falls."""
    n = ctx.f.size
    if not 0 <= k < n:
        return
    base = int(np.ceil(ctx.props.mainlobe_half_width_bins)) + 1
    cap = 4 * base
    lo = k - base
    while lo - 1 >= 0 and k - lo < cap and ctx.lnP[lo - 1] < ctx.lnP[lo]:
        lo -= 1
    hi = k + base
    while hi + 1 < n and hi - k < cap and ctx.lnP[hi + 1] < ctx.lnP[hi]:
        hi += 1
    mask[max(lo, 0): min(hi, n - 1) + 1] = True


# --------------------------------------------------------------------------------------------
# all peaks of a spectrum


def analyse_peaks(spectrum: Spectrum, *, mesh_frequency_Hz: float | None = None,
                  shaft_frequencies_Hz: Sequence[float] = (), prominence_dB: float = 6.0,
                  min_sigma: float = 5.0, false_alarm: float = FALSE_ALARM,
                  f_range_Hz: Sequence[float] | None = None,
                  max_peaks: int = 20, tolerance_Hz: float | None = None, rtol: float = 0.002,
                  max_sideband: int = 3, max_shaft_harmonic: int = 10,
                  response: Response = "displacement", fit_span: float = 5.0) -> PeakAnalysis:
    r"""Find, locate, classify and damp the peaks of one channel's PSD.

    Parameters
    ----------
    spectrum : Spectrum
        One channel's Welch PSD.
    mesh_frequency_Hz : float, optional
        Mesh frequency :math:`z_1 n_1/60` (Hz).
    shaft_frequencies_Hz : sequence of float
        Shaft frequencies (Hz), for sidebands and shaft harmonics.
    prominence_dB : float
        Least prominence of a peak on the log PSD (dB).
    min_sigma : float
        Least prominence in standard deviations of the log PSD estimate,
        :math:`\sigma_{dB} = 10 \log_{10}(e) \sqrt{\psi'(\nu/2)}`; the threshold is the larger.
    false_alarm : float
        A peak must also stand above the local background (running median) by the
        chi-square quantile of the Welch estimate (:math:`\nu` dof) that pure noise exceeds
        with this probability anywhere in the searched band (Sidak over its bins), or have a
        prominence above the spread between the upper and lower such quantiles.
    f_range_Hz : (float, float), optional
        Band searched (Hz); default from just above the window's main lobe at 0 Hz to
        the Nyquist frequency.
    max_peaks : int
        Most prominent peaks kept.
    tolerance_Hz : float, optional
        Absolute matching tolerance (Hz); default the window's half-power bandwidth
        (1.44 bins for Hann). The tolerance at f is ``tolerance_Hz + rtol * f``.
    rtol : float
        Relative matching tolerance (speed variation during the record).
    max_sideband, max_shaft_harmonic : int
        See :func:`classify_frequency`.
    response : {'displacement', 'velocity', 'acceleration'}
        See :func:`fit_sdof`.
    fit_span : float
        See :func:`fit_sdof`.

    Returns
    -------
    PeakAnalysis

    Notes
    -----
    A mesh or shaft line near a peak is masked out of that peak's half-power search and fit;
    another unexplained peak limits the fitted band at the PSD minimum between the two.
    """
    p = _check_response(response)
    ctx = _PSDContext(spectrum)
    f, lnP, df = ctx.f, ctx.lnP, ctx.df
    n = f.size
    first = int(np.ceil(ctx.props.mainlobe_half_width_bins)) + 1
    if f_range_Hz is None:
        a, b = first, n - 1
    else:
        lo_, hi_ = _check_band(f_range_Hz, spectrum.fs_Hz)
        a, b = max(int(np.ceil(lo_ / df)), 1), min(int(np.floor(hi_ / df)), n - 1)
    if not (np.isfinite(prominence_dB) and prominence_dB >= 0):
        raise SignalError("prominence_dB", "finite and >= 0", repr(prominence_dB))
    if not 0 < false_alarm < 1:
        raise SignalError("false_alarm", "in (0, 1)", repr(false_alarm))
    sigma_dB = 10 * np.log10(np.e) * np.sqrt(ctx.eps2)
    threshold = max(float(prominence_dB), float(min_sigma) * sigma_dB)
    LdB = 10 * np.log10(np.e) * lnP
    detect_dB, spread_dB = _detection_threshold_db(ctx.dof, b - a + 1, false_alarm)
    bg_dB = 10 * np.log10(np.e) * _background_log(ctx)
    idx, props = sps.find_peaks(LdB[a: b + 1], prominence=threshold)
    idx = idx + a
    prom = props["prominences"]
    # significant: above the local noise floor by more than noise reaches anywhere in the
    # band, or (a broad feature that lifts the running median) prominent by more than the
    # spread between the highest and lowest noise values in the band
    sig = (LdB[idx] - bg_dB[idx] >= detect_dB) | (prom >= spread_dB)
    idx, prom = idx[sig], prom[sig]
    order = np.argsort(-prom)[: int(max_peaks)]
    keep = np.sort(order)
    idx, prom = idx[keep], prom[keep]
    atol = (ctx.props.bandwidth_3dB_bins * df) if tolerance_Hz is None else float(tolerance_Hz)
    shafts = tuple(float(s) for s in shaft_frequencies_Hz)
    located = []
    for k in idx:
        fk, fstd, lnk = ctx.interpolate(int(k))
        loc = classify_frequency(fk, mesh_frequency_Hz=mesh_frequency_Hz,
                                 shaft_frequencies_Hz=shafts, tolerance_Hz=atol, rtol=rtol,
                                 max_sideband=max_sideband,
                                 max_shaft_harmonic=max_shaft_harmonic)
        located.append((int(k), fk, fstd, lnk, loc))
    line_mask = np.zeros(n, bool)
    for k, *_, loc in located:
        if loc.kind is not None:
            _mask_line(ctx, k, line_mask)
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        # mesh harmonics too weak to be detected as peaks still bend a nearby fit
        for fk in np.arange(1, int(f[-1] // mesh_frequency_Hz) + 1) * mesh_frequency_Hz:
            k = round(fk / df)
            if 0 < k < n - 1 and not line_mask[k]:
                _mask_line(ctx, k + int(np.argmax(lnP[k - 1: k + 2])) - 1, line_mask)
    free = [k for k, *_, loc in located if loc.kind is None]
    peaks = []
    for k, fk, fstd, lnk, loc in located:
        own = np.zeros(n, bool)  # the peak itself is what is measured: never masked
        _mask_line(ctx, k, own)
        mask = line_mask & ~own
        lo, hi = 1, n - 2
        others = [j for j in free if j != k] if loc.kind is None else [
            j for j, *_ in located if j != k]
        left = [j for j in others if j < k]
        right = [j for j in others if j > k]
        if left:
            j = max(left)
            lo = j + int(np.argmin(np.where(mask[j: k + 1], np.inf, lnP[j: k + 1])))
        if right:
            j = min(right)
            hi = k + int(np.argmin(np.where(mask[k: j + 1], np.inf, lnP[k: j + 1])))
        mode = _estimate(ctx, k, lo, hi, mask, p, fit_span, response,
                         line=loc.kind is not None)
        z, zhp = mode.fit.zeta, mode.zeta_half_power
        if loc.kind in ("mesh_sideband", "shaft_harmonic") and mode.broad:
            # Sidebands and shaft lines are as narrow as a tone; a broad peak that merely falls
            # within their tolerance is a resonance (its `location` still names the line).
            kind = "structural"
        elif loc.kind is not None:
            kind = loc.kind
        elif mode.broad:
            kind = "structural"
        elif np.isfinite(z) and (mode.fit.at_lower_bound or z <= mode.zeta_resolution):
            kind = "tonal"
        elif not np.isfinite(z) and zhp <= mode.zeta_resolution:  # too hemmed in to fit
            kind = "tonal"
        else:  # fit failed, or damping not told apart from the resolution limit
            kind = "unresolved"
        peaks.append(Peak(index=k, f_Hz=fk, f_std_Hz=fstd, psd_per_Hz=float(np.exp(lnk)),
                          prominence_dB=float(prom[list(idx).index(k)]), kind=kind,
                          location=loc, mode=mode))
    return PeakAnalysis(peaks=tuple(peaks), mesh_frequency_Hz=mesh_frequency_Hz,
                        shaft_frequencies_Hz=shafts, tolerance_Hz=atol, rtol=float(rtol),
                        threshold_dB=threshold, detection_threshold_dB=detect_dB,
                        false_alarm=float(false_alarm))


def _detection_threshold_db(dof: float, n_bins: int, false_alarm: float
                           ) -> tuple[float, float]:
    r"""Detection threshold (dB) above the local background, and noise's prominence spread.

    The height a noise bin exceeds with probability ``false_alarm`` anywhere among
    ``n_bins``.

    :math:`\nu \hat S / S \sim \chi^2_\nu`; Sidak correction for the bins searched,
    :math:`\alpha_1 = 1 - (1 - \alpha)^{1/n}`, the bins taken as independent (conservative:
    neighbouring Welch bins are correlated, so fewer independent tries are made).
    Returns that height and the spread (dB) between the upper and the lower such quantile,
    the most prominence pure noise shows with that probability.
    """
    nu = max(float(dof), 1.0)
    alpha1 = -np.expm1(np.log1p(-float(false_alarm)) / max(int(n_bins), 1))
    hi = float(10 * np.log10(chi2.isf(alpha1, nu) / nu))
    lo = float(10 * np.log10(chi2.ppf(alpha1, nu) / nu))
    return hi, hi - lo


def _background_log(ctx: _PSDContext) -> np.ndarray:
    r"""Natural log of the local background PSD: running median over a wide window, bias-corrected.

    The window (at least 65 bins, a sixteenth of the spectrum) is wide against a resonance,
    so the median follows the noise floor; the median of :math:`\chi^2_\nu/\nu` is below
    1, corrected for.
    """
    n = ctx.psd.size
    w = max(65, n // 16)
    w += 1 - w % 2
    med = median_filter(ctx.psd, size=min(w, n - (1 - n % 2)), mode="reflect")
    nu = max(ctx.dof, 1.0)
    return np.log(np.maximum(med, ctx.psd.max() * 1e-30)) - np.log(chi2.median(nu) / nu)


def natural_frequencies(spectrum: Spectrum, **kwargs: Any) -> tuple[ModalEstimate, ...]:
    """Modal estimates of the structural peaks of a PSD (see :func:`analyse_peaks`)."""
    return analyse_peaks(spectrum, **kwargs).modes


# --------------------------------------------------------------------------------------------
# a whole recording


@dataclass(frozen=True)
class QualityFlags:
    """What was used of a channel, and what is wrong with it.

    Attributes
    ----------
    n_samples, n_valid, n_invalid : int
        Samples in the channel, valid and invalid (gaps, rejected).
    n_segments, n_segments_dropped, n_samples_dropped : int
        Valid segments used; segments shorter than one window and their samples, dropped.
    n_windows : int
        Welch windows averaged.
    dof : float
        Equivalent degrees of freedom of each PSD value.
    clipping : Clipping or None
    constant : bool
        Every valid sample equal.
    too_short : bool
        No valid segment long enough for the requested resolution.
    messages : tuple of str
        Human-readable notes, one per problem.
    """

    n_samples: int
    n_valid: int
    n_invalid: int
    n_segments: int = 0
    n_segments_dropped: int = 0
    n_samples_dropped: int = 0
    n_windows: int = 0
    dof: float = 0.0
    clipping: Clipping | None = None
    constant: bool = False
    too_short: bool = False
    messages: tuple[str, ...] = ()

    @property
    def clipped(self) -> bool:
        """The channel holds runs at its extreme values (see :func:`detect_clipping`)."""
        return bool(self.clipping is not None and self.clipping.clipped)

    @property
    def ok(self) -> bool:
        """Analysed, not clipped, nothing dropped."""
        return not (self.clipped or self.constant or self.too_short or self.n_samples_dropped)


@dataclass(frozen=True)
class ChannelAnalysis:
    """Spectrum, RMS, peaks and quality of one channel.

    Attributes
    ----------
    name, unit : str
    sample_rate_Hz : float
    spectrum : Spectrum or None
        None when the channel could not be analysed (see ``error``).
    rms : BandRMS or None
        Full band: time domain (detrended valid segments) and Parseval (PSD integral).
    band_rms : tuple of BandRMS
        One per requested band.
    peaks : PeakAnalysis or None
    quality : QualityFlags
    error : str or None
        Why the channel was not analysed (with ``errors="flag"``).
    """

    name: str
    unit: str
    sample_rate_Hz: float
    spectrum: Spectrum | None
    rms: BandRMS | None
    band_rms: tuple[BandRMS, ...]
    peaks: PeakAnalysis | None
    quality: QualityFlags
    error: str | None = None

    @property
    def modes(self) -> tuple[ModalEstimate, ...]:
        """Modal estimates of the structural peaks (empty when none or not analysed)."""
        return () if self.peaks is None else self.peaks.modes


@dataclass(frozen=True)
class RecordingAnalysis:
    """Per-channel analysis of a recording, and the settings used.

    Attributes
    ----------
    channels : dict of str to ChannelAnalysis
    settings : dict
        The analysis parameters (JSON-ready).
    """

    channels: dict[str, ChannelAnalysis]
    settings: dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, name: str) -> ChannelAnalysis:
        return self.channels[name]


def _channels_of(rec: Any, names: Sequence[str] | None) -> dict[str, Any]:
    chans = rec.channels if hasattr(rec, "channels") else rec
    if not isinstance(chans, Mapping):
        raise SignalError("rec", "a Recording or a mapping of name to Channel",
                          type(rec).__name__)
    if names is None:
        return dict(chans)
    missing = [n for n in names if n not in chans]
    if missing:
        raise SignalError("channels", f"names of channels in the recording {sorted(chans)}",
                          repr(missing))
    return {n: chans[n] for n in names}


def analyse_recording(rec: Any, *, channels: Sequence[str] | None = None,
                      nperseg: int | None = None, resolution_Hz: float | None = None,
                      noverlap: int | None = None, window: Window = "hann",
                      detrend: Detrend = "constant", average: Average = "mean",
                      mesh_frequency_Hz: float | None = None,
                      shaft_frequencies_Hz: Sequence[float] = (),
                      bands_Hz: Sequence[Sequence[float]] = (), peaks: bool = True,
                      prominence_dB: float = 6.0, f_range_Hz: Sequence[float] | None = None,
                      max_peaks: int = 20, response: Response = "displacement",
                      clip_min_run: int = 3, full_scale: Sequence[float] | None = None,
                      errors: Literal["flag", "raise"] = "flag") -> RecordingAnalysis:
    """Spectra, RMS, natural frequencies and quality flags of a recording's channels.

    Channels that share sample rate, length and validity mask are estimated together in one
    :func:`scipy.signal.welch` call per valid segment.

    Parameters
    ----------
    rec : Recording or mapping of str to Channel
        The recording (its ``channels``).
    channels : sequence of str, optional
        Channels to analyse; default all.
    nperseg, resolution_Hz, noverlap, window, detrend, average
        As for :func:`~rigtools.analysis.spectra.welch_psd`.
    mesh_frequency_Hz, shaft_frequencies_Hz, prominence_dB, f_range_Hz, max_peaks, response
        As for :func:`analyse_peaks`.
    bands_Hz : sequence of (float, float)
        Bands for band-limited RMS (Hz).
    peaks : bool
        Look for peaks (False: spectra and RMS only).
    clip_min_run : int
        Run of identical extreme samples taken as clipping (:func:`detect_clipping`).
    full_scale : (float, float), optional
        Acquisition full scale (unit), e.g. ``(-491.52, 491.505)`` for the reference DBC.
    errors : {'flag', 'raise'}
        ``"flag"``: a channel that is constant or too short gets ``error`` and quality flags
        and no spectrum; ``"raise"``: the :class:`~rigtools.analysis.spectra.SignalError` is
        raised, naming the channel.

    Returns
    -------
    RecordingAnalysis
    """
    if errors not in ("flag", "raise"):
        raise SignalError("errors", "'flag' or 'raise'", repr(errors))
    if average not in ("mean", "median"):
        raise SignalError("average", "'mean' or 'median'", repr(average))
    _check_response(response)
    det = _check_detrend(detrend)
    chans = _channels_of(rec, channels)
    bands = [tuple(float(v) for v in b) for b in bands_Hz]
    settings = {"nperseg": nperseg, "resolution_Hz": resolution_Hz, "noverlap": noverlap,
                "window": window if not isinstance(window, np.ndarray) else "custom",
                "detrend": det if not callable(det) else "custom", "average": average,
                "mesh_frequency_Hz": mesh_frequency_Hz,
                "shaft_frequencies_Hz": list(shaft_frequencies_Hz), "bands_Hz": bands,
                "prominence_dB": prominence_dB, "response": response}
    results: dict[str, ChannelAnalysis] = {}
    # quality first, then group by (rate, length, mask) for batched Welch
    groups: dict[tuple[Any, ...], list[str]] = {}
    prep: dict[str, dict[str, Any]] = {}
    for name, ch in chans.items():
        fs = _check_fs(ch.sample_rate_Hz)
        x = np.asarray(ch.values)
        v = np.asarray(ch.valid, bool)
        whole = bool(v.all())
        n_valid = x.size if whole else int(np.count_nonzero(v))
        clip = detect_clipping(x, v, min_run=clip_min_run, full_scale=full_scale)
        base = dict(n_samples=int(x.size), n_valid=n_valid, n_invalid=int(x.size - n_valid))
        msgs = []
        if clip.clipped:
            msgs.append(f"clipped: {clip.n_clipped} samples in {clip.n_runs} run(s) at the "
                        f"extreme values {clip.low:g} / {clip.high:g} {ch.unit}")
        prep[name] = dict(ch=ch, fs=fs, x=x, mask=None if whole else v, clip=clip, base=base,
                          msgs=msgs)
        if n_valid == 0 or clip.high == clip.low:
            err = SignalError(name, detail="holds no valid sample") if n_valid == 0 else (
                _constant_error(name, n_valid, clip.high))
            _fail(results, name, ch, prep[name], err, errors, constant=n_valid > 0)
            continue
        nps = _resolve_nperseg(nperseg, resolution_Hz, fs)
        key = (fs, x.size, x.dtype.str, nps, b"all" if whole else v.tobytes())
        groups.setdefault(key, []).append(name)
    for (fs, n, _, nps, _), names in groups.items():
        nov = _check_noverlap(noverlap, nps)
        w = _window_array(window, nps)
        wkey = window if not isinstance(window, np.ndarray) else w
        props = window_properties(wkey, nps)
        first = prep[names[0]]
        mask = first["mask"]
        if nps > n:
            err = _short_error(nps, n, fs, n, "len(x)")
            for name in names:
                _fail(results, name, prep[name]["ch"], prep[name], err, errors, too_short=True)
            continue
        xs = first["x"][None, :] if len(names) == 1 else np.stack(
            [prep[nm]["x"] for nm in names])
        try:
            freq, P, acc, segs_list = _welch_core(xs, mask, fs, w, nps, nov, det, average,
                                                  "density", props)
        except SignalError as e:
            for name in names:
                _fail(results, name, prep[name]["ch"], prep[name], e, errors, too_short=True)
            continue
        segs = segs_list[0]
        rows = np.arange(len(names))
        tot, cnt = _mean_square_time(xs, segs, rows, fs, (0.0, fs / 2), det)
        band_ms = [(band, *_mean_square_time(xs, segs, rows, fs, band, det))
                   for band in (_check_band(b, fs) for b in bands)]
        for i, name in enumerate(names):
            pr = prep[name]
            ch = pr["ch"]
            account = WelchAccount(**{k: getattr(acc, k)[i] for k in (
                "n_windows", "dof", "n_segments", "n_segments_dropped", "n_samples_dropped",
                "n_invalid", "n_samples_used")})
            spec = Spectrum(freq_Hz=freq, unit=ch.unit, fs_Hz=fs, nperseg=nps, noverlap=nov,
                            window=window, detrend=det, account=account, psd_per_Hz=P[i],
                            average=average)
            rms = BandRMS(band_Hz=(0.0, fs / 2), rms_time=float(np.sqrt(tot[i] / cnt)),
                          rms_parseval=float(rms_from_psd(spec)), unit=ch.unit,
                          n_samples=int(cnt))
            brms = [BandRMS(band_Hz=band, rms_time=float(np.sqrt(bt[i] / bc)),
                            rms_parseval=float(rms_from_psd(spec, band)), unit=ch.unit,
                            n_samples=int(bc))
                    for band, bt, bc in band_ms]
            msgs = list(pr["msgs"])
            if account.n_segments_dropped:
                msgs.append(f"{int(account.n_segments_dropped)} valid segment(s) shorter than "
                            f"one window ({nps} samples) dropped: "
                            f"{int(account.n_samples_dropped)} samples")
            quality = QualityFlags(
                **pr["base"], n_segments=int(account.n_segments),
                n_segments_dropped=int(account.n_segments_dropped),
                n_samples_dropped=int(account.n_samples_dropped),
                n_windows=int(account.n_windows), dof=float(account.dof),
                clipping=pr["clip"], messages=tuple(msgs))
            pk = None
            error = None
            if peaks:
                try:
                    pk = analyse_peaks(spec, mesh_frequency_Hz=mesh_frequency_Hz,
                                       shaft_frequencies_Hz=shaft_frequencies_Hz,
                                       prominence_dB=prominence_dB, f_range_Hz=f_range_Hz,
                                       max_peaks=max_peaks, response=response)
                except SignalError as e:
                    if errors == "raise":
                        raise e.for_channel(name) from e
                    error = str(e.for_channel(name))
            results[name] = ChannelAnalysis(name=name, unit=ch.unit, sample_rate_Hz=fs,
                                            spectrum=spec, rms=rms, band_rms=tuple(brms),
                                            peaks=pk, quality=quality, error=error)
    ordered = {name: results[name] for name in chans}
    return RecordingAnalysis(channels=ordered, settings=settings)


def _constant_error(name: str, n_valid: int, value: float) -> SignalError:
    return ConstantSignalError(
        "values", detail=f"is constant (all {n_valid} valid samples equal {value!r}): its "
        "spectrum is zero, no peak or damping can be estimated", channel=name)


def _short_error(nps: int, longest: int, fs: float, n: int, what: str) -> SignalError:
    return InsufficientDataError(
        "nperseg", f"<= {what}={longest}", str(nps),
        f"resolution {fs / nps:g} Hz needs {nps / fs:g} s of signal, there are {n / fs:g} s")


def _fail(results: dict[str, ChannelAnalysis], name: str, ch: Any, pr: dict[str, Any],
          err: SignalError, errors: str, constant: bool = False, too_short: bool = False
          ) -> None:
    err = err if err.channel == name else err.for_channel(name)
    if errors == "raise":
        raise err
    quality = QualityFlags(**pr["base"], clipping=pr["clip"], constant=constant,
                           too_short=too_short, messages=(*pr["msgs"], str(err)))
    results[name] = ChannelAnalysis(name=name, unit=ch.unit, sample_rate_Hz=pr["fs"],
                                    spectrum=None, rms=None, band_rms=(), peaks=None,
                                    quality=quality, error=str(err))
