r"""Two close modes in one PSD peak: a joint fit, and the test that says whether it is needed.

When two modes lie within one or two half-power bandwidths of each other the peak search sees
one merged peak (or two peaks whose fitted bands end at the dip between them), and the
single-DOF fit of :mod:`rigtools.analysis.sdof_fit` is flagged ``misfit`` (or
``band_too_narrow``): the weaker mode is lost and the other one is biased. Here the band is
fitted again with *two* SDOF responses, and the two-mode model is kept only when the data
ask for it.

Notes
-----
**Model.** The same expected Welch estimate as the single-DOF fit (:class:`SDOFFit`), with
two modes of the same response type (p = 0, 1, 2 for displacement, velocity, acceleration)
through the same spectral window :math:`K_m` and one linear background B:

.. math:: E[\hat S(f_k)] = \sum_m K_m \sum_{i=1}^{2} S_i \frac{(2\zeta_i)^2 r_{im}^{2p}}
          {(1 - r_{im}^2)^2 + (2\zeta_i r_{im})^2} + B, \qquad
          r_{im} = (f_k - m\delta)/f_i,

seven parameters :math:`\ln f_i` (Hz), :math:`\ln\zeta_i`, :math:`\ln W_i`
(:math:`W_i = \pi\zeta_i f_i S_i`, the mean square under mode i, unit^2) and :math:`B/B_\text{ref}`,
fitted to the log PSD by least squares (:func:`scipy.optimize.least_squares`), with the
sandwich covariance :math:`(J^TJ)^{-1}J^T\Sigma J(J^TJ)^{-1}`, :math:`\Sigma` the covariance
of the log estimates of the fitted two-mode spectrum (:meth:`PSDContext.log_covariance`),
scaled up by the reduced chi-square when it exceeds 1: all exactly as for one mode. The two
responses add in power: two uncorrelated sources (a gear-mesh mode and a housing mode
excited by different forces). Two modes of one structure under one force add as complex
FRFs and interfere (the PSD dips between them below the sum); the two-mode model then
misfits and is not taken, and the single-DOF fit keeps its flags. Start
values: the one-mode fit on the same bins, and the second mode on a grid over
:math:`f_1 \pm 3` half-power bandwidths (:data:`GRID_BANDWIDTHS`), plus the largest bump of
the one-mode residuals and any other peak the search found in the band; the best few starts
are refined.

**The test.** Both models are fitted on the same bins. With :math:`\chi^2_w = \sum_k r_k^2 /
\psi'(\nu/2)` the weighted residual sum of squares of the log PSD, the reduction
:math:`\Delta = \chi^2_{w,1} - \chi^2_{w,2}` is, for a linearised model and Gaussian log
estimates of covariance :math:`\psi'(\nu/2) R`, the quadratic form
:math:`e^T (P_2 - P_1) e` (:math:`P_j` the projection on the columns of model j's
Jacobian), whose mean and variance are

.. math:: \mu = \operatorname{tr}(DR), \qquad \sigma^2 = 2\operatorname{tr}(DRDR)(1 + \kappa/2),
          \qquad D = P_2 - P_1,

:math:`\kappa` the excess kurtosis of :math:`\ln\chi^2_\nu` (as in
:func:`~rigtools.analysis.sdof_fit.misfit_threshold`); approximated by a scaled chi-square
:math:`g\chi^2_h` with that mean and variance (Satterthwaite; about three degrees of freedom,
scaled by the correlation of neighbouring Welch bins). The two-mode model is taken when
:math:`\Delta` exceeds the upper :data:`JOINT_FALSE_ALARM` (:math:`10^{-3}`, as
:data:`~rigtools.analysis.sdof_fit.MISFIT_FALSE_ALARM`) quantile of that distribution, the two
natural frequencies are apart by more than :data:`SEPARATION_SIGMA` = 3 standard uncertainties
of their difference (from the joint covariance, with the correlation of the two) and by at most
:data:`MAX_SEPARATION` = 2.5 mean half-power bandwidths :math:`\zeta_1 f_1 + \zeta_2 f_2` (two
modes of one peak; the brief's widest case, 2 bandwidths of a mode with zeta 0.03 beside one of
0.02, is 2.3), and the two-mode model itself fits (its reduced chi-square below the ``misfit``
threshold), and each mode lies :data:`MIN_INSIDE` half-power half-widths inside the band (a
"mode" at the band's edge is the rise to the next peak). The second mode's frequency is not
defined when its amplitude is zero, so the reference distribution holds for a second mode that
is there, not for the search over its frequency under one mode alone (Davies 1987): the
threshold is then a guide, not an exact rate. Measured on one mode alone (2843 Hz, zeta 0.03,
20 dB, 3 s and 20 s records, both routes of ``tests/analysis/modal_signals.py``, the three
responses, 80 seeds) the largest reduction reached 0.82 of the threshold;
``tests/analysis/test_two_mode_fit.py`` asserts at most 2 % false splits over 200 seeds. The
test is what keeps one mode whole: the joint fit is tried on every structural peak (and on
every unresolved peak that is no line: a merged pair's maximum lies off its single-DOF fit's
f_n, which makes it unresolved), because the single-DOF fit's reduced chi-square, a sum over
the whole band, misses a weaker mode on a taller one's skirt that the test finds (a 3:1 pair
one bandwidth apart: split in 8 of 8 seeds by the test, flagged ``misfit`` in 4). A joint fit
costs 0.2-0.4 s CPU per peak (20 s at 25.6 kHz, nperseg 4096).

References
----------
.. [1] R. B. Davies, "Hypothesis testing when a nuisance parameter is present only under
       the alternative", Biometrika 74(1), 33-43, 1987.
.. [2] F. E. Satterthwaite, "An approximate distribution of estimates of variance
       components", Biometrics Bulletin 2(6), 110-114, 1946.
.. [3] D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*,
       Cambridge University Press, 1993, Sec. 6.17 and Eq. (292b).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from scipy.optimize import OptimizeResult, least_squares
from scipy.stats import chi2

from rigtools.analysis.sdof_fit import (
    BACKGROUND_BELOW_ZERO,
    MAX_FIT_EVALUATIONS,
    MIN_COVER,
    MIN_FIT_HALF_BINS,
    MIN_RESOLVED_WIDTH,
    MISFIT_FALSE_ALARM,
    ZETA_MIN_FRACTION,
    PSDContext,
    SDOFFit,
    misfit_threshold,
    sdof_shape,
)
from rigtools.analysis.signal_checks import RESPONSE_POWER

__all__ = [
    "GRID_BANDWIDTHS",
    "JOINT_FALSE_ALARM",
    "SEPARATION_SIGMA",
    "TwoModeFit",
    "fit_two_modes_in_band",
    "joint_band",
]

#: Probability that the chi-square reduction of a needless second mode exceeds the threshold
#: of the test (module notes).
JOINT_FALSE_ALARM: Final[float] = 1e-3
#: The two natural frequencies must be apart by more than this many standard uncertainties of
#: their difference.
SEPARATION_SIGMA: Final[float] = 3.0
#: The two modes must lie within this many of their mean half-power bandwidths,
#: :math:`\zeta_1 f_1 + \zeta_2 f_2`, of each other: further apart they are two peaks, each
#: fitted on its own (and a narrow feature two bandwidths off a mode's skirt, such as a line
#: with its sidebands, is not taken for a second mode of its peak).
MAX_SEPARATION: Final[float] = 2.5
#: Each mode's f_n must lie this many of its half-power half-widths inside the band fitted.
MIN_INSIDE: Final[float] = 1.0
#: Offsets of the second mode's starting frequency from the one-mode fit, in half-power
#: bandwidths :math:`2\zeta f` of a mode of the starting damping (module notes).
GRID_BANDWIDTHS: Final[tuple[float, ...]] = (-3.0, -1.5, -0.75, 0.75, 1.5, 3.0)
#: Starts refined to convergence after a short pass over all of them.
REFINED_STARTS: Final[int] = 2
#: Evaluations of the short pass per start.
SCREEN_EVALUATIONS: Final[int] = 15
#: Reach of the band beyond the outer peak, in half-power half-widths of the one-mode fit.
JOINT_SPAN: Final[float] = 6.0

_RESPONSE_NAME: Final[dict[int, str]] = {p: name for name, p in RESPONSE_POWER.items()}


@dataclass(frozen=True, eq=False)
class TwoModeFit:
    r"""Two SDOF responses fitted jointly to one band of a PSD, and the test against one.

    Attributes
    ----------
    modes : tuple of SDOFFit
        The two modes in order of frequency, each with its own f_n, zeta and their standard
        uncertainties from the joint covariance, the shared background, the joint fit's
        ``redchi2`` and ``chi2``, and ``flags`` holding ``"joint_fit"`` (plus ``misfit``,
        ``band_too_narrow``, ``unresolved`` where they apply to the joint fit or the mode).
    covariance : numpy.ndarray
        Shape (4, 4): covariance of :math:`(f_1, \zeta_1, f_2, \zeta_2)` (Hz and 1).
    chi2_one, chi2_two : float
        Weighted residual sums of squares of the one- and two-mode fits on the same bins.
    delta_threshold : float
        The reduction of the chi-square a needless second mode exceeds with probability
        ``false_alarm`` (module notes).
    false_alarm : float
    separation_Hz, separation_std_Hz : float
        :math:`f_2 - f_1` (Hz) and its standard uncertainty (Hz).
    accepted : bool
        The two-mode model is clearly better (module notes): use :attr:`modes`.
    one_mode : SDOFFit
        The one-mode fit on the same bins (its standard uncertainties not computed: NaN).
    band_Hz : tuple of float
        Frequencies fitted (Hz).
    n_bins : int
        Bins fitted.
    message : str
        Why the two-mode model was or was not taken.
    """

    modes: tuple[SDOFFit, SDOFFit]
    covariance: np.ndarray
    chi2_one: float
    chi2_two: float
    delta_threshold: float
    false_alarm: float
    separation_Hz: float
    separation_std_Hz: float
    accepted: bool
    one_mode: SDOFFit
    band_Hz: tuple[float, float]
    n_bins: int
    message: str = ""

    @property
    def delta_chi2(self) -> float:
        """Reduction of the weighted chi-square by the second mode."""
        return self.chi2_one - self.chi2_two


# --------------------------------------------------------------------------------------------
# the model


class _Model:
    """Expected Welch PSD of n_modes SDOF responses plus a background on bins ``idx``."""

    def __init__(self, ctx: PSDContext, idx: np.ndarray, p: int, B_ref: float,
                 floor: float) -> None:
        self.ctx, self.p, self.B_ref, self.floor = ctx, p, B_ref, floor
        self.kern = ctx.props.kernel
        self.fe = np.abs(ctx.f[idx][:, None] - ctx.props.kernel_offsets_bins[None, :] * ctx.df)
        self.y = ctx.lnP[idx] - ctx.bias
        self._key = b""
        self._val: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros((0, 0)))

    def evaluate(self, th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = th.tobytes()
        if key == self._key:
            return self._val
        n_modes = (th.size - 1) // 3
        M = np.full(self.fe.shape[0], th[-1] * self.B_ref)
        cols = []
        for i in range(n_modes):
            f_n, zeta, W = np.exp(th[3 * i: 3 * i + 3])
            c = W / (np.pi * zeta * f_n)
            s, ds_f, ds_z = sdof_shape(self.fe, f_n, zeta, self.p)
            Sk, Sf, Sz = s @ self.kern, ds_f @ self.kern, ds_z @ self.kern
            M += c * Sk
            cols += [c * (Sf - Sk), c * (Sz - Sk), c * Sk]
        cols.append(np.full(M.size, self.B_ref))
        M = np.maximum(M, self.floor)
        self._key, self._val = key, (M, np.column_stack(cols))
        return self._val

    def resid(self, th: np.ndarray) -> np.ndarray:
        return self.y - np.log(self.evaluate(th)[0])

    def jac(self, th: np.ndarray) -> np.ndarray:
        M, dM = self.evaluate(th)
        return -dM / M[:, None]

    def psd_of_bin(self, th: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        """The fitted PSD before the window, at frequencies given in bins."""
        n_modes = (th.size - 1) // 3
        B = float(th[-1] * self.B_ref)
        df = self.ctx.df
        pars = [tuple(float(v) for v in np.exp(th[3 * i: 3 * i + 3])) for i in range(n_modes)]

        def psd(g: np.ndarray) -> np.ndarray:
            out = np.full(np.shape(g), B)
            for f_n, zeta, W in pars:
                out = out + W / (np.pi * zeta * f_n) * sdof_shape(np.abs(g) * df, f_n, zeta,
                                                                  self.p)[0]
            return out

        return psd


def _solve(model: _Model, starts: Sequence[np.ndarray], lower: np.ndarray, upper: np.ndarray,
           max_nfev: int) -> list[OptimizeResult]:
    out = []
    for th0 in starts:
        th0 = np.clip(th0, lower + 1e-6, upper - 1e-6)
        try:
            r = least_squares(model.resid, th0, jac=model.jac, bounds=(lower, upper),
                              method="trf", x_scale=1.0, max_nfev=max_nfev)
        except (ValueError, np.linalg.LinAlgError):
            continue
        out.append(r)
    return sorted(out, key=lambda r: float(r.cost))


# --------------------------------------------------------------------------------------------
# the band and the fit


def joint_band(ctx: PSDContext, single: SDOFFit, k_lo: int, k_hi: int, lo: int, hi: int,
               fit_span: float) -> tuple[int, int]:
    """Bins ``[a, b]`` of the joint fit: beyond the outer peak bins ``k_lo``, ``k_hi``.

    By :data:`JOINT_SPAN` half-power half-widths of the one-mode fit ``single`` (at least
    ``fit_span``, and :data:`~rigtools.analysis.sdof_fit.MIN_FIT_HALF_BINS` bins), within
    ``[lo, hi]``.
    """
    hw = single.zeta * single.f_n_Hz / ctx.df if np.isfinite(single.zeta) else 0.0
    span = int(np.ceil(max(max(JOINT_SPAN, fit_span) * hw, MIN_FIT_HALF_BINS)))
    return max(lo, k_lo - span, 1), min(hi, k_hi + span, ctx.f.size - 2)


def fit_two_modes_in_band(ctx: PSDContext, a: int, b: int, mask: np.ndarray, single: SDOFFit,
                          zeta_res: float, p: int, hints_Hz: Sequence[float] = (),
                          false_alarm: float = JOINT_FALSE_ALARM) -> TwoModeFit | None:
    """Fit one and two SDOF responses to bins ``[a, b]`` (unmasked) and test one against two.

    Parameters
    ----------
    ctx : PSDContext
    a, b : int
        First and last bin of the band.
    mask : numpy.ndarray of bool
        Bins left out (lines).
    single : SDOFFit
        The one-mode fit of the peak (start values).
    zeta_res : float
        The resolution equivalent damping (the lower bound of zeta is a fifth of it).
    p : int
        Response power (:data:`~rigtools.analysis.signal_checks.RESPONSE_POWER`).
    hints_Hz : sequence of float
        Frequencies (Hz) where the second mode may be (other peaks in the band).
    false_alarm : float
        Of the test (module notes).

    Returns
    -------
    TwoModeFit or None
        None when the band is too short or a fit fails.
    """
    f, lnP, df = ctx.f, ctx.lnP, ctx.df
    idx = np.arange(a, b + 1)
    idx = idx[~mask[idx]]
    if idx.size < 16 or not (single.success and np.isfinite(single.zeta)):
        return None
    band = (float(f[a]), float(f[b]))
    zmin = ZETA_MIN_FRACTION * zeta_res
    ln_pk = float(np.max(lnP[idx]))
    B_ref = float(np.exp(min(float(np.percentile(lnP[idx], 5)), ln_pk - 0.7)))
    P_min = float(np.exp(np.min(lnP[idx])))
    model = _Model(ctx, idx, p, B_ref, 1e-6 * P_min)
    lnW_pk = ln_pk + np.log(ctx.props.enbw_bins * df)
    mode_lo = [np.log(max(f[a], 1e-12)), np.log(zmin), lnW_pk - 8]
    mode_hi = [np.log(f[b]), np.log(0.5), lnW_pk + 12]
    bg = ([-BACKGROUND_BELOW_ZERO * P_min / B_ref], [np.exp(ln_pk) / B_ref])
    lower1, upper1 = np.array(mode_lo + bg[0]), np.array(mode_hi + bg[1])
    lower2 = np.array(mode_lo + mode_lo + bg[0])
    upper2 = np.array(mode_hi + mode_hi + bg[1])

    # one mode on these bins, from the peak's own fit
    f_s, z_s = single.f_n_Hz, single.zeta
    W_s = np.pi * z_s * f_s * max(single.peak_psd_per_Hz, 1e-300)
    beta_s = single.background_per_Hz / B_ref
    th1 = np.array([np.log(f_s), np.log(z_s), np.log(W_s), beta_s])
    one = _solve(model, [th1], lower1, upper1, MAX_FIT_EVALUATIONS)
    if not one:
        return None
    r1 = one[0]

    # two modes: the second on a grid about the first, at the residual bump and the hints
    z0 = float(np.clip(0.6 * np.exp(r1.x[1]), 1.5 * zmin, 0.4))
    f1 = float(np.exp(r1.x[0]))
    W1 = float(np.exp(r1.x[2]))
    resid = r1.fun
    m = max(3, round(z0 * f1 / df) | 1)
    bump = np.convolve(resid, np.ones(m) / m, mode="same")
    cands = [f1 + d * 2 * z0 * f1 for d in GRID_BANDWIDTHS]
    # the residuals y - model are largest where the second mode lifts the data
    cands += [float(f[idx[int(np.argmax(bump))]]), *hints_Hz]
    starts = []
    for f2 in cands:
        if not f[a] < f2 < f[b] or abs(f2 - f1) < 0.3 * z0 * f1:
            continue
        f1_0 = f1 - 0.3 * (f2 - f1)
        if not f[a] < f1_0 < f[b]:
            f1_0 = f1
        starts.append(np.array([np.log(f1_0), np.log(z0), np.log(0.7 * W1),
                                np.log(f2), np.log(z0), np.log(0.35 * W1), r1.x[3]]))
    if not starts:
        return None
    screened = _solve(model, starts, lower2, upper2, SCREEN_EVALUATIONS)
    refined = _solve(model, [r.x for r in screened[:REFINED_STARTS]], lower2, upper2,
                     2 * MAX_FIT_EVALUATIONS)
    if not refined:
        return None
    r2 = refined[0]
    th = r2.x.copy()
    if th[3] < th[0]:  # order by frequency (the same fit)
        th = np.r_[th[3:6], th[0:3], th[6]]

    # statistics: the joint covariance (sandwich) and the test on the same bins
    n = idx.size
    J2 = model.jac(th)
    J1 = model.jac(r1.x)
    Sigma2 = ctx.log_covariance(model.psd_of_bin(th), idx)
    Sigma1 = ctx.log_covariance(model.psd_of_bin(r1.x), idx)
    A = np.linalg.pinv(J2.T @ J2)
    cov = A @ (J2.T @ Sigma2 @ J2) @ A
    chi2_two = float(np.sum(model.resid(th) ** 2) / ctx.eps2)
    chi2_one = float(np.sum(r1.fun**2) / ctx.eps2)
    redchi2 = chi2_two / max(n - 7, 1)
    cov *= max(1.0, redchi2)
    cov *= max(1.0, 2.0 * MIN_FIT_HALF_BINS / max(n, 1))
    threshold = _delta_threshold(ctx, J1, J2, Sigma1 / ctx.eps2, false_alarm)
    misfit_at = misfit_threshold(ctx, Sigma2 / ctx.eps2, 7)
    joint_misfit = redchi2 > misfit_at

    fz = np.exp(th[[0, 1, 3, 4]])
    G = np.diag(fz)
    cov4 = G @ cov[np.ix_([0, 1, 3, 4], [0, 1, 3, 4])] @ G
    sep = float(fz[2] - fz[0])
    sep_std = float(np.sqrt(max(cov4[0, 0] + cov4[2, 2] - 2 * cov4[0, 2], 0.0)))
    ok = bool(r2.status > 0)
    at_low = [bool(th[3 * i + 1] <= lower2[3 * i + 1] + 0.05) for i in range(2)]
    B_fit = float(th[6] * B_ref)
    why = []
    delta = chi2_one - chi2_two
    if not ok:
        why.append(f"the two-mode fit did not converge ({r2.message})")
    if not delta > threshold:
        why.append(f"chi-square reduced by {delta:.1f}, not above {threshold:.1f} (false alarm "
                   f"{false_alarm:g}): one mode explains the band as well")
    if not sep > SEPARATION_SIGMA * sep_std:
        why.append(f"the modes {sep:.1f} Hz apart, within {SEPARATION_SIGMA:g} x "
                   f"{sep_std:.1f} Hz")
    mean_bw = float(fz[0] * fz[1] + fz[2] * fz[3])
    if not sep <= MAX_SEPARATION * mean_bw:
        why.append(f"the modes {sep:.1f} Hz apart, more than {MAX_SEPARATION:g} mean "
                   f"half-power bandwidths ({mean_bw:.1f} Hz): not one peak")
    if joint_misfit:
        why.append(f"the two-mode fit misfits too (reduced chi-square {redchi2:.2f} above "
                   f"{misfit_at:.2f})")
    if any(at_low):
        why.append("a mode's damping at its lower bound (a tone)")
    reach = [min(fz[2 * i] / df - a, b - fz[2 * i] / df) / max(fz[2 * i] * fz[2 * i + 1] / df,
                                                                0.5) for i in range(2)]
    if min(reach) < MIN_INSIDE:
        why.append(f"a mode {min(reach):.1f} half-power half-widths from the band's edge (need "
                   f"{MIN_INSIDE:g}): the rise to a neighbouring peak, not a mode of this one")
    accepted = not why
    message = "; ".join(why) if why else (
        f"two modes: chi-square reduced by {delta:.1f} > {threshold:.1f} (false alarm "
        f"{false_alarm:g}), {sep:.1f} Hz apart ({sep / max(sep_std, 1e-300):.1f} sd)")

    modes = []
    for i in range(2):
        f_n, zeta, W = (float(v) for v in np.exp(th[3 * i: 3 * i + 3]))
        flags: dict[str, str] = {"joint_fit": message}
        if joint_misfit:
            flags["misfit"] = (f"reduced chi-square {redchi2:.2f} above {misfit_at:.2f} (false "
                               f"alarm {MISFIT_FALSE_ALARM:g})")
        hw = max(zeta * f_n / df, 0.5)
        cover = min(f_n / df - a, b - f_n / df) / hw
        if cover < MIN_COVER:
            flags["band_too_narrow"] = (f"the band fitted reaches {cover:.1f} half-power "
                                        f"half-widths from the mode (need {MIN_COVER:g})")
        width = 2 * zeta * f_n / df / ctx.props.bandwidth_3dB_bins
        if not at_low[i] and width < MIN_RESOLVED_WIDTH:
            flags["unresolved"] = (f"half-power band {width:.2f} times the window's 3 dB "
                                   "bandwidth")
        if at_low[i]:
            flags["at_lower_bound"] = "damping at its lower bound (a tone)"
        modes.append(SDOFFit(
            f_n_Hz=f_n, f_n_std_Hz=float(np.sqrt(max(cov4[2 * i, 2 * i], 0.0))),
            zeta=zeta, zeta_std=float(np.sqrt(max(cov4[2 * i + 1, 2 * i + 1], 0.0))),
            peak_psd_per_Hz=W / (np.pi * zeta * f_n), background_per_Hz=B_fit, band_Hz=band,
            n_bins=int(n), redchi2=redchi2, success=ok, at_lower_bound=at_low[i],
            message="; ".join(flags.values()), chi2=chi2_two, response=_RESPONSE_NAME[p],
            flags=tuple(flags)))
    f_1, z_1, W_1 = (float(v) for v in np.exp(r1.x[:3]))
    one_fit = SDOFFit(
        f_n_Hz=f_1, f_n_std_Hz=float("nan"), zeta=z_1, zeta_std=float("nan"),
        peak_psd_per_Hz=W_1 / (np.pi * z_1 * f_1), background_per_Hz=float(r1.x[3] * B_ref),
        band_Hz=band, n_bins=int(n), redchi2=chi2_one / max(n - 4, 1), success=r1.status > 0,
        at_lower_bound=False, message="the one-mode fit on the joint band", chi2=chi2_one,
        response=_RESPONSE_NAME[p])
    return TwoModeFit(modes=(modes[0], modes[1]), covariance=cov4, chi2_one=chi2_one,
                      chi2_two=chi2_two, delta_threshold=threshold,
                      false_alarm=float(false_alarm), separation_Hz=sep,
                      separation_std_Hz=sep_std, accepted=accepted, one_mode=one_fit,
                      band_Hz=band, n_bins=int(n), message=message)


def _delta_threshold(ctx: PSDContext, J1: np.ndarray, J2: np.ndarray, R: np.ndarray,
                     false_alarm: float) -> float:
    r"""Upper ``false_alarm`` quantile of the chi-square reduction by a second mode.

    :math:`g\chi^2_h` with the mean :math:`\operatorname{tr}(DR)` and variance
    :math:`2\operatorname{tr}(DRDR)(1 + \kappa/2)` of :math:`e^T D e`, :math:`D = P_2 - P_1`
    (module notes).
    """
    Q1 = np.linalg.qr(J1)[0]
    Q2 = np.linalg.qr(J2)[0]
    A22 = Q2.T @ R @ Q2
    A11 = Q1.T @ R @ Q1
    A12 = Q1.T @ R @ Q2
    mean = float(np.trace(A22) - np.trace(A11))
    sq = float(np.sum(A22 * A22) - 2 * np.sum(A12 * A12) + np.sum(A11 * A11))
    q = J2.shape[1] - J1.shape[1]
    if not (mean > 0 and sq > 0):  # the projections not nested: q parameters, lag-1 scaled
        mean, sq = float(q), float(q)
    sq *= 1.0 + 0.5 * ctx.log_kurtosis
    h = mean * mean / sq
    g = sq / mean
    return float(g * chi2.isf(false_alarm, h))
