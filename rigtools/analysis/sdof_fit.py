"""Damping of one PSD peak: half-power bandwidth and a single-DOF fit, with uncertainties.

The estimators behind :mod:`rigtools.analysis.peaks` (see its docstring for the method and
references): :func:`half_power_damping` and :func:`fit_sdof`, over the band-limited forms
:func:`half_power_in_band` and :func:`fit_sdof_in_band` on a :class:`PSDContext`, which the
peak analysis calls with its own bands and masks.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.special import polygamma
from scipy.stats import chi2

from rigtools.analysis.signal_checks import RESPONSE_POWER, Response, check_response
from rigtools.analysis.spectra import Spectrum, log_chi2_stats
from rigtools.errors import SignalError

__all__ = [
    "HalfPower",
    "PSDContext",
    "SDOFFit",
    "fit_sdof",
    "fit_sdof_in_band",
    "half_power_damping",
    "half_power_in_band",
    "mask_line",
    "not_fitted",
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
#: Least half-width of the fitted band: bins, and multiples of the window's 3 dB bandwidth.
MIN_FIT_HALF_BINS = 16
MIN_FIT_HALF_RES = 8.0


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
        self.rho2 = self.props.averaged_bin_correlation(
            spectrum.noverlap, int(np.asarray(account.n_windows)),
            int(np.asarray(account.n_segments)))
        #: Excess kurtosis of the log of a chi-square_nu / nu variable,
        #: psi'''(nu/2) / psi'(nu/2)^2 (for the null distribution of the residuals).
        self.log_kurtosis = float(polygamma(3, 0.5 * max(self.dof, 1.0)) / self.eps2**2)

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
        Half-width of the fitted band in half-power half-bandwidths (at least 8 bins).
    exclude_Hz : iterable of float
        Frequencies of lines to mask out of the fit (a few bins each side).

    Returns
    -------
    SDOFFit
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
