r"""Test signals of structural modes made by other routes than the SDOF fit inverts.

The fit in :mod:`rigtools.analysis.sdof_fit` models the *expected Welch PSD* of a mode: a
closed-form :math:`r^{2p}/((1-r^2)^2 + (2\zeta r)^2)` shape convolved with the window's
spectral window, plus a white background. The signals here are made from the physics instead,
two ways, so that a fit that assumes the wrong response (or a wrong estimator statistic) shows
up as an error against the truth:

(a) **frequency domain** (:func:`frequency_domain_signal`): a white Gaussian force (seeded
    :class:`numpy.random.Generator`), its FFT multiplied per FFT bin by the continuous FRF of
    one or more modes (:func:`frf`): receptance

    .. math:: H(\omega) = \sum_j \frac{1}{k_j - m_j\omega^2 + i c_j\omega},

    mobility :math:`i\omega H` or accelerance :math:`-\omega^2 H` (which tends to the mass
    line :math:`1/m` above resonance: the floor the accelerance has up to the Nyquist
    frequency), and the inverse FFT. The result is a circularly stationary Gaussian process
    whose PSD is exactly :math:`|H(f_k)|^2 S_F` on the FFT grid of the whole record.

(b) **time domain** (:func:`time_domain_signal`): each mode as a discrete filter by the
    matched-z transform: the poles :math:`s_{1,2} = -\zeta\omega_n \pm i\omega_n
    \sqrt{1-\zeta^2}` map to :math:`z = e^{s T}`, the zeros of the response at
    :math:`s = 0` (one for velocity, two for acceleration) to :math:`z = 1`, so
    :math:`H_d(z) = g\,(1 - z^{-1})^p / ((1 - z_1 z^{-1})(1 - z_2 z^{-1}))` with the gain g
    matched at low frequency, applied with :func:`scipy.signal.lfilter` to a white force.
    The filter runs at ``oversample`` times the output rate and is decimated by
    :func:`scipy.signal.resample_poly` (a linear-phase anti-alias FIR), as a sigma-delta
    acquisition does. Oversampling matters: at the output rate itself the discrete poles
    bring a factor :math:`\approx \omega T/\sin(\omega T)` and each matched-z difference
    :math:`(1 - e^{-i\omega T})/T` one of :math:`\sin(\omega T/2)/(\omega T/2)` into
    :math:`|H_d|`; for a mode at 2843 Hz sampled at 25.6 kHz the PSD of the displacement
    filter is tilted by a log-slope of +0.20 over 1.5-5 kHz and its fitted f_n moves by
    +0.05 % (+0.03 % for velocity; for acceleration the two factors nearly cancel). At 8
    times the rate the tilt is 0.003 and the shift under 0.001 % (tests: the Welch PSD of
    (b) against the exact expectation, in level and log-slope).

Options: a second mode within a few half-power bandwidths (:func:`close_pair`), mesh
harmonics with sidebands (:class:`Mesh`: tones at :math:`h f_m \pm k f_\text{shaft}`), and
additive white noise at a stated SNR.

**One force or one per mode.** By default (``forces="common"``) one force drives every mode
and the responses add as complex FRFs, :math:`|\sum_j H_j|^2 S_F` (modes of one structure
under one excitation: between two close modes of the same sign the receptances are out of
phase and the PSD dips below the sum of the two). With ``forces="independent"`` each mode is
driven by its own white force of the same PSD, drawn one after the other, and the PSD is the
sum :math:`\sum_j |H_j|^2 S_F`: two uncorrelated sources, such as a gear-mesh mode and a
housing mode excited by different forces (the demo campaign's case), and the model the
two-mode fit of :mod:`rigtools.analysis.two_mode_fit` assumes.

**SNR** (dB) is :math:`10\log_{10}(\overline{x_\text{modes}^2} / \sigma_\text{noise}^2)`:
the expected mean square of the noise-free modal response (all modes, without the mesh
tones; the continuous FRF integrated from 0 to :math:`f_s/2`) over the variance of the
added white noise, both over the full band 0 to :math:`f_s/2`. How far a mode's PSD peak
stands above the noise floor then depends on its damping and on the response type; it is
returned per mode in :attr:`ModalTruth.peak_to_floor_dB`.

The default rig: 25.6 kHz, 20 s, one mode at 2843 Hz with zeta 0.03 (issue 17), mesh 400 Hz
(16 teeth at 1500 rpm), shaft 25 Hz.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import signal as sps

__all__ = [
    "FS_HZ",
    "RESPONSE_POWER",
    "Forces",
    "Mesh",
    "ModalSignal",
    "ModalTruth",
    "Mode",
    "Response",
    "close_pair",
    "expected_psd",
    "frequency_domain_signal",
    "frf",
    "matched_z_filter",
    "mean_square",
    "modal_psd_shape",
    "pair_with_psd_ratio",
    "time_domain_signal",
]

Response = Literal["displacement", "velocity", "acceleration"]
Forces = Literal["common", "independent"]
#: Power of :math:`i\omega` that turns the receptance into the response.
RESPONSE_POWER: dict[str, int] = {"displacement": 0, "velocity": 1, "acceleration": 2}
#: The rig's sample rate (Hz).
FS_HZ = 25_600.0


@dataclass(frozen=True)
class Mode:
    r"""One structural mode.

    Attributes
    ----------
    f_n_Hz : float
        Undamped natural frequency :math:`\sqrt{k/m}/(2\pi)` (Hz).
    zeta : float
        Damping ratio :math:`c / (2\sqrt{k m})`.
    stiffness : float
        Modal stiffness k (force unit per response unit); the response is then rescaled to
        the requested RMS, so only the ratio between modes matters.
    """

    f_n_Hz: float
    zeta: float
    stiffness: float = 1.0

    @property
    def mass(self) -> float:
        r"""Modal mass :math:`m = k / \omega_n^2`."""
        return self.stiffness / (2 * np.pi * self.f_n_Hz) ** 2

    @property
    def damping(self) -> float:
        r"""Viscous damping :math:`c = 2\zeta\sqrt{k m}`."""
        return 2 * self.zeta * np.sqrt(self.stiffness * self.mass)

    @property
    def half_power_bandwidth_Hz(self) -> float:
        r""":math:`2\zeta f_n` (Hz)."""
        return 2 * self.zeta * self.f_n_Hz


@dataclass(frozen=True)
class Mesh:
    r"""Mesh harmonics with shaft sidebands, added as tones.

    Tones at :math:`h f_m + k f_s`, h = 1 .. ``harmonics``, k = -``sidebands`` ..
    ``sidebands``, with amplitude :math:`A_h\,r^{|k|}`, :math:`A_h` = ``amplitude / h``
    (times the modal RMS), r = ``sideband_ratio``, and random phases.

    Attributes
    ----------
    mesh_Hz, shaft_Hz : float
        Mesh and shaft frequencies (Hz).
    harmonics, sidebands : int
    amplitude : float
        Amplitude of the first harmonic over the RMS of the modal response.
    sideband_ratio : float
    """

    mesh_Hz: float = 400.0
    shaft_Hz: float = 25.0
    harmonics: int = 20
    sidebands: int = 2
    amplitude: float = 0.5
    sideband_ratio: float = 0.3

    def tones(self, fs_Hz: float) -> tuple[tuple[float, float], ...]:
        """``(frequency Hz, amplitude relative to the modal RMS)`` below the Nyquist frequency."""
        out = []
        for h in range(1, self.harmonics + 1):
            for k in range(-self.sidebands, self.sidebands + 1):
                f = h * self.mesh_Hz + k * self.shaft_Hz
                if 0 < f < fs_Hz / 2:
                    out.append((f, self.amplitude / h * self.sideband_ratio ** abs(k)))
        return tuple(out)


@dataclass(frozen=True)
class ModalTruth:
    """What a test signal was made from.

    Attributes
    ----------
    modes : tuple of Mode
    response : str
        ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    route : str
        ``"frequency"`` (FRF per FFT bin) or ``"time"`` (matched-z filter).
    fs_Hz, duration_s : float
    seed : int or None
    signal_rms : float
        RMS of the noise-free modal response (expected value, signal unit).
    snr_dB : float or None
        See the module docstring; None: no noise added.
    noise_rms : float
    tones : tuple of (float, float)
        Mesh tones added: ``(frequency Hz, amplitude in the signal unit)``.
    peak_to_floor_dB : tuple of float
        Per mode, the PSD of the modal response at :math:`f_n` over the noise PSD (dB; inf
        without noise).
    force_psd : float
        One-sided PSD of the force that makes the modal response (force unit^2/Hz), after
        scaling to ``signal_rms``: the PSD of the modal response is ``|frf|^2 * force_psd``
        (with independent forces, the sum of each mode's ``|frf|^2`` times it).
    independent : bool
        Each mode driven by its own force (module docstring).
    """

    modes: tuple[Mode, ...]
    response: str
    route: str
    fs_Hz: float
    duration_s: float
    seed: int | None
    signal_rms: float
    snr_dB: float | None
    noise_rms: float
    tones: tuple[tuple[float, float], ...]
    peak_to_floor_dB: tuple[float, ...]
    force_psd: float
    independent: bool = False

    @property
    def f_n_Hz(self) -> float:
        """Natural frequency of the first mode (Hz)."""
        return self.modes[0].f_n_Hz

    @property
    def zeta(self) -> float:
        """Damping ratio of the first mode."""
        return self.modes[0].zeta

    @property
    def noise_psd(self) -> float:
        """One-sided PSD of the added white noise (unit^2/Hz)."""
        return 2 * self.noise_rms**2 / self.fs_Hz

    def tones_near(self, f_Hz: float, half_width_Hz: float) -> list[float]:
        """Frequencies of the mesh tones within ``half_width_Hz`` of ``f_Hz``."""
        return [f for f, _ in self.tones if abs(f - f_Hz) <= half_width_Hz]


@dataclass(frozen=True)
class ModalSignal:
    """A test signal and its truth.

    Attributes
    ----------
    x : numpy.ndarray
        Samples, float64, shape ``(n,)``.
    truth : ModalTruth
    modal : numpy.ndarray
        The noise-free modal response alone (no tones, no noise).
    """

    x: np.ndarray
    truth: ModalTruth
    modal: np.ndarray = field(repr=False)


# --------------------------------------------------------------------------------------------
# the continuous FRF


def _check_response(response: str) -> int:
    if response not in RESPONSE_POWER:
        raise ValueError(f"`response` must be one of {sorted(RESPONSE_POWER)}, was {response!r}")
    return RESPONSE_POWER[response]


def frf(f_Hz: np.ndarray | float, modes: Sequence[Mode], response: str) -> np.ndarray:
    r"""Continuous FRF of a sum of modes: receptance, mobility or accelerance.

    :math:`(i\omega)^p \sum_j 1/(k_j - m_j\omega^2 + i c_j\omega)`, p = 0, 1, 2.

    Parameters
    ----------
    f_Hz : array_like
        Frequencies (Hz).
    modes : sequence of Mode
    response : {'displacement', 'velocity', 'acceleration'}

    Returns
    -------
    numpy.ndarray
        Complex FRF (response unit per force unit).
    """
    p = _check_response(response)
    w = 2 * np.pi * np.asarray(f_Hz, np.float64)
    h = np.zeros(w.shape, np.complex128)
    for m in modes:
        h += 1.0 / (m.stiffness - m.mass * w * w + 1j * m.damping * w)
    return h * (1j * w) ** p


def mean_square(modes: Sequence[Mode], response: str, fs_Hz: float, n_grid: int = 400_001,
                independent: bool = False) -> float:
    r""":math:`\int_0^{f_s/2} |H(f)|^2 df` per unit one-sided force PSD (trapezoid).

    With ``independent`` forces, :math:`\int \sum_j |H_j|^2 df`.
    """
    f = np.linspace(0.0, fs_Hz / 2, n_grid)
    # a grid fine against the narrowest mode: at least 40 points per half-power bandwidth
    bw = min(m.half_power_bandwidth_Hz for m in modes)
    if (f[1] - f[0]) * 40 > bw:
        f = np.linspace(0.0, fs_Hz / 2, int(fs_Hz / 2 / bw * 40) + 1)
    return float(np.trapezoid(modal_psd_shape(f, modes, response, independent), f))


def modal_psd_shape(f_Hz: np.ndarray | float, modes: Sequence[Mode], response: str,
                    independent: bool = False) -> np.ndarray:
    r"""PSD of the modal response per unit force PSD.

    :math:`|\sum_j H_j|^2`, or :math:`\sum_j |H_j|^2` with ``independent`` forces (module
    docstring).
    """
    if independent:
        return np.sum([np.abs(frf(f_Hz, [m], response)) ** 2 for m in modes], axis=0)
    return np.abs(frf(f_Hz, modes, response)) ** 2


def expected_psd(f_Hz: np.ndarray, truth: ModalTruth) -> np.ndarray:
    """PSD of the modal response plus the noise at ``f_Hz`` (unit^2/Hz; no window, no tones)."""
    return (modal_psd_shape(f_Hz, truth.modes, truth.response, truth.independent)
            * truth.force_psd + truth.noise_psd)


def close_pair(f_n_Hz: float = 2843.0, zeta: float = 0.03, separation_bw: float = 2.0,
               relative_level: float = 1.0, zeta2: float | None = None) -> tuple[Mode, Mode]:
    r"""Two modes ``separation_bw`` half-power bandwidths apart (the second above).

    ``relative_level`` is the ratio of the second mode's receptance peak to the first's;
    ``zeta2`` the second mode's damping (default ``zeta``). The separation is in half-power
    bandwidths :math:`2\zeta f_n` of the first mode.
    """
    first = Mode(f_n_Hz, zeta)
    f2 = f_n_Hz + separation_bw * first.half_power_bandwidth_Hz
    z2 = zeta if zeta2 is None else float(zeta2)
    # receptance peak ~ 1 / (2 zeta k): scale k
    second = Mode(f2, z2, stiffness=zeta / (z2 * relative_level))
    return first, second


def pair_with_psd_ratio(f1_Hz: float, zeta1: float, f2_Hz: float, zeta2: float,
                        psd_ratio: float, response: str) -> tuple[Mode, Mode]:
    r"""Two modes whose own response PSDs peak in the ratio ``psd_ratio`` (second over first).

    The peak of :math:`|H_j|^2` of a mode's response is :math:`(2\pi f_j)^{2p} / (2\zeta_j
    k_j)^2` (at :math:`f_j`, to first order in zeta): the second mode's stiffness is set so.
    """
    p = _check_response(response)
    first = Mode(f1_Hz, zeta1)
    peak1 = (2 * np.pi * f1_Hz) ** (2 * p) / (2 * zeta1) ** 2
    k2 = np.sqrt((2 * np.pi * f2_Hz) ** (2 * p) / (2 * zeta2) ** 2 / (psd_ratio * peak1))
    return first, Mode(f2_Hz, zeta2, stiffness=float(k2))


# --------------------------------------------------------------------------------------------
# the routes


def _rng(rng: np.random.Generator | int | None) -> tuple[np.random.Generator, int | None]:
    if isinstance(rng, np.random.Generator):
        return rng, None
    return np.random.default_rng(rng), rng


def _check_forces(forces: str) -> bool:
    if forces not in ("common", "independent"):
        raise ValueError(f"`forces` must be 'common' or 'independent', was {forces!r}")
    return forces == "independent"


def _finish(modal: np.ndarray, modes: tuple[Mode, ...], response: str, route: str,
            fs_Hz: float, rng: np.random.Generator, seed: int | None, signal_rms: float,
            scale: float, snr_dB: float | None, mesh: Mesh | None,
            independent: bool = False) -> ModalSignal:
    n = modal.size
    t = np.arange(n) / fs_Hz
    x = modal.copy()
    tones: list[tuple[float, float]] = []
    if mesh is not None:
        for f, a_rel in mesh.tones(fs_Hz):
            a = a_rel * signal_rms
            x += a * np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
            tones.append((f, a))
    if snr_dB is None:
        noise_rms = 0.0
    else:
        noise_rms = signal_rms * 10 ** (-float(snr_dB) / 20)
        x += rng.normal(0.0, noise_rms, n)
    force_psd = scale**2 * 2.0 / fs_Hz  # unit-variance force samples, scaled
    floor = 2 * noise_rms**2 / fs_Hz
    peak = [float(modal_psd_shape(m.f_n_Hz, modes, response, independent) * force_psd)
            for m in modes]
    p2f = tuple(10 * np.log10(p / floor) if floor > 0 else float("inf") for p in peak)
    truth = ModalTruth(modes=modes, response=response, route=route, fs_Hz=fs_Hz,
                       duration_s=n / fs_Hz, seed=seed, signal_rms=signal_rms, snr_dB=snr_dB,
                       noise_rms=noise_rms, tones=tuple(tones), peak_to_floor_dB=p2f,
                       force_psd=force_psd, independent=independent)
    return ModalSignal(x=x, truth=truth, modal=modal)


def frequency_domain_signal(modes: Sequence[Mode], response: str = "acceleration", *,
                            fs_Hz: float = FS_HZ, duration_s: float = 20.0,
                            snr_dB: float | None = 20.0, mesh: Mesh | None = None,
                            signal_rms: float = 1.0, forces: Forces = "common",
                            rng: np.random.Generator | int | None = None) -> ModalSignal:
    """Route (a): white force, FFT, times the continuous FRF per bin, inverse FFT.

    Parameters
    ----------
    modes : sequence of Mode
    response : {'displacement', 'velocity', 'acceleration'}
    fs_Hz : float
        Sample rate (Hz).
    duration_s : float
        Record length (s).
    snr_dB : float or None
        Noise level (module docstring); None: no noise.
    mesh : Mesh, optional
        Mesh tones to add.
    signal_rms : float
        Expected RMS of the modal response (signal unit).
    forces : {'common', 'independent'}
        One force for all modes, or one per mode (module docstring).
    rng : numpy.random.Generator, int or None
        Randomness (force(s), tone phases, noise, in that order).

    Returns
    -------
    ModalSignal
    """
    modes = tuple(modes)
    _check_response(response)
    independent = _check_forces(forces)
    gen, seed = _rng(rng)
    n = round(duration_s * fs_Hz)
    f = np.fft.rfftfreq(n, 1.0 / fs_Hz)
    groups = [(m,) for m in modes] if independent else [modes]
    spectra = []
    ms = 0.0
    # exact expected mean square of this construction (Parseval over the full FFT)
    weight = np.full(f.size, 2.0)
    weight[0] = 1.0
    if n % 2 == 0:
        weight[-1] = 1.0
    for group in groups:
        force = gen.standard_normal(n)
        h = frf(f, group, response)
        if n % 2 == 0:
            h[-1] = h[-1].real  # the Nyquist bin of a real signal is real
        ms += float(np.sum(weight * np.abs(h) ** 2)) / n
        spectra.append(np.fft.rfft(force) * h)
    scale = signal_rms / np.sqrt(ms)
    modal = np.fft.irfft(np.sum(spectra, axis=0), n) * scale
    return _finish(modal, modes, response, "frequency", fs_Hz, gen, seed, signal_rms, scale,
                   snr_dB, mesh, independent)


def matched_z_filter(mode: Mode, response: str, fs_Hz: float) -> tuple[np.ndarray, np.ndarray]:
    r"""Matched-z filter ``(b, a)`` of one mode's receptance, mobility or accelerance.

    Poles :math:`e^{s_{1,2}T}`; p zeros at :math:`z = 1` (the zeros of :math:`(i\omega)^p`
    at s = 0); gain so that :math:`H_d \approx H` at low frequency:
    :math:`g = A(1) / (k T^p)`, :math:`(1 - z^{-1})/T \to i\omega`.
    """
    p = _check_response(response)
    T = 1.0 / fs_Hz
    wn = 2 * np.pi * mode.f_n_Hz
    sigma = mode.zeta * wn
    wd = wn * np.sqrt(1 - mode.zeta**2)
    r = np.exp(-sigma * T)
    a = np.array([1.0, -2 * r * np.cos(wd * T), r * r])
    g = float(np.sum(a)) / (mode.stiffness * T**p)
    b = g * np.poly1d([1.0, -1.0]) ** p if p else np.poly1d([g])
    return np.atleast_1d(np.asarray(b.coeffs, np.float64)), a


def time_domain_signal(modes: Sequence[Mode], response: str = "acceleration", *,
                       fs_Hz: float = FS_HZ, duration_s: float = 20.0,
                       snr_dB: float | None = 20.0, mesh: Mesh | None = None,
                       signal_rms: float = 1.0, oversample: int = 8,
                       forces: Forces = "common",
                       rng: np.random.Generator | int | None = None) -> ModalSignal:
    """Route (b): white force through the modes' matched-z filters, then decimated.

    Parameters
    ----------
    modes, response, fs_Hz, duration_s, snr_dB, mesh, signal_rms, forces, rng
        As for :func:`frequency_domain_signal`.
    oversample : int
        The filters run at ``oversample * fs_Hz`` (module docstring); 1: at the output rate,
        no decimation.

    Returns
    -------
    ModalSignal
    """
    modes = tuple(modes)
    _check_response(response)
    independent = _check_forces(forces)
    gen, seed = _rng(rng)
    q = int(oversample)
    fs_o = fs_Hz * q
    n = round(duration_s * fs_Hz)
    # settle: 40 decay times of the slowest mode, and the decimator's edges
    settle = int(40 / (2 * np.pi * min(m.zeta * m.f_n_Hz for m in modes)) * fs_Hz) + 64
    n_o = (n + 2 * settle) * q
    # a force with the same one-sided PSD (2 / fs_Hz) as route (a)'s unit-variance samples
    force = gen.standard_normal(n_o) * np.sqrt(q)
    y = np.zeros(n_o)
    for i, m in enumerate(modes):
        if independent and i > 0:
            force = gen.standard_normal(n_o) * np.sqrt(q)
        b, a = matched_z_filter(m, response, fs_o)
        y += sps.lfilter(b, a, force)
    if q > 1:
        # linear-phase anti-alias FIR: flat (0.1 %) to about 0.8 of the new Nyquist frequency
        taps = sps.firwin(32 * q + 1, 1.0 / q, window=("kaiser", 9.0))
        y = sps.resample_poly(y, 1, q, window=taps)
    modal = y[settle: settle + n]
    scale = signal_rms / np.sqrt(mean_square(modes, response, fs_Hz, independent=independent)
                                 * 2.0 / fs_Hz)
    modal = modal * scale
    return _finish(modal, modes, response, "time", fs_Hz, gen, seed, signal_rms, scale,
                   snr_dB, mesh, independent)
