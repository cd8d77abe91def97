r"""Damping of one PSD peak: half-power bandwidth and a single-DOF fit, with uncertainties.

The estimators behind :mod:`rigtools.analysis.peaks`: :func:`half_power_damping` and
:func:`fit_sdof`, over the band-limited forms :func:`half_power_in_band` and
:func:`fit_sdof_in_band` on a :class:`PSDContext`, which the peak analysis calls with its own
bands and masks.

Notes
-----
**Model.** Around a peak the expected Welch estimate is the SDOF response PSD convolved with
the window's spectral window, plus a background (:class:`SDOFFit`); the response (p = 0, 1,
2 for displacement, velocity, acceleration, :data:`RESPONSE_POWER`) must be the one
measured: an accelerance read as a receptance moves f_n by about a percent at zeta = 0.03
(issue 17). The accelerance's mass-line floor (:math:`4\zeta^2 S_0` above resonance) and the
receptance's stiffness line below are part of the shape. The model is fitted to the log PSD
by least squares, where the Welch scatter is additive and of known variance
:math:`\psi'(\nu/2)` (Percival and Walden 1993, Eq. 292b).

**The background is a free nuisance on a linear scale.** At 20 dB SNR the band fitted
(five half-power half-widths each side) ends some 20 dB above the noise floor, which it
cannot then resolve (the linearised uncertainty of ln B is about 7). Fitted as ln B (B > 0)
the background sits at its boundary half the time; the estimate of zeta, which is correlated
with it (-0.7), then comes out low by half the boundary's pull, 0.25 standard errors, and
scatters 15-20 % less than the linearised covariance says: both are what a normal estimate
truncated at a boundary gives (Self and Liang 1987), and were measured on 200 records.
Fitted as B, free to fall below zero by its uncertainty, the estimator stays linear in the
nuisance, unbiased, and its covariance is the linearised one.

**Covariance.** The sandwich :math:`(J^TJ)^{-1} J^T \Sigma J (J^TJ)^{-1}` with
:math:`\Sigma` the covariance of the log estimates of the *fitted* spectrum
(:meth:`PSDContext.log_covariance`): by Isserlis' theorem from the window's transform, the
spectrum and the overlap of the averaged windows. For a white spectrum it is
:math:`\psi'(\nu/2)` times the correlation 1, 0.459, 0.039 of neighbouring bins (Hann, 50 %
overlap); where the PSD changes within the window's main lobe (a mode a few bins wide) the
correlation of neighbouring bins rises to 0.6 at the peak, which the local-white form
misses (zeta's scatter was then 20 % above its stated uncertainty). The covariance is
scaled by the reduced chi-square when that exceeds 1.

**Flags** (:data:`FIT_FLAGS`) say where the estimate cannot be trusted, instead of
inflating its uncertainty by rules of thumb: ``misfit`` when the reduced chi-square exceeds
what a correct model reaches with probability :data:`MISFIT_FALSE_ALARM`
(:func:`misfit_threshold`): a second mode in the band, an unmasked line, another response;
``band_too_narrow`` when the band reaches fewer than :data:`MIN_COVER` half-power half-widths
from f_n on a side (at one half-width zeta came out 4.6 % low, half its standard error; at
two, unbiased); ``unresolved`` when the half-power band is narrower than the window's 3 dB
bandwidth (:data:`MIN_RESOLVED_WIDTH`); ``at_lower_bound`` (a tone) and ``fit_failed``; and
``joint_fit`` on each of two close modes fitted together
(:mod:`rigtools.analysis.two_mode_fit`, set there).

References
----------
.. [1] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
       Cambridge University Press, 1993, Sec. 6.17 and Eq. (292b).
.. [2] S. G. Self and K.-Y. Liang, "Asymptotic properties of maximum likelihood estimators
       and likelihood ratio tests under nonstandard conditions", J. Am. Stat. Assoc. 82(398),
       605-610, 1987.
.. [3] D. J. Ewins, *Modal Testing: Theory, Practice and Application*, 2nd ed., Research
       Studies Press, 2000, Sec. 4.3 (half-power point method).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Final

import numpy as np
from scipy.optimize import least_squares
from scipy.special import polygamma
from scipy.stats import chi2

from rigtools.analysis.signal_checks import RESPONSE_POWER, Response, check_response
from rigtools.analysis.spectra import Spectrum, log_chi2_stats
from rigtools.errors import SignalError

__all__ = [
    "FIT_FLAGS",
    "HalfPower",
    "PSDContext",
    "SDOFFit",
    "fit_sdof",
    "fit_sdof_in_band",
    "half_power_damping",
    "half_power_in_band",
    "mask_line",
    "misfit_threshold",
    "not_fitted",
    "sdof_shape",
    "zeta_resolution",
]

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
#: Probability that a correct SDOF model is flagged ``misfit`` (:func:`misfit_threshold`).
MISFIT_FALSE_ALARM = 1e-3
#: The fitted background may fall below zero by this fraction of the lowest PSD in the band.
BACKGROUND_BELOW_ZERO = 0.25
#: Least reach of the fitted band from the peak on either side, in half-power half-widths,
#: for the estimate to be trusted (``band_too_narrow`` below).
MIN_COVER = 2.0
#: Least width of the fitted half-power band, 2 zeta f_n, in multiples of the window's 3 dB
#: bandwidth (``unresolved`` below): narrower, the peak's width is mostly the window's own.
MIN_RESOLVED_WIDTH = 1.0
#: What each flag of :attr:`SDOFFit.flags` means.
FIT_FLAGS: Final[dict[str, str]] = {
    "fit_failed": "the least-squares fit did not converge",
    "at_lower_bound": "damping at its lower bound: a tone, narrower than the resolution",
    "misfit": "the residuals exceed the estimator's scatter beyond chance: the band holds "
              "more than one SDOF response on a white background",
    "band_too_narrow": "the band fitted reaches too few half-power half-widths from the peak",
    "unresolved": "the half-power band is narrower than the window's 3 dB bandwidth",
    "joint_fit": "fitted jointly with a mode within two half-power bandwidths",
}
#: Least half-width of the fitted band: bins, and multiples of the window's 3 dB bandwidth.
MIN_FIT_HALF_BINS = 16
MIN_FIT_HALF_RES = 8.0


_RESPONSE_NAME: Final[dict[int, str]] = {p: name for name, p in RESPONSE_POWER.items()}

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
        B (unit^2/Hz): fitted free of a bound (module notes), so below zero by up to its
        uncertainty when the band does not reach the noise floor.
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
        Empty, or what went wrong and why each flag was set.
    chi2 : float
        Weighted residual sum of squares :math:`\sum_k r_k^2 / \psi'(\nu/2)` of the log
        PSD (``redchi2`` times the residual degrees of freedom): the criterion by which
        responses are compared on the same bins (:func:`fit_sdof_responses`).
    response : str
        The SDOF response fitted (``"displacement"``, ``"velocity"``, ``"acceleration"``).
    flags : tuple of str
        Why the estimate cannot be trusted, empty when it can: names from
        :data:`FIT_FLAGS` (a caller may add its own, e.g. ``"response_guessed"``).
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
    chi2: float = float("nan")
    response: str = ""
    flags: tuple[str, ...] = ()

    @property
    def trusted(self) -> bool:
        """Fitted, with no flag: the estimate and its uncertainty can be used as they are."""
        return bool(self.success and not self.flags)


# --------------------------------------------------------------------------------------------
# peak estimators


class PSDContext:
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
        # correlation of neighbouring bins of the averaged estimate: the window's own and
        # that of overlapping windows (WindowProperties.averaged_bin_correlation)
        account = spectrum.account
        self.noverlap = int(spectrum.noverlap)
        self.n_windows = int(np.asarray(account.n_windows))
        self.n_segments = int(np.asarray(account.n_segments))
        self.rho2 = self.props.averaged_bin_correlation(self.noverlap, self.n_windows,
                                                        self.n_segments)
        #: Excess kurtosis of the log of a chi-square_nu / nu variable,
        #: psi'''(nu/2) / psi'(nu/2)^2 (for the null distribution of the residuals).
        self.log_kurtosis = float(polygamma(3, 0.5 * max(self.dof, 1.0)) / self.eps2**2)

    def log_covariance(self, psd_of_bin: Callable[[np.ndarray], np.ndarray], idx: np.ndarray
                       ) -> np.ndarray:
        r"""Covariance of the log PSD estimates at bins ``idx`` if the PSD were ``psd_of_bin``.

        :meth:`~rigtools.analysis.spectral_window.WindowProperties.welch_covariance` (relative
        covariance of the Welch estimates, :math:`2/\nu` on the diagonal for a white
        spectrum), scaled by :math:`\psi'(\nu/2)\,\nu/2` so that a white spectrum gives the
        log variance :attr:`eps2` and the correlation :attr:`rho2`.
        """
        V = self.props.welch_covariance(psd_of_bin, idx, self.noverlap, self.n_windows,
                                        self.n_segments)
        return V * (self.eps2 * max(self.dof, 1.0) / 2.0)

    def lag_matrix(self, idx: np.ndarray) -> np.ndarray:
        """Correlation matrix of the PSD estimates at bins ``idx`` (from :attr:`rho2`)."""
        lag = np.abs(idx[:, None] - idx[None, :])
        return np.where(lag < self.rho2.size, self.rho2[np.minimum(lag, self.rho2.size - 1)],
                        0.0)

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


def _smoothed_log(ctx: PSDContext, mask: np.ndarray, m: int) -> np.ndarray:
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


def _half_power_pass(ctx: PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray, m: int
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


def half_power_in_band(ctx: PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray
                       ) -> HalfPower:
    """Half-power bandwidth of the peak at bin ``k0``, searched within bins ``[lo, hi]``.

    Found on the PSD smoothed over about a sixth of the bandwidth; bins where ``mask`` is True
    are skipped.
    """
    raw = _half_power_pass(ctx, k0, lo, hi, mask, 1)
    if not np.isfinite(raw.zeta):
        return raw
    m = round((raw.f_hi_Hz - raw.f_lo_Hz) / ctx.df / HALF_POWER_SMOOTHING)
    m = min(m + 1 - m % 2, 31)  # odd, at most 31 bins
    if m <= 1:
        return raw
    smooth = _half_power_pass(ctx, k0, lo, hi, mask, m)
    return smooth if np.isfinite(smooth.zeta) else raw


def sdof_shape(fe: np.ndarray, f_n: float, zeta: float, p: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""SDOF PSD shape and its derivatives with respect to :math:`\ln f_n` and :math:`\ln\zeta`.

    Parameters
    ----------
    fe : numpy.ndarray
        Frequencies (Hz), any shape.
    f_n : float
        Natural frequency (Hz).
    zeta : float
        Damping ratio.
    p : int
        Response power (0, 1, 2: displacement, velocity, acceleration).

    Returns
    -------
    s, ds_f, ds_z : numpy.ndarray
        :math:`s = (2\zeta)^2 r^{2p} / ((1 - r^2)^2 + (2\zeta r)^2)`, :math:`r = f/f_n`
        (1 at :math:`f_n`), and its derivatives.
    """
    r2 = (fe / f_n) ** 2
    z2 = zeta * zeta
    D = (1 - r2) ** 2 + 4 * z2 * r2
    s = 4 * z2 * (r2**p if p else 1.0) / D
    ds_f = s * (-2 * p - (4 * r2 * (1 - r2) - 8 * z2 * r2) / D)
    ds_z = s * (2 - 8 * z2 * r2 / D)
    return s, ds_f, ds_z


def fit_sdof_in_band(ctx: PSDContext, k0: int, lo: int, hi: int, mask: np.ndarray,
                     zeta0: float, zeta_res: float, p: int, fit_span: float) -> SDOFFit:
    """Fit the SDOF model to the peak at bin ``k0`` within bins ``[lo, hi]``, unmasked bins.

    ``zeta0`` is the starting damping (the half-power one), ``zeta_res`` the resolution
    equivalent, ``p`` the response power (:data:`~rigtools.analysis.signal_checks.RESPONSE_POWER`)
    and ``fit_span`` the half-width of the band in half-power half-bandwidths.
    """
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
                       f"{idx.size} bins around the peak: too few to fit (need 8)",
                       response=_RESPONSE_NAME[p], flags=("fit_failed",))
    y = lnP[idx] - ctx.bias
    kern = ctx.props.kernel
    fe = np.abs(f[idx][:, None] - ctx.props.kernel_offsets_bins[None, :] * df)
    zmin = ZETA_MIN_FRACTION * zeta_res
    z0 = float(np.clip(z0, zmin * 1.5, 0.4))
    # parameters: ln f_n, ln zeta, ln W (W = pi zeta f_n S_0, the power under the peak) and
    # beta = B / B_ref, the background on a linear scale and free to go below zero by its
    # uncertainty (see the module notes: a nuisance held at a bound biases zeta)
    lnW0 = ln_pk + np.log(np.pi * z0 * f_pk)
    B_ref = float(np.exp(min(float(np.percentile(lnP[idx], 5)), ln_pk - 0.7)))
    P_min = float(np.exp(np.min(lnP[idx])))
    theta0 = np.array([np.log(f_pk), np.log(z0), lnW0, 1.0])
    lnW_pk = ln_pk + np.log(ctx.props.enbw_bins * df)  # a tone's power
    lower = np.array([np.log(max(f[a], 1e-12)), np.log(zmin), lnW_pk - 8,
                      -BACKGROUND_BELOW_ZERO * P_min / B_ref])
    upper = np.array([np.log(f[b]), np.log(0.5), lnW_pk + 12, np.exp(ln_pk) / B_ref])
    theta0 = np.clip(theta0, lower + 1e-6, upper - 1e-6)
    M_floor = 1e-6 * P_min  # keeps the log defined while an iterate overshoots
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = th.tobytes()
        hit = cache.get(key)
        if hit is not None:
            return hit
        f_n, zeta, W = np.exp(th[:3])
        c = W / (np.pi * zeta * f_n)
        s, ds_f, ds_z = sdof_shape(fe, f_n, zeta, p)
        Sk, Sf, Sz = s @ kern, ds_f @ kern, ds_z @ kern
        M = np.maximum(c * Sk + th[3] * B_ref, M_floor)
        dM = np.column_stack([c * (Sf - Sk), c * (Sz - Sk), c * Sk, np.full_like(Sk, B_ref)])
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
                       f"fit failed: {err}", response=_RESPONSE_NAME[p], flags=("fit_failed",))
    th = res.x
    J = res.jac
    n, npar = J.shape
    f_n, zeta, W = (float(v) for v in np.exp(th[:3]))
    c_fit, B_fit = W / (np.pi * zeta * f_n), float(th[3] * B_ref)

    def psd_of_bin(g: np.ndarray) -> np.ndarray:  # the fitted PSD, before the window
        return c_fit * sdof_shape(np.abs(g) * df, f_n, zeta, p)[0] + B_fit

    # covariance of the log estimates for the fitted spectrum (the correlation of
    # neighbouring bins depends on how the PSD changes within the window's main lobe)
    Sigma = ctx.log_covariance(psd_of_bin, idx)
    A = np.linalg.pinv(J.T @ J)
    cov = A @ (J.T @ Sigma @ J) @ A
    chi2_w = float(np.sum(res.fun**2) / ctx.eps2)
    redchi2 = chi2_w / max(n - npar, 1)
    cov *= max(1.0, redchi2)
    hw = max(zeta * f_n / df, 0.5)  # half-power half-width (bins)
    k_n = f_n / df  # the band's reach about the fitted f_n, in half-power half-widths
    cover = min(k_n - a, b - k_n) / hw
    cov *= max(1.0, 2.0 * MIN_FIT_HALF_BINS / max(n, 1))
    at_low = bool(th[1] <= lower[1] + 0.05)  # within 5 % of the bound
    ok = bool(res.status > 0)
    why: dict[str, str] = {}
    if not ok:
        why["fit_failed"] = str(res.message)
    if at_low:
        why["at_lower_bound"] = ("damping at its lower bound: narrower than the resolution "
                                 "shows (a tone)")
    threshold = misfit_threshold(ctx, Sigma / ctx.eps2, npar)
    if redchi2 > threshold:
        why["misfit"] = (f"reduced chi-square {redchi2:.2f} above {threshold:.2f} (false "
                         f"alarm {MISFIT_FALSE_ALARM:g}): the band holds more than one SDOF "
                         "response and a white background (another mode, an unmasked line, "
                         "another response)")
    if cover < MIN_COVER:
        why["band_too_narrow"] = (f"the band fitted reaches {cover:.1f} half-power "
                                  f"half-widths from the peak on one side (need {MIN_COVER:g})")
    width = 2 * zeta * f_n / df / ctx.props.bandwidth_3dB_bins
    if not at_low and width < MIN_RESOLVED_WIDTH:
        why["unresolved"] = (f"half-power band {width:.2f} times the window's 3 dB bandwidth "
                             f"(need {MIN_RESOLVED_WIDTH:g}): the peak is as wide as the "
                             "window makes a tone")
    return SDOFFit(
        f_n_Hz=f_n, f_n_std_Hz=f_n * float(np.sqrt(max(cov[0, 0], 0.0))),
        zeta=zeta, zeta_std=zeta * float(np.sqrt(max(cov[1, 1], 0.0))),
        peak_psd_per_Hz=c_fit, background_per_Hz=B_fit, band_Hz=band, n_bins=int(n),
        redchi2=redchi2, success=ok, at_lower_bound=at_low, message="; ".join(why.values()),
        chi2=chi2_w, response=_RESPONSE_NAME[p], flags=tuple(why))


def misfit_threshold(ctx: PSDContext, R: np.ndarray, n_params: int,
                     false_alarm: float | None = None) -> float:
    r"""The reduced chi-square a correct model exceeds with probability ``false_alarm``.

    The log-PSD residuals of a correct model are correlated (R, :meth:`PSDContext.lag_matrix`)
    nearly Gaussian variables of variance :math:`\psi'(\nu/2)`; their weighted sum of squares
    is approximated by a scaled chi-square with the same mean and variance (Satterthwaite):

    .. math:: \chi^2_w \approx g\,\chi^2_h, \qquad h = \frac{n - p}{s_R (1 + \kappa/2)},
              \qquad s_R = \frac{1}{n}\sum_{ij} R_{ij}^2,

    :math:`\kappa` the excess kurtosis of :math:`\ln \chi^2_\nu`
    (:math:`\psi^{(3)}(\nu/2)/\psi'(\nu/2)^2`); the reduced chi-square is then
    :math:`\chi^2_h / h` and the threshold is its upper ``false_alarm`` quantile.

    Parameters
    ----------
    ctx : PSDContext
    R : numpy.ndarray
        Correlation matrix of the bins fitted, shape ``(n, n)``.
    n_params : int
        Parameters fitted.
    false_alarm : float, optional
        Default :data:`MISFIT_FALSE_ALARM`.

    Returns
    -------
    float
    """
    alpha = MISFIT_FALSE_ALARM if false_alarm is None else float(false_alarm)
    n = R.shape[0]
    s_r = float(np.sum(R * R)) / max(n, 1)
    h = max(n - n_params, 1) / (s_r * (1.0 + 0.5 * ctx.log_kurtosis))
    return float(chi2.isf(alpha, h) / h)


def _start_zetas(ctx: PSDContext, k0: int, a: int, b: int, mask: np.ndarray
                 ) -> list[float]:
    """Starting dampings from the half-power width of the PSD smoothed over 3, 7, 15 bins."""
    out = []
    for m in (3, 7, 15):
        hp = _half_power_pass(ctx, k0, a, b, mask, m)
        if np.isfinite(hp.zeta) and hp.zeta > 0:
            out.append(float(hp.zeta))
    return out


def not_fitted(why: str) -> SDOFFit:
    """An :class:`SDOFFit` that was not attempted, saying why."""
    nan = float("nan")
    return SDOFFit(nan, nan, nan, nan, nan, nan, (nan, nan), 0, nan, False, False, why)


def zeta_resolution(ctx: PSDContext, f_Hz: float) -> float:
    r"""The damping a pure tone at ``f_Hz`` appears to have, :math:`B_{3dB} / (2 f)`."""
    return ctx.props.bandwidth_3dB_bins * ctx.df / (2 * max(f_Hz, ctx.df))


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
    ctx = PSDContext(spectrum)
    k0 = _local_max(ctx, f_Hz)
    return half_power_in_band(ctx, k0, 1, ctx.f.size - 2, np.zeros(ctx.f.size, bool))


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
        Half-width of the fitted band in half-power half-bandwidths (at least
        ``MIN_FIT_HALF_BINS`` bins and ``MIN_FIT_HALF_RES`` window 3 dB bandwidths).
    exclude_Hz : iterable of float
        Frequencies of lines to mask out of the fit (a few bins each side).

    Returns
    -------
    SDOFFit
        With ``flags`` naming why the estimate cannot be trusted, if it cannot (a second mode
        or a line in the band, the wrong response, a band too narrow; module notes).

    Examples
    --------
    A mode at 2843 Hz, zeta = 0.03, measured as acceleration (the white force's response
    through the continuous accelerance, made per FFT bin), read over 20 s at 25.6 kHz:

    >>> fs, n = 25600.0, 512_000
    >>> f = np.fft.rfftfreq(n, 1 / fs)
    >>> r = f / 2843.0
    >>> h = -(r**2) / (1 - r**2 + 2j * 0.03 * r)  # accelerance, up to its scale
    >>> force = np.fft.rfft(np.random.default_rng(0).normal(size=n))
    >>> x = np.fft.irfft(force * h, n)
    >>> from rigtools.analysis.welch import welch_psd
    >>> fit = fit_sdof(welch_psd(x, fs), 2843.0, response="acceleration")
    >>> abs(fit.f_n_Hz / 2843.0 - 1) < 0.001, abs(fit.zeta / 0.03 - 1) < 0.05, fit.flags
    (True, True, ())
    >>> fit_sdof(welch_psd(x, fs), 2843.0, response="displacement").flags
    ('misfit',)
    """
    p = check_response(response)
    ctx = PSDContext(spectrum)
    k0 = _local_max(ctx, f_Hz)
    mask = np.zeros(ctx.f.size, bool)
    for fx in exclude_Hz:
        mask_line(ctx, round(fx / ctx.df), mask)
    mask[k0] = False
    hp = half_power_in_band(ctx, k0, 1, ctx.f.size - 2, mask)
    zres = zeta_resolution(ctx, ctx.f[k0])
    return fit_sdof_in_band(ctx, k0, 1, ctx.f.size - 2, mask, hp.zeta, zres, p, fit_span)


def _local_max(ctx: PSDContext, f_Hz: float) -> int:
    k = round(float(f_Hz) / ctx.df)
    if not 1 <= k <= ctx.f.size - 2:
        raise SignalError("f_Hz", f"inside (0, {ctx.f[-1]:g}) Hz", repr(f_Hz))
    a, b = max(1, k - 2), min(ctx.f.size - 2, k + 2)
    return a + int(np.argmax(ctx.lnP[a: b + 1]))


def mask_line(ctx: PSDContext, k: int, mask: np.ndarray) -> None:
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
