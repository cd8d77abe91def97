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
   :math:`k f_\text{mesh} \pm j f_\text{shaft}` (:math:`1 \le k \le` ``max_mesh_order``,
   default :data:`~rigtools.analysis.mesh_lines.MAX_MESH_ORDER` = 5: the mesh harmonics a rig's
   spectrum shows as lines) or :math:`k f_\text{shaft}` is a mesh harmonic, a mesh sideband or
   a shaft harmonic (in that order of precedence). Mesh harmonics above ``max_mesh_order`` are
   not mesh lines: a peak there is classified like any other.
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

5. **Kind**, from the peak's width against the window's main lobe:

   * ``"structural"``: a *broad* peak, wherever it sits
     (:attr:`~rigtools.analysis.peak_results.ModalEstimate.broad`): the fit succeeded, its
     damping exceeds the resolution equivalent beyond doubt
     (:math:`\zeta - 2\sigma_\zeta > \zeta_\text{res} = B_\text{3dB} / (2 f)`, with
     :math:`B_\text{3dB}` the window's half-power bandwidth: a pure tone appears that wide),
     its half-power band :math:`2 \zeta f_n` spans at least ``MIN_RESOLVED_MAINLOBES`` = 2
     of the window's whole main lobes (8 bins for Hann) and ``MIN_RESOLVED_BINS`` bins, and the
     peak lies near the fitted :math:`f_n`, where a mode's noisy maximum can (a tone on the
     skirt of a mode, or a horn of a line swept by a varying speed, is not the mode its fit
     describes).
   * a *line*, no wider than the main lobe (half-power damping at most ``LINE_FIT_FACTOR`` times
     a tone's, or a fitted damping at or below :math:`\zeta_\text{res}`): its location class
     (``"mesh_harmonic"``, ``"mesh_sideband"``, ``"shaft_harmonic"``), else ``"tonal"``;
   * ``"unresolved"`` otherwise (the fit fails, or its damping cannot be told apart from the
     resolution limit), or the location class of a peak at a mesh or shaft line.

   Estimates from a PSD with fewer than ``LOW_DOF`` equivalent dof are flagged
   ``ModalEstimate.low_dof``.

   5a. **Two close modes in one peak.** Every structural peak (and every unresolved peak
   that is no mesh or shaft line, such as the merged peak of two modes whose maximum lies off
   its single-DOF fit's f_n) is fitted again as two modes
   (:func:`~rigtools.analysis.two_mode_fit.fit_two_modes_in_band`), over a band that reaches
   past the other structural or unresolved peaks within ``JOINT_REACH`` half-power bandwidths,
   with every mesh harmonic (of any order), sideband and shaft harmonic that stands out there
   masked (``LINE_STAND_OUT_FALSE_ALARM``: a cluster of weak lines is not a second mode).
   When the two-mode model is clearly better (a chi-square-difference test at a false alarm
   of :data:`~rigtools.analysis.two_mode_fit.JOINT_FALSE_ALARM`, the modes apart by more than
   three standard uncertainties, the joint model fitting, both modes' damping resolved
   beyond doubt, and broad where a mode sits at a mesh or shaft line) each mode becomes
   its own structural peak at its f_n, its fit flagged ``joint_fit`` (without ``misfit``) and
   carrying the joint fit (:attr:`~rigtools.analysis.peak_results.ModalEstimate.joint`);
   otherwise the single-DOF fit stands with its flags.
6. **A line on a mode**: every line is masked out of the fits of the modes beside it (its
   main lobe, further while the PSD falls), and the structural peaks are refitted so. A line
   that sits on a mode hides the mode's maximum, so both are reported: for each line the PSD
   beside it (smoothed over ``SHOULDER_SMOOTHING_BINS``, the lines masked) is followed uphill
   to its maximum, and when that has the prominence threshold, an SDOF is fitted there with
   the line's main lobe masked; a broad mode found so is reported as its own
   ``"structural"`` peak (unless another peak already reports it). A broad peak at which the
   PSD stands above the mode fitted without it by more than the Welch estimate's one-sided
   ``false_alarm`` quantile (Sidak-corrected for the bins across the mode's half-power band,
   among which its maximum falls) and by at least ``LINE_ON_MODE_MIN_DB`` is a line on a
   mode: both are reported, the mode by the masked fit. A line within a structural peak's
   half-power band names it in :attr:`~rigtools.analysis.peak_results.Peak.on_mode`.
7. **The quota** ``max_peaks`` keeps the peaks wider than the main lobe first, then the lines,
   each by prominence: lines do not crowd out modes. Lines beyond the quota are not reported
   but are masked and searched for a mode they hide (6).

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

import math
from collections.abc import Callable, Collection, Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from scipy import signal as sps
from scipy.ndimage import median_filter
from scipy.stats import chi2

from rigtools.analysis.mesh_lines import (
    MAX_MESH_ORDER,
    LocationClass,
    classify_frequency,
    line_bins,
    mask_main_lobe,
    mask_standing_lines,
)
from rigtools.analysis.peak_results import (
    FALSE_ALARM,
    LINE_KINDS,
    ModalEstimate,
    Peak,
    PeakAnalysis,
    joint_mode_resolved,
    peak_kind,
)
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
    sdof_shape,
    zeta_resolution,
)
from rigtools.analysis.signal_checks import (
    RESPONSE_POWER,
    Response,
    check_band,
    check_response,
)
from rigtools.analysis.spectrum_results import Spectrum
from rigtools.analysis.two_mode_fit import TwoModeFit, fit_two_modes_in_band, joint_band
from rigtools.errors import SignalError

__all__ = [
    "HalfPower",
    "SDOFFit",
    "TwoModeFit",
    "analyse_peaks",
    "detection_threshold_db",
    "fit_sdof",
    "half_power_damping",
    "natural_frequencies",
]

# log10(e): 10 log10(e) dB per unit of natural log of power (math.e: mypy misreads numpy's e
# once numba, which ships its types, is analysed in the same run)
_LOG10_E = math.log10(math.e)

#: Width (bins) of the moving average the PSD beside a line is followed on, uphill to a mode.
SHOULDER_SMOOTHING_BINS = 7
#: A line is told apart on a mode whose half-power band spans this many times the line's
#: masked main lobe (and one bin more each side), or more.
LINE_ON_MODE_WIDTHS = 2.0
#: ... and when its bin stands at least this far above the mode fitted without it (dB).
LINE_ON_MODE_MIN_DB = 3.0
#: Peaks within this many half-power bandwidths of a peak are fitted with it as two modes
#: (module docstring, 5a).
JOINT_REACH = 3.0



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
        fit=fit, half_power=hp, response=response, dof=ctx.dof, resolution_Hz=ctx.df,
        mainlobe_half_width_Hz=ctx.props.mainlobe_half_width_bins * ctx.df)


def _band(ctx: PSDContext, k: int, others: Sequence[int], mask: np.ndarray
          ) -> tuple[int, int]:
    """Bins ``[lo, hi]`` a peak at k is fitted in: up to the PSD minimum before the next peak."""
    lnP = ctx.lnP
    lo, hi = 1, ctx.f.size - 2
    left = [j for j in others if j < k]
    right = [j for j in others if j > k]
    if left:
        j = max(left)
        lo = j + int(np.argmin(np.where(mask[j: k + 1], np.inf, lnP[j: k + 1])))
    if right:
        j = min(right)
        hi = k + int(np.argmin(np.where(mask[k: j + 1], np.inf, lnP[k: j + 1])))
    return lo, hi


def _smoothed_log(psd: np.ndarray, mask: np.ndarray, m: int) -> np.ndarray:
    """Natural log of the m-bin moving average of the PSD over unmasked bins (NaN where masked)."""
    w = (~mask).astype(np.float64)
    box = np.ones(m)
    num = np.convolve(psd * w, box, mode="same")
    den = np.convolve(w, box, mode="same")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.log(num / den)
    out[mask | (den < 0.5 * m)] = np.nan
    return out


def _uphill(L: np.ndarray, k: int, step: int, limit: int) -> int | None:
    """From bin k outward (``step`` -1 or 1), the first local maximum of ``L`` (NaN skipped)."""
    i = k + step
    while (i >= limit) if step < 0 else (i <= limit):
        if np.isfinite(L[i]):
            break
        i += step
    else:
        return None
    best = i
    j = i + step
    while (j >= limit) if step < 0 else (j <= limit):
        if np.isfinite(L[j]):
            if L[j] < L[best]:
                break
            best = j
        j += step
    return best


def _sdof_expected_log(ctx: PSDContext, fit: SDOFFit, k: int, p: int) -> float:
    """Natural log of the expected Welch PSD of a fitted SDOF at bin k (:class:`SDOFFit`)."""
    fe = np.abs(ctx.f[k] - ctx.props.kernel_offsets_bins * ctx.df)
    r2 = (fe / fit.f_n_Hz) ** 2
    z2 = fit.zeta**2
    s = 4 * z2 * (r2**p if p else 1.0) / ((1 - r2) ** 2 + 4 * z2 * r2)
    return float(np.log(fit.peak_psd_per_Hz * float(s @ ctx.props.kernel)
                        + fit.background_per_Hz))


class _Peaks:
    """The detected peaks of one PSD while they are classified (see :func:`analyse_peaks`)."""

    def __init__(self, ctx: PSDContext, p: int, fit_span: float, response: str,
                 threshold_dB: float, false_alarm: float) -> None:
        self.ctx, self.p, self.fit_span, self.response = ctx, p, fit_span, response
        self.threshold = float(threshold_dB) / (10 * _LOG10_E)  # natural log
        self.false_alarm = float(false_alarm)
        #: Bins of every mesh harmonic (any order), its sidebands and the shaft harmonics.
        self.line_bins = np.zeros(0, np.int64)

    def estimate(self, k: int, lo: int, hi: int, mask: np.ndarray, line: bool = False
                 ) -> ModalEstimate:
        return _estimate(self.ctx, k, lo, hi, mask, self.p, self.fit_span, self.response,
                         line=line)

    def mode_beside(self, k: int, lo: int, hi: int, mask: np.ndarray, tried: dict[int, bool],
                    known: Sequence[Peak] = ()) -> tuple[ModalEstimate, float] | None:
        """A broad, prominent mode whose maximum the line at bin k hides, fitted without it.

        ``mask`` holds the other lines; the line's own main lobe is masked here. The PSD beside
        the line, smoothed over ``SHOULDER_SMOOTHING_BINS``, is followed uphill on both sides;
        the higher maximum must have the prominence threshold on that smoothed PSD (masked bins
        bridged linearly). Returns the mode and that prominence (dB). A maximum already in
        ``tried`` (filled here) or within the half-power band of a ``known`` structural peak
        is not fitted again.
        """
        own = mask.copy()
        mask_main_lobe(self.ctx, k, own)
        L = _smoothed_log(self.ctx.psd, own, SHOULDER_SMOOTHING_BINS)
        tops = [t for t in (_uphill(L, k, -1, lo), _uphill(L, k, 1, hi)) if t is not None]
        if not tops:
            return None
        k0 = max(tops, key=lambda t: L[t])
        ok = np.isfinite(L)
        filled = np.interp(np.arange(L.size), np.flatnonzero(ok), L[ok])
        if not (filled[k0] > filled[k0 - 1] and filled[k0] >= filled[k0 + 1]):
            return None  # rising on: the maximum lies beyond the band searched
        if k0 in tried or any(q.mode is not None and abs(self.ctx.f[k0] - q.mode.f_n_Hz)
                              <= q.mode.zeta * q.mode.f_n_Hz for q in known):
            return None
        tried[k0] = True
        height = float(sps.peak_prominences(filled, [k0])[0][0])
        if not height >= self.threshold:
            return None
        mode = self.estimate(k0, lo, hi, own)
        return (mode, 10 * _LOG10_E * height) if mode.broad else None

    def two_modes(self, k: int, mode: ModalEstimate, limits: Sequence[int], mask: np.ndarray,
                  locate: Callable[[float], LocationClass], joined: Collection[int] = ()
                  ) -> tuple[TwoModeFit, tuple[int, ...]] | None:
        """Two close modes in the peak at bin k, fitted jointly, when they are clearly there.

        Tried on every peak whose single-DOF fit succeeded (the test of
        :mod:`~rigtools.analysis.two_mode_fit` keeps one mode whole); another structural or
        unresolved peak (of ``limits``) within :data:`JOINT_REACH` half-power bandwidths is a
        partner (unless in ``joined``, reported by a joint fit already): the band reaches past
        the partner peaks
        (:func:`~rigtools.analysis.two_mode_fit.joint_band`) up to the dip before the next
        peak. Returns the accepted joint fit (both modes resolved,
        :func:`~rigtools.analysis.peak_results.joint_mode_resolved`) and the partner peaks it
        covers, or None: the single-DOF fit stands, with its flags.
        """
        ctx, fit = self.ctx, mode.fit
        if not (fit.success and np.isfinite(fit.zeta)):
            return None
        reach = JOINT_REACH * 2 * fit.zeta * fit.f_n_Hz
        partners = tuple(j for j in limits if j != k and j not in joined
                         and abs(ctx.f[j] - ctx.f[k]) <= reach)
        group = (k, *partners)
        lo, hi = _band(ctx, k, [j for j in limits if j not in group], mask)
        a, b = joint_band(ctx, fit, min(group), max(group), lo, hi, self.fit_span)
        mask = mask_standing_lines(ctx, self.line_bins, a, b, mask)
        tm = fit_two_modes_in_band(ctx, a, b, mask, fit, mode.zeta_resolution, self.p,
                                   hints_Hz=[float(ctx.f[j]) for j in partners])
        if tm is None or not tm.accepted:
            return None
        if not all(joint_mode_resolved(e, locate(e.f_n_Hz))
                   for e in _joint_estimates(ctx, tm, self.response)):
            return None
        covered = tuple(j for j in limits if j != k and j not in joined and any(
            abs(ctx.f[j] - m.f_n_Hz) <= max(reach, 2 * m.zeta * m.f_n_Hz) for m in tm.modes))
        return tm, covered

    def prominence_without_lines(self, k: int, mask: np.ndarray) -> float:
        """Prominence (dB) of the peak at bin k on the PSD smoothed with the lines masked.

        The PSD is averaged over ``SHOULDER_SMOOTHING_BINS`` unmasked bins, masked bins are
        bridged linearly, and the maximum nearest k is taken: a line taller than a mode's
        top on its skirt cuts the mode's prominence on the raw PSD, not here.
        """
        L = _smoothed_log(self.ctx.psd, mask, SHOULDER_SMOOTHING_BINS)
        ok = np.isfinite(L)
        if np.count_nonzero(ok) < 3:
            return float("nan")
        filled = np.interp(np.arange(L.size), np.flatnonzero(ok), L[ok])
        k0 = int(k)
        for step in (-1, 1):  # uphill from k, either way
            while 0 < k0 + step < filled.size - 1 and filled[k0 + step] > filled[k0]:
                k0 += step
        if not (0 < k0 < filled.size - 1):
            return float("nan")
        return float(10 * _LOG10_E * sps.peak_prominences(filled, [k0])[0][0])

    def line_on(self, k: int, mode: ModalEstimate, mask: np.ndarray) -> bool:
        r"""The PSD at bin k stands above the mode fitted without it beyond the Welch scatter.

        The excess of :math:`\ln \hat S_k` over the fitted model is taken relative to the
        median excess of the unmasked bins across the mode's half-power band (so that a model
        a little low or high at the top, fitted on the flanks, does not count), and compared
        with the one-sided chi-square quantile of ``false_alarm``, Sidak-corrected for the
        :math:`N = 2\zeta f_n/\Delta f` bins of that band among which the maximum falls,
        :math:`\alpha_1 = 1 - (1-\alpha)^{1/N}`, scaled up by the ratio of the residuals'
        robust spread (1.4826 MAD) to the estimator's :math:`\sqrt{\psi'(\nu/2)}` when the
        model fits worse than the scatter; and it must be at least ``LINE_ON_MODE_MIN_DB``
        (a line that does not double the PSD at its bin hardly moves the mode's fit). A mode
        whose half-power band is narrower than ``LINE_ON_MODE_WIDTHS`` times the masked main
        lobe is not tested: a line on it cannot be told apart.
        """
        ctx = self.ctx
        n_top = mode.resolved_bins
        width = 2 * (int(np.ceil(ctx.props.mainlobe_half_width_bins)) + 1) + 1  # as masked
        if n_top < LINE_ON_MODE_WIDTHS * width:
            return False  # the mode is hardly wider than the line: not told apart
        nu = max(ctx.dof, 1.0)
        alpha1 = -np.expm1(np.log1p(-self.false_alarm) / n_top)
        threshold = float(np.log(chi2.isf(alpha1, nu) / nu) - ctx.bias)
        half = mode.zeta * mode.f_n_Hz
        top = np.flatnonzero((np.abs(ctx.f - mode.f_n_Hz) <= half) & ~mask)
        if top.size < 3:
            return False
        resid = np.array([ctx.lnP[j] - _sdof_expected_log(ctx, mode.fit, int(j), self.p)
                          for j in top])
        centre = float(np.median(resid))
        spread = 1.4826 * float(np.median(np.abs(resid - centre)))
        # the model's misfit widens the residuals beyond the estimator's own scatter
        threshold *= max(1.0, spread / np.sqrt(ctx.eps2))
        threshold = max(threshold, LINE_ON_MODE_MIN_DB / (10 * _LOG10_E))
        excess = ctx.lnP[k] - _sdof_expected_log(ctx, mode.fit, k, self.p) - centre
        return bool(excess > threshold)


def analyse_peaks(spectrum: Spectrum, *, mesh_frequency_Hz: float | None = None,
                  shaft_frequencies_Hz: Sequence[float] = (), prominence_dB: float = 6.0,
                  min_sigma: float = 5.0, false_alarm: float = FALSE_ALARM,
                  f_range_Hz: Sequence[float] | None = None,
                  max_peaks: int = 20, tolerance_Hz: float | None = None, rtol: float = 0.002,
                  max_sideband: int = 3, max_shaft_harmonic: int = 10,
                  max_mesh_order: int = MAX_MESH_ORDER,
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
        prominence above the spread between the upper and lower such quantiles. Also the
        probability that a mode's maximum is taken for a line on it (module docstring, 6).
    f_range_Hz : (float, float), optional
        Band searched (Hz); default from just above the window's main lobe at 0 Hz to
        the Nyquist frequency.
    max_peaks : int
        Peaks kept: those wider than the window's main lobe (at half their prominence) first,
        then the lines, each by prominence. Lines beyond it are not reported, but are masked
        out of the fits and searched for a mode they hide.
    tolerance_Hz : float, optional
        Absolute matching tolerance (Hz); default the window's half-power bandwidth
        (1.44 bins for Hann). The tolerance at f is ``tolerance_Hz + rtol * f``.
    rtol : float
        Relative matching tolerance (speed variation during the record).
    max_sideband, max_shaft_harmonic : int
        See :func:`~rigtools.analysis.mesh_lines.classify_frequency`.
    max_mesh_order : int
        Highest mesh harmonic taken as a mesh line (with its sidebands), default
        :data:`~rigtools.analysis.mesh_lines.MAX_MESH_ORDER` = 5: the harmonics a rig's spectrum
        shows as lines. A peak at
        a higher harmonic is classified like any other (a narrow one ``"tonal"``, a broad
        one ``"structural"``). 0: no mesh lines.
    response : {'displacement', 'velocity', 'acceleration'}
        See :func:`fit_sdof`.
    fit_span : float
        See :func:`fit_sdof`.

    Returns
    -------
    PeakAnalysis

    Notes
    -----
    Each peak is first fitted with the mesh and shaft lines near it masked out of its
    half-power search and fit, and another unexplained peak limiting the fitted band at the
    PSD minimum between the two; its kind follows (module docstring, 5). Then every line is
    masked out of the fits of the structural peaks, which are refitted between their
    neighbouring structural or unresolved peaks, and the modes that lines sit on are found
    (module docstring, 6).
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
    if isinstance(max_mesh_order, bool) or not isinstance(max_mesh_order, int | np.integer) \
            or max_mesh_order < 0:
        raise SignalError("max_mesh_order", "an integer >= 0", repr(max_mesh_order))
    max_order = int(max_mesh_order)
    sigma_dB = 10 * _LOG10_E * np.sqrt(ctx.eps2)
    threshold = max(float(prominence_dB), float(min_sigma) * sigma_dB)
    LdB = 10 * _LOG10_E * lnP
    detect_dB, spread_dB = detection_threshold_db(ctx.dof, b - a + 1, false_alarm)
    bg_dB = 10 * _LOG10_E * _background_log(ctx)
    idx, props = sps.find_peaks(LdB[a: b + 1], prominence=threshold)
    idx = idx + a
    prom = props["prominences"]
    # significant: above the local noise floor by more than noise reaches anywhere in the
    # band, or (a broad feature that lifts the running median) prominent by more than the
    # spread between the highest and lowest noise values in the band
    sig = (LdB[idx] - bg_dB[idx] >= detect_dB) | (prom >= spread_dB)
    idx, prom = idx[sig], prom[sig]
    # the quota keeps peaks wider than a line first (modes are not crowded out by lines),
    # each group by prominence; the lines beyond it are still searched for hidden modes
    mainlobe = 2 * ctx.props.mainlobe_half_width_bins
    wide = (sps.peak_widths(ctx.psd, idx, rel_height=0.5)[0] > mainlobe) if idx.size else (
        np.zeros(0, bool))
    order = np.lexsort((-prom, ~wide))
    keep = np.sort(order[: int(max_peaks)])
    beyond = np.sort(order[int(max_peaks):])
    beyond = idx[beyond][~wide[beyond]]
    idx, prom = idx[keep], prom[keep]
    atol = (ctx.props.bandwidth_3dB_bins * df) if tolerance_Hz is None else float(tolerance_Hz)
    shafts = tuple(float(s) for s in shaft_frequencies_Hz)

    def locate(fk: float) -> LocationClass:
        return classify_frequency(fk, mesh_frequency_Hz=mesh_frequency_Hz,
                                  shaft_frequencies_Hz=shafts, tolerance_Hz=atol, rtol=rtol,
                                  max_sideband=max_sideband,
                                  max_shaft_harmonic=max_shaft_harmonic,
                                  max_harmonic=max_order)

    located = []
    for k in idx:
        fk, fstd, lnk = ctx.interpolate(int(k))
        located.append((int(k), fk, fstd, lnk, locate(fk)))
    line_mask = np.zeros(n, bool)
    for k, *_, loc in located:
        if loc.kind is not None:
            mask_line(ctx, k, line_mask)
    if mesh_frequency_Hz is not None and mesh_frequency_Hz > 0:
        # mesh lines too weak to be detected as peaks still bend a nearby fit: their main
        # lobe is masked (no further: on a mode's maximum the PSD falls away from them)
        top = min(max_order, int(f[-1] // mesh_frequency_Hz))
        for fk in np.arange(1, top + 1) * mesh_frequency_Hz:
            k = round(fk / df)
            if 0 < k < n - 1 and not line_mask[k]:
                mask_main_lobe(ctx, k + int(np.argmax(lnP[k - 1: k + 2])) - 1, line_mask)
    work = _Peaks(ctx, p, fit_span, response, threshold, false_alarm)
    work.line_bins = line_bins(ctx, mesh_frequency_Hz, shafts, max_sideband,
                                max_shaft_harmonic)
    prominence = {int(k): float(v) for k, v in zip(idx, prom, strict=True)}

    # pass 1: each peak measured as found, its kind from its width
    free = [k for k, *_, loc in located if loc.kind is None]
    first_pass = []
    fitted: dict[int, tuple[int, int, np.ndarray]] = {}
    for k, fk, fstd, lnk, loc in located:
        own = np.zeros(n, bool)  # the peak itself is what is measured: never masked
        mask_line(ctx, k, own)
        mask = line_mask & ~own
        others = [j for j in free if j != k] if loc.kind is None else [
            j for j, *_ in located if j != k]
        lo, hi = _band(ctx, k, others, mask)
        mode = work.estimate(k, lo, hi, mask, line=loc.kind is not None)
        first_pass.append((k, fk, fstd, lnk, loc, mode, peak_kind(mode, loc)))
        fitted[k] = (lo, hi, mask)

    # pass 2: every line masked out of the modes beside it
    lines = [r for r in first_pass if r[6] in LINE_KINDS]
    line_masks = {}
    for r in lines:
        m_ = np.zeros(n, bool)
        mask_line(ctx, r[0], m_)
        line_masks[r[0]] = m_
    for k in beyond:  # lines beyond the quota: not reported, still masked and searched
        m_ = np.zeros(n, bool)
        mask_line(ctx, int(k), m_)
        line_masks[int(k)] = m_
    all_lines = line_mask.copy()
    for m_ in line_masks.values():
        all_lines |= m_
    limits = [r[0] for r in first_pass if r[6] not in LINE_KINDS]
    peaks: list[Peak] = []
    modes: list[Peak] = []  # structural, in the order found: direct ones first

    def line_mask_of(k: int, mask: np.ndarray) -> np.ndarray:
        out = mask.copy()
        mask_main_lobe(ctx, k, out)
        return out

    joined: set[int] = set()  # peaks reported by a joint fit of two modes

    def add_joint(k: int, prom_k: float, pair: tuple[TwoModeFit, tuple[int, ...]]) -> bool:
        tm, partners = pair
        ests = _joint_estimates(ctx, tm, response)
        others = [q for q in modes if q.index not in partners]
        if any(_known(e, others) for e in ests):
            return False  # a mode reported already: the pair is not two new modes
        joined.update((k, *partners))
        # a partner reported already (its own fit unflagged) is one of the two modes now
        modes[:] = [q for q in modes if q.index not in partners
                    or (q.mode is not None and q.mode.joint is not None)]
        near = {j: prominence[j] for j in (k, *partners)}
        near[k] = prom_k
        for est in ests:
            d, j = min((abs(ctx.f[j] - est.f_n_Hz), j) for j in near)
            prom = near[j] if d <= est.zeta * est.f_n_Hz else prom_k
            modes.append(_mode_peak(ctx, est, prom, locate))
        return True

    for k, fk, fstd, lnk, loc, mode, kind in first_pass:
        if k in joined:
            continue
        if kind != "structural":
            # a merged peak of two modes can lie off its one-mode fit's f_n: not broad
            if kind == "unresolved" and loc.kind is None:
                own = np.zeros(n, bool)
                mask_line(ctx, k, own)
                pair = work.two_modes(k, mode, limits, all_lines & ~own, locate, joined)
                if pair is not None:
                    add_joint(k, prominence[k], pair)
            continue
        own = np.zeros(n, bool)
        mask_line(ctx, k, own)
        mask = all_lines & ~own
        lo, hi = _band(ctx, k, [j for j in limits if j != k], mask)
        lo1, hi1, mask1 = fitted[k]
        if (lo, hi) != (lo1, hi1) or not np.array_equal(mask[lo:hi + 1], mask1[lo:hi + 1]):
            refit = work.estimate(k, lo, hi, mask)
            mode = refit if refit.broad else mode
        # a line on the mode stands above even the fit that includes it: only then is the
        # mode fitted without it, and the line tested against that fit
        under = None
        if work.line_on(k, mode, line_mask_of(k, mask)):
            under = work.mode_beside(k, lo, hi, mask, {})
        if under is not None and work.line_on(k, under[0], line_mask_of(k, mask)):
            # a line on the mode: the line as measured, the mode fitted without it
            peaks.append(Peak(index=k, f_Hz=fk, f_std_Hz=fstd, psd_per_Hz=float(np.exp(lnk)),
                              prominence_dB=prominence[k], kind=loc.kind or "tonal",
                              location=loc, mode=None))
            modes.append(_mode_peak(ctx, *under, locate))
            continue
        prom_k = max(prominence[k], work.prominence_without_lines(k, mask))
        pair = work.two_modes(k, mode, limits, mask, locate, joined)
        if pair is not None and add_joint(k, prom_k, pair):
            continue
        modes.append(Peak(index=k, f_Hz=fk, f_std_Hz=fstd, psd_per_Hz=float(np.exp(lnk)),
                          prominence_dB=prom_k, kind=kind, location=loc, mode=mode))
    for k, fk, fstd, lnk, loc, mode, kind in first_pass:
        if kind == "structural" or k in joined:
            continue
        peaks.append(Peak(index=k, f_Hz=fk, f_std_Hz=fstd, psd_per_Hz=float(np.exp(lnk)),
                          prominence_dB=prominence[k], kind=kind, location=loc, mode=mode))
    tried: dict[int, bool] = {}  # tops of the smoothed PSD already fitted
    for k in sorted(line_masks):
        mask = all_lines & ~line_masks[k]
        lo, hi = _band(ctx, k, [j for j in limits if j != k], mask)
        under = work.mode_beside(k, lo, hi, mask, tried, modes)
        if under is not None and not _known(under[0], modes):
            modes.append(_mode_peak(ctx, *under, locate))
    modes.sort(key=lambda q: q.f_Hz)
    # the lines within a mode's half-power band belong to it
    for i, q in enumerate(peaks):
        if q.kind == "unresolved" and q.mode is not None and q.mode.broad:
            continue
        held = [(abs(q.f_Hz - m.mode.f_n_Hz), j) for j, m in enumerate(modes)
                if m.mode is not None
                and abs(q.f_Hz - m.mode.f_n_Hz) <= m.mode.zeta * m.mode.f_n_Hz]
        if held:
            peaks[i] = replace(q, on_mode=min(held)[1])
    out = sorted([*peaks, *modes], key=lambda q: q.f_Hz)
    return PeakAnalysis(peaks=tuple(out), mesh_frequency_Hz=mesh_frequency_Hz,
                        shaft_frequencies_Hz=shafts, tolerance_Hz=atol, rtol=float(rtol),
                        threshold_dB=threshold, detection_threshold_dB=detect_dB,
                        false_alarm=float(false_alarm), max_mesh_order=max_order)


def _joint_estimates(ctx: PSDContext, tm: TwoModeFit, response: str
                     ) -> tuple[ModalEstimate, ModalEstimate]:
    """The two modes of an accepted joint fit as modal estimates (``f_peak_Hz`` = f_n)."""
    nan = float("nan")
    hp = HalfPower(nan, nan, nan, nan, message="not measured: the peak holds two modes, "
                   "fitted jointly")
    out = []
    for i, fit in enumerate(tm.modes):
        other = tm.modes[1 - i]
        at = np.array([fit.f_n_Hz])
        psd = (fit.peak_psd_per_Hz + fit.background_per_Hz + other.peak_psd_per_Hz
               * float(sdof_shape(at, other.f_n_Hz, other.zeta, RESPONSE_POWER[response])[0][0]))
        out.append(ModalEstimate(
            f_n_Hz=fit.f_n_Hz, f_n_std_Hz=fit.f_n_std_Hz, zeta=fit.zeta, zeta_std=fit.zeta_std,
            zeta_half_power=nan, zeta_half_power_std=nan, f_peak_Hz=fit.f_n_Hz,
            f_peak_std_Hz=fit.f_n_std_Hz, psd_peak_per_Hz=float(psd),
            zeta_resolution=zeta_resolution(ctx, fit.f_n_Hz), fit=fit, half_power=hp,
            response=response, dof=ctx.dof, resolution_Hz=ctx.df,
            mainlobe_half_width_Hz=ctx.props.mainlobe_half_width_bins * ctx.df, joint=tm))
    return out[0], out[1]


def _known(mode: ModalEstimate, modes: Sequence[Peak]) -> bool:
    """Another structural peak already reports this mode (within either's half-power band)."""
    for q in modes:
        m = q.mode
        if m is None:
            continue
        d = abs(m.f_n_Hz - mode.f_n_Hz)
        if d <= max(m.zeta * m.f_n_Hz, mode.zeta * mode.f_n_Hz):
            return True
    return False


def _mode_peak(ctx: PSDContext, mode: ModalEstimate, prominence_dB: float,
               locate: Callable[[float], LocationClass]) -> Peak:
    """A structural peak for a mode found beside a line: at its f_n (fitted)."""
    k = int(np.clip(round(mode.f_n_Hz / ctx.df), 1, ctx.f.size - 2))
    return Peak(index=k, f_Hz=mode.f_n_Hz, f_std_Hz=mode.f_n_std_Hz,
                psd_per_Hz=mode.fit.peak_psd_per_Hz + mode.fit.background_per_Hz,
                prominence_dB=prominence_dB, kind="structural",
                location=locate(mode.f_n_Hz), mode=mode)


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
