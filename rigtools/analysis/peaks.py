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

:func:`~rigtools.analysis.recording.analyse_recording` runs spectra, RMS, quality checks and
peaks over the channels of a :class:`~rigtools.ingest.recording.Recording` and returns one
:class:`~rigtools.analysis.recording.ChannelAnalysis` each.

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

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy import signal as sps
from scipy.ndimage import median_filter
from scipy.stats import chi2

from rigtools.analysis.sdof_fit import (
    LINE_FIT_FACTOR,
    HalfPower,
    PSDContext,
    SDOFFit,
    fit_sdof,
    fit_sdof_in_band,
    half_power_damping,
    half_power_in_band,
    mask_line,
    not_fitted,
    zeta_resolution,
)
from rigtools.analysis.signal_checks import Response, check_band, check_response
from rigtools.analysis.spectrum_results import Spectrum
from rigtools.errors import SignalError

__all__ = [
    "FALSE_ALARM",
    "LOW_DOF",
    "HalfPower",
    "LocationClass",
    "ModalEstimate",
    "Peak",
    "PeakAnalysis",
    "SDOFFit",
    "analyse_peaks",
    "classify_frequency",
    "detection_threshold_db",
    "fit_sdof",
    "half_power_damping",
    "natural_frequencies",
]

PeakKind = Literal["structural", "mesh_harmonic", "mesh_sideband", "shaft_harmonic", "tonal",
                   "unresolved"]
#: Default false-alarm probability per spectrum of the detection threshold (a noise bin
#: anywhere in the searched band exceeding it).
FALSE_ALARM = 0.01
#: A structural peak's fitted damping must exceed the resolution equivalent by this many of
#: its standard uncertainties.
ZETA_MARGIN_SIGMA = 2.0
#: ... and its half-power band (2 zeta f_n) must span at least this many bins.
MIN_RESOLVED_BINS = 4.0
#: Below this many equivalent degrees of freedom a modal estimate is flagged ``low_dof``.
LOW_DOF = 35.0


# --------------------------------------------------------------------------------------------
# results


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


def _estimate(ctx: PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray, p: int,
              fit_span: float, response: str, line: bool = False) -> ModalEstimate:
    f_pk, f_std, ln_pk = ctx.interpolate(k0)
    zres = zeta_resolution(ctx, f_pk)
    hp = half_power_in_band(ctx, k0, lo, hi, mask)
    if line and not (hp.zeta > LINE_FIT_FACTOR * zres):
        fit = not_fitted("not fitted: a mesh or shaft line no wider than the window "
                          f"(half-power zeta <= {LINE_FIT_FACTOR:g} x resolution equivalent)")
    else:
        fit = fit_sdof_in_band(ctx, k0, lo, hi, mask, hp.zeta, zres, p, fit_span)
    return ModalEstimate(
        f_n_Hz=fit.f_n_Hz, f_n_std_Hz=fit.f_n_std_Hz, zeta=fit.zeta, zeta_std=fit.zeta_std,
        zeta_half_power=hp.zeta, zeta_half_power_std=hp.zeta_std, f_peak_Hz=f_pk,
        f_peak_std_Hz=f_std, psd_peak_per_Hz=float(np.exp(ln_pk)), zeta_resolution=zres,
        fit=fit, half_power=hp, response=response, dof=ctx.dof, resolution_Hz=ctx.df)


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
    p = check_response(response)
    ctx = PSDContext(spectrum)
    f, lnP, df = ctx.f, ctx.lnP, ctx.df
    n = f.size
    first = int(np.ceil(ctx.props.mainlobe_half_width_bins)) + 1
    if f_range_Hz is None:
        a, b = first, n - 1
    else:
        lo_, hi_ = check_band(f_range_Hz, spectrum.fs_Hz)
        a, b = max(int(np.ceil(lo_ / df)), 1), min(int(np.floor(hi_ / df)), n - 1)
    if not (np.isfinite(prominence_dB) and prominence_dB >= 0):
        raise SignalError("prominence_dB", "finite and >= 0", repr(prominence_dB))
    if not 0 < false_alarm < 1:
        raise SignalError("false_alarm", "in (0, 1)", repr(false_alarm))
    sigma_dB = 10 * np.log10(np.e) * np.sqrt(ctx.eps2)
    threshold = max(float(prominence_dB), float(min_sigma) * sigma_dB)
    LdB = 10 * np.log10(np.e) * lnP
    detect_dB, spread_dB = detection_threshold_db(ctx.dof, b - a + 1, false_alarm)
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
            mask_line(ctx, k, line_mask)
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        # mesh harmonics too weak to be detected as peaks still bend a nearby fit
        for fk in np.arange(1, int(f[-1] // mesh_frequency_Hz) + 1) * mesh_frequency_Hz:
            k = round(fk / df)
            if 0 < k < n - 1 and not line_mask[k]:
                mask_line(ctx, k + int(np.argmax(lnP[k - 1: k + 2])) - 1, line_mask)
    free = [k for k, *_, loc in located if loc.kind is None]
    peaks = []
    for k, fk, fstd, lnk, loc in located:
        own = np.zeros(n, bool)  # the peak itself is what is measured: never masked
        mask_line(ctx, k, own)
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


def detection_threshold_db(dof: float, n_bins: int, false_alarm: float
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


def _background_log(ctx: PSDContext) -> np.ndarray:
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
