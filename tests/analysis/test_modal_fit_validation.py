r"""The SDOF fit against spectra nobody here shaped (issue 17, must-hold 2).

The signals come from :mod:`modal_signals`: white force through the continuous FRF per FFT
bin (route a) or through matched-z filters (route b), for displacement, velocity and
acceleration responses, with a close second mode, mesh harmonics with sidebands and white
noise at a stated SNR (its definition is in :mod:`modal_signals`). The fit is always told the
response the signal has (``fit_sdof(..., response=...)``); what the default
``response="displacement"`` does to accelerometer data is measured, not asserted, here.

What must hold (issue 17, item 2):

- f_n within 0.1 % and zeta within 10 % at 20 dB SNR;
- over at least 50 seeds the normalised errors (error / stated standard uncertainty) of f_n and
  of zeta have a spread (sample sd) within 0.8-1.25 and lie within 2 stated sd in at least 90 %
  of the cases, from 40 dB down to 0 dB SNR;
- where the fit cannot be trusted (band too narrow, overlapping modes, a model that does not
  fit the spectrum) it says so in a flag; where it can, it does not.

"Flagged" is read from the fit alone (:func:`flagged`): a non-empty ``flags`` attribute (the
``flags`` of issue 17 item 3), ``success`` False or ``at_lower_bound``. A large stated
uncertainty is not a flag.

The default run uses 20 s records at one SNR and a reduced seed count where it can (about 20 s
in all); ``-m slow`` runs 100 seeds at every SNR, both routes, every response.

The generators themselves are checked first: the FRF against :func:`scipy.signal.freqs` of
``1/(m s^2 + c s + k)``; route (a) multiplies the force's FFT by the FRF exactly; the Welch
PSD (:func:`scipy.signal.welch`, not rigtools') of routes (a) and (b) matches the expected
value, :math:`|H|^2 S_F` convolved with the window's spectral window, to within the Welch
estimator's known scatter (:math:`\ln\hat S` has mean :math:`\psi(\nu/2) - \ln(\nu/2)` and
variance :math:`\psi'(\nu/2)`, Percival and Walden 1993 Eq. 292b for :math:`\nu`), in level
and in log-slope; a matched-z filter run at the output rate fails that slope check.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import modal_signals as ms
import numpy as np
import pytest
from modal_signals import Mesh, ModalSignal, Mode
from scipy import signal as sps
from scipy.special import polygamma

from rigtools.analysis import fit_sdof, natural_frequencies, welch_psd

F_N, ZETA = 2843.0, 0.03  # issue 17's mode
FS = ms.FS_HZ
RESPONSES = ("displacement", "velocity", "acceleration")
UNIT = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}
ROUTES: dict[str, Callable[..., ModalSignal]] = {
    "frequency": ms.frequency_domain_signal, "time": ms.time_domain_signal}
TOL_F, TOL_Z = 0.001, 0.10  # issue 17 item 2, at 20 dB
SPREAD = (0.8, 1.25)  # sample sd of the normalised errors
WITHIN_2SD = 0.90
#: A fit not flagged must be within this many stated sd (else it is silently wrong).
HONEST_SD = 3.5
NPERSEG = 4096  # the default of welch_psd: 6.25 Hz at 25.6 kHz


# --------------------------------------------------------------------------------------------
# helpers


def flagged(fit: Any) -> bool:
    """The fit (or modal estimate) says it cannot be trusted."""
    if getattr(fit, "flags", None):
        return True
    inner = getattr(fit, "fit", None)  # a ModalEstimate: its SDOFFit
    if inner is not None and inner is not fit:
        return flagged(inner)
    return bool(not fit.success or fit.at_lower_bound)


def fit_signal(sig: ModalSignal, response: str | None = None, **kw: Any) -> Any:
    """Welch PSD (defaults of welch_psd) and fit_sdof at the first mode, tones masked."""
    resp = sig.truth.response if response is None else response
    sp = welch_psd(sig.x, FS, unit=UNIT[sig.truth.response])
    exclude = sig.truth.tones_near(sig.truth.f_n_Hz, 1000.0)
    return fit_sdof(sp, sig.truth.f_n_Hz, response=resp, exclude_Hz=exclude, **kw)


def normalised(fits: Sequence[Any], f_n: float, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """(f_n error / stated sd, zeta error / stated sd); NaN where the fit gave none."""
    with np.errstate(divide="ignore", invalid="ignore"):
        zf = np.array([(f.f_n_Hz - f_n) / f.f_n_std_Hz for f in fits], float)
        zz = np.array([(f.zeta - zeta) / f.zeta_std for f in fits], float)
    return zf, zz


def calibration_failures(z: np.ndarray, what: str) -> list[str]:
    """The must-hold on normalised errors: spread in 0.8-1.25, |z| < 2 in >= 90 % of cases."""
    n = z.size
    finite = np.isfinite(z)
    spread = float(np.std(z[finite], ddof=1)) if finite.sum() > 1 else float("nan")
    inside = float(np.count_nonzero(np.abs(z[finite]) < 2)) / n
    bias = float(np.mean(z[finite])) if finite.any() else float("nan")
    out = []
    if not (SPREAD[0] <= spread <= SPREAD[1]):
        out.append(f"{what}: spread of the normalised errors {spread:.2f} outside "
                   f"{SPREAD[0]}-{SPREAD[1]} (bias {bias:+.2f}, n {n})")
    if not inside >= WITHIN_2SD:
        out.append(f"{what}: |error| < 2 sd in {inside:.0%} of {n} cases, need "
                   f"{WITHIN_2SD:.0%} (bias {bias:+.2f}, spread {spread:.2f})")
    if not finite.all():
        out.append(f"{what}: {n - int(finite.sum())} fits without an uncertainty")
    return out


def run_seeds(route: str, modes: Sequence[Mode], response: str, snr_dB: float,
              seeds: range, duration_s: float = 20.0, mesh: Mesh | None = None
              ) -> list[Any]:
    gen = ROUTES[route]
    return [fit_signal(gen(modes, response, snr_dB=snr_dB, duration_s=duration_s, mesh=mesh,
                           rng=seed))
            for seed in seeds]


# --------------------------------------------------------------------------------------------
# the generators are right


@pytest.mark.parametrize("response", RESPONSES)
def test_frf_is_the_transfer_function_of_m_c_k(response):
    """Sum of two modes against scipy.signal.freqs of (s^p)/(m s^2 + c s + k)."""
    modes = ms.close_pair(F_N, ZETA, 2.0, relative_level=0.5)
    f = np.linspace(10.0, 12_000.0, 4001)
    p = ms.RESPONSE_POWER[response]
    want = np.zeros(f.size, complex)
    for m in modes:
        b = np.r_[1.0, np.zeros(p)]
        _, h = sps.freqs(b, [m.mass, m.damping, m.stiffness], worN=2 * np.pi * f)
        want += h
    np.testing.assert_allclose(ms.frf(f, modes, response), want, rtol=1e-10)


def test_frf_limits_and_the_mass_line():
    m = Mode(F_N, ZETA, stiffness=3.0)
    assert ms.frf(0.0, [m], "displacement") == pytest.approx(1 / 3.0)  # static compliance
    assert ms.frf(0.0, [m], "velocity") == 0 and ms.frf(0.0, [m], "acceleration") == 0
    # at f_n the receptance is in quadrature, the mobility real and 1/c
    assert ms.frf(F_N, [m], "displacement").real == pytest.approx(0.0, abs=1e-12)
    assert ms.frf(F_N, [m], "velocity") == pytest.approx(1 / m.damping, rel=1e-12)
    # above resonance the accelerance tends to the mass line 1/m (the floor up to Nyquist)
    r = np.array([10.0, 40.0])
    a = ms.frf(r * F_N, [m], "acceleration")
    np.testing.assert_allclose(a * m.mass, r**2 / (r**2 - 1 - 2j * ZETA * r), rtol=1e-12)
    assert abs(a[1] * m.mass - 1) < 0.002


def test_route_a_multiplies_the_force_spectrum_by_the_frf():
    sig = ms.frequency_domain_signal([Mode(F_N, ZETA)], "acceleration", duration_s=2.0,
                                     snr_dB=None, rng=11)
    n = sig.x.size
    force = np.random.default_rng(11).standard_normal(n)  # the first draw (module docstring)
    f = np.fft.rfftfreq(n, 1 / FS)
    scale = np.sqrt(sig.truth.force_psd * FS / 2)
    ratio = np.fft.rfft(sig.modal)[1:-1] / np.fft.rfft(force)[1:-1]
    np.testing.assert_allclose(ratio, scale * ms.frf(f[1:-1], sig.truth.modes, "acceleration"),
                               rtol=1e-6)


def test_snr_is_the_modal_mean_square_over_the_noise_variance():
    sig = ms.frequency_domain_signal([Mode(F_N, ZETA)], "velocity", snr_dB=10.0,
                                     signal_rms=2.0, rng=12)
    t = sig.truth
    assert t.noise_rms == pytest.approx(2.0 * 10 ** (-0.5))
    noise = sig.x - sig.modal
    assert np.std(noise) == pytest.approx(t.noise_rms, rel=0.01)
    # the realised modal mean square scatters about the stated one by ~ 1/sqrt(B T)
    assert np.mean(sig.modal**2) == pytest.approx(4.0, rel=0.05)
    assert t.peak_to_floor_dB[0] == pytest.approx(
        10 * np.log10(np.abs(ms.frf(F_N, t.modes, "velocity")) ** 2 * t.force_psd
                      / t.noise_psd))


def test_mesh_tones_are_harmonics_with_sidebands():
    sig = ms.frequency_domain_signal([Mode(F_N, ZETA)], "acceleration", duration_s=1.0,
                                     mesh=Mesh(harmonics=3, sidebands=1), rng=13)
    freqs = sorted(f for f, _ in sig.truth.tones)
    assert freqs == [375, 400, 425, 775, 800, 825, 1175, 1200, 1225]
    amp = dict(sig.truth.tones)
    assert amp[800] == pytest.approx(0.25) and amp[825] == pytest.approx(0.075)


def expected_welch(truth: ms.ModalTruth, n: int, nperseg: int) -> np.ndarray:
    r"""Exact expected Welch PSD (Hann, one-sided) of a route-(a) signal of n samples.

    A window's DFT at bin k of a circular process with spectrum :math:`|H_j|^2` on the grid
    j/n sees :math:`\sum_j |H_j|^2 |W(j/n - k/N)|^2`: a circular correlation of
    :math:`|H|^2` with the window's zero-padded power response, taken at :math:`j = k n/N`.
    """
    if n % nperseg:
        raise ValueError("n must be a multiple of nperseg")
    w = sps.get_window("hann", nperseg)
    j = np.fft.fftfreq(n, 1 / FS)
    h2 = np.abs(ms.frf(np.abs(j), truth.modes, truth.response)) ** 2
    g = np.abs(np.fft.fft(w, n)) ** 2
    corr = np.fft.ifft(np.fft.fft(h2) * np.conj(np.fft.fft(g))).real
    scale2 = truth.force_psd * FS / 2
    k = np.arange(nperseg // 2 + 1)
    return 2 / (FS * np.dot(w, w)) * scale2 / n * corr[k * (n // nperseg)] + truth.noise_psd


def welch_scatter(n: int, nperseg: int) -> tuple[float, float, np.ndarray]:
    r"""Mean and variance of :math:`\ln(\hat S/S)` and the lag correlation of Welch bins.

    Hann, 50 % overlap; :math:`\nu = 2K^2/(K + 2(K-1)\rho^2)` (Percival and Walden 1993,
    Eq. 292b); the correlation of averaged bins q apart counts both the window's own
    (:math:`|\sum w^2 e^{-2\pi i q n/N}|^2`) and that of overlapping windows.
    """
    w = sps.get_window("hann", nperseg)
    s = nperseg // 2
    k = (n - nperseg) // s + 1
    s2 = np.dot(w, w)
    idx = np.arange(nperseg)

    def c(q: int, shift: int) -> float:
        prod = w[shift:] * w[: nperseg - shift]
        return float(abs(np.sum(prod * np.exp(-2j * np.pi * q * idx[: nperseg - shift]
                                              / nperseg))) ** 2 / s2**2)

    nu = 2 * k * k / (k + 2 * (k - 1) * c(0, s))
    tot = np.array([k * c(q, 0) + 2 * (k - 1) * c(q, s) for q in range(4)])
    h = nu / 2
    return float(polygamma(0, h) - np.log(h)), float(polygamma(1, h)), tot / tot[0]


def log_ratio_checks(x: np.ndarray, truth: ms.ModalTruth, bands: Sequence[tuple[float, float]],
                     slope_band: tuple[float, float]) -> list[str]:
    """Level per band and log-log slope of the Welch PSD against the exact expectation."""
    f, p = sps.welch(x, FS, window="hann", nperseg=NPERSEG, detrend=False)
    e = expected_welch(truth, x.size, NPERSEG)
    mean, var, rho = welch_scatter(x.size, NPERSEG)
    d = np.log(p / e) - mean
    out = []
    for lo, hi in bands:
        sel = (f >= lo) & (f < hi)
        nb = int(sel.sum())
        sd_mean = np.sqrt(var * (1 + 2 * np.sum(rho[1:])) / nb)
        m = float(d[sel].mean())
        if abs(m) > 4 * sd_mean:
            out.append(f"{truth.route} {truth.response}: {lo:g}-{hi:g} Hz level "
                       f"{100 * m:+.2f} % (4 sd {400 * sd_mean:.2f} %)")
        # relative sd of a sample variance of correlated Gaussian values
        v = float(d[sel].var())
        sd_v = np.sqrt(2 * (1 + 2 * np.sum(rho[1:] ** 2)) / nb)
        if abs(v / var - 1) > 4 * sd_v:
            out.append(f"{truth.route} {truth.response}: {lo:g}-{hi:g} Hz scatter "
                       f"{v / var:.2f} x psi'(nu/2) (4 sd {4 * sd_v:.2f})")
    sel = (f >= slope_band[0]) & (f < slope_band[1])
    lf = np.log(f[sel])
    lf -= lf.mean()
    slope = float(np.dot(lf, d[sel]) / np.dot(lf, lf))
    # variance of a regression slope on correlated residuals (lags 0..3)
    num = var * sum(r * (np.dot(lf, lf) if q == 0 else 2 * np.dot(lf[q:], lf[:-q]))
                    for q, r in enumerate(rho))
    sd_slope = np.sqrt(num) / np.dot(lf, lf)
    if abs(slope) > 4 * sd_slope:
        out.append(f"{truth.route} {truth.response}: log-slope {slope:+.4f} over "
                   f"{slope_band} Hz (4 sd {4 * sd_slope:.4f})")
    return out


BANDS = [(300.0, 2000.0), (2000.0, 2600.0), (2600.0, 3100.0), (3100.0, 4500.0),
         (4500.0, 9000.0)]


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("response", RESPONSES)
def test_welch_psd_of_the_generators_is_frf_squared_times_the_force_psd(route, response):
    """Routes (a) and (b) against the same exact expected Welch PSD: they agree."""
    modes = [Mode(F_N, ZETA), Mode(6100.0, 0.02, stiffness=2.0)]
    sig = ROUTES[route](modes, response, snr_dB=30.0, duration_s=20.0, rng=21)
    problems = log_ratio_checks(sig.x, sig.truth, BANDS, (1500.0, 5000.0))
    assert not problems, "\n".join(problems)


def test_matched_z_at_the_output_rate_fails_the_slope_check():
    """The checks have teeth: without oversampling the matched-z PSD is tilted (docstring)."""
    sig = ms.time_domain_signal([Mode(F_N, ZETA)], "displacement", snr_dB=30.0,
                                duration_s=20.0, oversample=1, rng=22)
    problems = log_ratio_checks(sig.x, sig.truth, [], (1500.0, 5000.0))
    assert any("log-slope" in p for p in problems), problems


def test_matched_z_poles_are_exp_of_the_continuous_poles():
    m = Mode(F_N, ZETA)
    fs = 8 * FS
    b, a = ms.matched_z_filter(m, "acceleration", fs)
    s = np.roots([m.mass, m.damping, m.stiffness])
    np.testing.assert_allclose(np.sort_complex(np.roots(a)), np.sort_complex(np.exp(s / fs)),
                               rtol=1e-12)
    np.testing.assert_allclose(np.roots(b), [1.0, 1.0], atol=1e-6)  # two zeros at z = 1


# --------------------------------------------------------------------------------------------
# accuracy at 20 dB (response given)


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("response", RESPONSES)
def test_f_n_within_0p1_percent_and_zeta_within_10_percent_at_20_dB(route, response):
    sig = ROUTES[route]([Mode(F_N, ZETA)], response, snr_dB=20.0, rng=31)
    fit = fit_signal(sig)
    msg = f"{route} route, {response} fitted as {response}: {fit}"
    assert abs(fit.f_n_Hz / F_N - 1) <= TOL_F, msg
    assert abs(fit.zeta / ZETA - 1) <= TOL_Z, msg
    assert not flagged(fit), msg  # a clean mode: no flag


@pytest.mark.parametrize("response", RESPONSES)
def test_mesh_harmonics_and_sidebands_masked_at_20_dB(response):
    """Mode at 2843 Hz between the 7th mesh harmonic (2800 Hz) and its sidebands (25 Hz)."""
    sig = ms.frequency_domain_signal([Mode(F_N, ZETA)], response, snr_dB=20.0, mesh=Mesh(),
                                     rng=32)
    fit = fit_signal(sig)
    msg = f"{response}: {fit}"
    assert abs(fit.f_n_Hz / F_N - 1) <= TOL_F, msg
    assert abs(fit.zeta / ZETA - 1) <= TOL_Z, msg
    assert abs(fit.f_n_Hz - F_N) < HONEST_SD * fit.f_n_std_Hz, msg
    assert abs(fit.zeta - ZETA) < HONEST_SD * fit.zeta_std, msg


@pytest.mark.parametrize("response", RESPONSES)
def test_natural_frequencies_passes_the_response_through(response):
    sig = ms.time_domain_signal([Mode(F_N, ZETA)], response, snr_dB=20.0, rng=33)
    (mode,) = natural_frequencies(welch_psd(sig.x, FS, unit=UNIT[response]),
                                  response=response)
    assert mode.response == response
    assert abs(mode.f_n_Hz / F_N - 1) <= TOL_F, mode
    assert abs(mode.zeta / ZETA - 1) <= TOL_Z, mode


# --------------------------------------------------------------------------------------------
# stated uncertainties: normalised errors over seeds


def test_normalised_errors_over_50_seeds_at_20_dB():
    """Reduced variant of the slow matrix: route (a), acceleration, 20 dB, 50 seeds."""
    response = "acceleration"
    fits = run_seeds("frequency", [Mode(F_N, ZETA)], response, 20.0, range(100, 150))
    zf, zz = normalised(fits, F_N, ZETA)
    problems = (calibration_failures(zf, f"f_n ({response})")
                + calibration_failures(zz, f"zeta ({response})"))
    n_flagged = sum(flagged(f) for f in fits)
    if n_flagged > 0.1 * len(fits):
        problems.append(f"{n_flagged} of {len(fits)} fits of a clean mode flagged")
    assert not problems, "\n".join(problems)


@pytest.mark.slow
@pytest.mark.parametrize("snr_dB", [40.0, 20.0, 10.0, 0.0])
@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("response", RESPONSES)
def test_normalised_errors_over_100_seeds(response, route, snr_dB):
    seeds = range(10_000 + 1000 * int(snr_dB), 10_100 + 1000 * int(snr_dB))
    fits = run_seeds(route, [Mode(F_N, ZETA)], response, snr_dB, seeds)
    zf, zz = normalised(fits, F_N, ZETA)
    what = f"{route} route, {response}, {snr_dB:g} dB"
    problems = (calibration_failures(zf, f"f_n, {what}")
                + calibration_failures(zz, f"zeta, {what}"))
    if snr_dB == 20.0:
        ef = np.array([f.f_n_Hz / F_N - 1 for f in fits])
        ez = np.array([f.zeta / ZETA - 1 for f in fits])
        for name, e, tol in (("f_n", ef, TOL_F), ("zeta", ez, TOL_Z)):
            if np.mean(np.abs(e) <= tol) < 0.95:
                problems.append(f"{name}, {what}: within {tol:.1%} in "
                                f"{np.mean(np.abs(e) <= tol):.0%} of the seeds")
    assert not problems, "\n".join(problems)


@pytest.mark.slow
@pytest.mark.parametrize("response", RESPONSES)
def test_normalised_errors_with_mesh_tones_over_100_seeds(response):
    fits = run_seeds("frequency", [Mode(F_N, ZETA)], response, 20.0, range(20_000, 20_100),
                     mesh=Mesh())
    zf, zz = normalised(fits, F_N, ZETA)
    problems = (calibration_failures(zf, f"f_n, mesh, {response}")
                + calibration_failures(zz, f"zeta, mesh, {response}"))
    assert not problems, "\n".join(problems)


# --------------------------------------------------------------------------------------------
# flags: where the fit cannot be trusted it says so, and only there


def untrusted_and_silent(fits: Sequence[Any], f_n: float, zeta: float,
                         tolerance: bool = True) -> list[str]:
    """Fits not flagged that are off by more than HONEST_SD stated sd.

    With ``tolerance``, also those off by more than the 20 dB tolerance (0.1 %, 10 %).
    """
    zf, zz = normalised(fits, f_n, zeta)
    out = []
    for i, f in enumerate(fits):
        if flagged(f):
            continue
        ef, ez = f.f_n_Hz / f_n - 1, f.zeta / zeta - 1
        close = abs(ef) <= TOL_F and abs(ez) <= TOL_Z
        if not (abs(zf[i]) < HONEST_SD and abs(zz[i]) < HONEST_SD and (close or not tolerance)):
            rc2 = getattr(getattr(f, "fit", f), "redchi2", float("nan"))
            out.append(f"#{i}: f_n {100 * ef:+.2f} % ({zf[i]:+.1f} sd), zeta {100 * ez:+.1f} % "
                       f"({zz[i]:+.1f} sd), redchi2 {rc2:.1f}, not flagged")
    return out


@pytest.mark.parametrize("separation_bw", [1.0, 2.0, 3.0])
@pytest.mark.parametrize("response", ["displacement", "acceleration"])
def test_a_second_mode_within_a_few_bandwidths_is_flagged(response, separation_bw):
    """Two equal modes ``separation_bw`` half-power bandwidths apart: flagged, or right."""
    modes = ms.close_pair(F_N, ZETA, separation_bw)
    fits = run_seeds("frequency", modes, response, 20.0, range(40, 43))
    bad = untrusted_and_silent(fits, F_N, ZETA)
    assert not bad, f"{response}, {separation_bw:g} bandwidths apart:\n" + "\n".join(bad)


@pytest.mark.parametrize("separation_bw", [1.0, 2.0])
def test_close_modes_found_by_natural_frequencies_are_flagged(separation_bw):
    modes = ms.close_pair(F_N, ZETA, separation_bw)
    sig = ms.frequency_domain_signal(modes, "acceleration", snr_dB=20.0, rng=46)
    found = natural_frequencies(welch_psd(sig.x, FS, unit="m/s^2"), response="acceleration")
    bad = []
    for est in found:
        truth = min(modes, key=lambda m: abs(m.f_n_Hz - est.f_n_Hz))
        bad += untrusted_and_silent([est], truth.f_n_Hz, truth.zeta)
    assert not bad, "\n".join(bad)


@pytest.mark.slow
@pytest.mark.parametrize("separation_bw", [1.0, 2.0, 3.0, 4.0])
@pytest.mark.parametrize("response", RESPONSES)
def test_close_modes_over_100_seeds(response, separation_bw):
    """Flagged or right, seed by seed; the fits not flagged have honest uncertainties."""
    modes = ms.close_pair(F_N, ZETA, separation_bw)
    fits = run_seeds("frequency", modes, response, 20.0, range(30_000, 30_100))
    problems = untrusted_and_silent(fits, F_N, ZETA)
    kept = [f for f in fits if not flagged(f)]
    if len(kept) >= 50:
        zf, zz = normalised(kept, F_N, ZETA)
        problems += calibration_failures(zf, "f_n (not flagged)")
        problems += calibration_failures(zz, "zeta (not flagged)")
    assert not problems, f"{response}, {separation_bw:g} bandwidths:\n" + "\n".join(problems)


def test_a_band_too_narrow_for_the_mode_is_flagged():
    """The fitted band spans one half-power half-width each side (``fit_span=1``)."""
    zeta = 0.06
    sig = ms.frequency_domain_signal([Mode(F_N, zeta)], "acceleration", snr_dB=20.0, rng=51)
    fit = fit_signal(sig, fit_span=1.0)
    half_width = zeta * F_N
    covered = min(F_N - fit.band_Hz[0], fit.band_Hz[1] - F_N) / half_width
    assert covered < 1.5, fit.band_Hz  # the case is what it says
    assert flagged(fit), f"band covers {covered:.2f} half-power half-widths: {fit}"


@pytest.mark.parametrize("zeta", [0.0005, 0.002])
def test_a_mode_narrower_than_a_few_bins_is_flagged_or_right(zeta):
    """Half-power band 0.45 and 1.8 bins wide: the fit is either honest or flagged.

    The 10 % on zeta is not asked: the resolution cannot give it.
    """
    fits = run_seeds("frequency", [Mode(F_N, zeta)], "acceleration", 20.0, range(60, 63))
    bad = untrusted_and_silent(fits, F_N, zeta, tolerance=False)
    assert not bad, "\n".join(bad)


def test_a_model_that_does_not_fit_is_flagged():
    """Accelerance fitted as receptance (today's default on an accelerometer) is flagged.

    Issue 17's +1.3 %, nine stated sd; the residuals show it (reduced chi-square far above 1).
    """
    sig = ms.frequency_domain_signal([Mode(F_N, ZETA)], "acceleration", snr_dB=20.0, rng=71)
    fit = fit_signal(sig, response="displacement")
    assert abs(fit.f_n_Hz - F_N) > 3 * fit.f_n_std_Hz  # the case is what it says
    assert flagged(fit), f"f_n {100 * (fit.f_n_Hz / F_N - 1):+.2f} %, {fit}"
