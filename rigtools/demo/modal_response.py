r"""Accelerometer signals of structural modes, mesh tones and sensor noise (synthesis only).

The demo's accelerometer signals are made by another route than the analysis takes to read
them (STYLE.md 5: test data must not be shaped like the method that inverts it): the analysis
fits a single-DOF *spectral model* to a Welch PSD; here each mode is the **acceleration
response of a mass-spring-damper to a broadband force**, applied bin by bin to the Fourier
transform of a random force record.

The accelerance
---------------
A mode of modal mass ``m``, natural frequency ``f_n`` and damping ratio ``zeta`` driven by a
force ``F`` has the acceleration response (Ewins 2000, sec. 2.2)

.. math::

    A(f) = \frac{\ddot x}{F} = \frac{1}{m}\,\frac{-r^2}{1 - r^2 + 2 i \zeta r},
    \qquad r = f / f_n ,

which rises as ``r^2`` below resonance, peaks at ``1 / (2 zeta m)`` (at
``f_n / sqrt(1 - 2 zeta^2)``) and tends to the **mass line** ``1 / m`` above it: the
acceleration PSD of a mode does not fall off above its resonance but settles on a floor
``(2 zeta)^2`` below its peak. A displacement model (``|H|^2 ~ 1 / ((1 - r^2)^2 + (2 zeta
r)^2)``) has no such floor.

Synthesis per FFT bin
---------------------
A white Gaussian force record ``w`` (unit variance) is transformed (``numpy.fft.rfft``), each
bin multiplied by ``A`` at its frequency, and transformed back: the circular convolution of
the force with the mode's impulse response, a stationary Gaussian record whose one-sided PSD
is ``|A(f)|^2 2 / f_s``. :func:`mode_acceleration` scales ``A`` so that the PSD at the peak is
the requested ``peak_psd``; several channels see one mode through their own gains (its mode
shape), so their records are coherent.

Mesh tones
----------
Gear mesh harmonics ``k f_m`` (k = 1, 2, 3) amplitude-modulated by both shaft rates (an
eccentric gear modulates the mesh force once per revolution), which puts sidebands at
``k f_m +- f_shaft``:

.. math::

    x(t) = \sum_k A_k \Bigl(1 + \sum_i \mu_i \cos(2\pi f_{s,i} t + \psi_i)\Bigr)
           \sin(2\pi k f_m t + \varphi_k) .

Sensor noise and quantisation
-----------------------------
White Gaussian noise at a broadband signal-to-noise ratio (RMS of the noiseless signal over
the noise RMS, in dB), then rounding to the acquisition's least significant bit.

References
----------
.. [1] D. J. Ewins, *Modal Testing: Theory, Practice and Application*, 2nd ed., Research
       Studies Press, 2000, sec. 2.2 (mobility and accelerance of a single-DOF system).
.. [2] J. S. Bendat, A. G. Piersol, *Random Data*, 4th ed., Wiley, 2010, sec. 6.1 (output PSD
       of a linear system, ``G_yy = |H|^2 G_xx``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "accelerance",
    "accelerance_peak",
    "add_sensor_noise",
    "mesh_tones",
    "mode_acceleration",
    "quantise",
]


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"`{name}` must be finite and > 0, was {value!r}")
    return v


def _zeta(zeta: float) -> float:
    z = float(zeta)
    if not (math.isfinite(z) and 0 < z < 1 / math.sqrt(2)):
        raise ValueError(f"`zeta` must lie in (0, 1/sqrt(2)) (a resonance peak), was {zeta!r}")
    return z


def accelerance(f_Hz: np.ndarray, f_n_Hz: float, zeta: float) -> np.ndarray:
    r"""Accelerance of a single-DOF mode times its modal mass, ``m A(f)`` (-), complex.

    .. math:: m A(f) = \frac{-r^2}{1 - r^2 + 2 i \zeta r}, \qquad r = f / f_n

    Parameters
    ----------
    f_Hz : numpy.ndarray
        Frequencies (Hz), >= 0.
    f_n_Hz : float
        Natural frequency (Hz), > 0.
    zeta : float
        Damping ratio (-), in (0, 1/sqrt(2)).

    Returns
    -------
    numpy.ndarray
        complex128, the shape of ``f_Hz``: 0 at ``f = 0``, ``1 / (2 zeta)`` in magnitude at
        ``f_n``, tending to 1 (the mass line) far above it.

    Examples
    --------
    >>> import numpy as np
    >>> a = accelerance(np.array([0.0, 1000.0, 1e6]), 1000.0, 0.05)
    >>> [round(float(v), 3) for v in np.abs(a)]
    [0.0, 10.0, 1.0]
    """
    f = np.asarray(f_Hz, dtype=float)
    r = f / _positive("f_n_Hz", f_n_Hz)
    return -(r**2) / (1.0 - r**2 + 2j * _zeta(zeta) * r)


def accelerance_peak(zeta: float) -> float:
    r"""Peak of ``|m A(f)|`` (-): ``1 / (2 zeta sqrt(1 - zeta^2))`` at ``f_n / sqrt(1 - 2 zeta^2)``.

    Parameters
    ----------
    zeta : float
        Damping ratio (-).

    Returns
    -------
    float

    Examples
    --------
    >>> round(accelerance_peak(0.05), 4)
    10.0125
    """
    z = _zeta(zeta)
    return 1.0 / (2.0 * z * math.sqrt(1.0 - z * z))


def mode_acceleration(n_samples: int, sample_rate_Hz: float, f_n_Hz: float, zeta: float,
                      peak_psd: float, rng: np.random.Generator | int | None = None
                      ) -> np.ndarray:
    r"""Acceleration record of one mode driven by a white force, synthesised per FFT bin.

    Parameters
    ----------
    n_samples : int
        Record length (samples), >= 2.
    sample_rate_Hz : float
        Sampling rate (Hz).
    f_n_Hz : float
        Natural frequency (Hz), below the Nyquist frequency.
    zeta : float
        Damping ratio (-).
    peak_psd : float
        One-sided PSD of the record at the resonance peak ((unit)^2/Hz), > 0: the record's
        PSD is ``peak_psd |A(f)|^2 / max|A|^2`` (mass-line floor ``peak_psd (2 zeta)^2``
        roughly).
    rng : numpy.random.Generator, int or None
        Randomness of the force (SPEC 7).

    Returns
    -------
    numpy.ndarray
        float64, shape ``(n_samples,)``.

    Notes
    -----
    With ``W_k`` the rfft of unit-variance white noise, the record is
    ``irfft(W_k g A(f_k))`` with ``g = sqrt(peak_psd f_s / 2) / max|A|``, so its one-sided PSD
    is ``g^2 |A(f)|^2 2 / f_s``, equal to ``peak_psd`` at the peak (Bendat and Piersol sec.
    6.1). The record is periodic in ``n_samples`` (a circular convolution); the mode's
    impulse response decays within ``1 / (2 pi zeta f_n)``, far shorter than any record here.
    """
    n = int(n_samples)
    if n < 2:
        raise ValueError(f"`n_samples` must be >= 2, was {n_samples!r}")
    fs = _positive("sample_rate_Hz", sample_rate_Hz)
    fn = _positive("f_n_Hz", f_n_Hz)
    if fn >= fs / 2:
        raise ValueError(f"`f_n_Hz` must be below the Nyquist frequency {fs / 2:g} Hz, was {fn!r}")
    level = _positive("peak_psd", peak_psd)
    gen = np.random.default_rng(rng)
    w = np.fft.rfft(gen.standard_normal(n))
    f = np.fft.rfftfreq(n, 1.0 / fs)
    gain = math.sqrt(level * fs / 2.0) / accelerance_peak(zeta)
    w *= gain * accelerance(f, fn, zeta)
    return np.fft.irfft(w, n)


def mesh_tones(n_samples: int, sample_rate_Hz: float, mesh_frequency_Hz: float,
               amplitudes: Sequence[float], *, shaft_frequencies_Hz: Sequence[float] = (),
               modulation_depths: Sequence[float] = (),
               rng: np.random.Generator | int | None = None) -> np.ndarray:
    r"""Mesh harmonics ``k f_m`` with shaft-rate amplitude modulation (module notes).

    Parameters
    ----------
    n_samples : int
        Record length (samples).
    sample_rate_Hz : float
        Sampling rate (Hz).
    mesh_frequency_Hz : float
        ``f_m`` (Hz), > 0.
    amplitudes : sequence of float
        ``A_k`` of harmonics 1, 2, ... (unit of the record), >= 0.
    shaft_frequencies_Hz : sequence of float
        ``f_s,i`` (Hz) of the modulating shafts.
    modulation_depths : sequence of float
        ``mu_i`` (-), one per shaft, in [0, 1): sideband amplitudes ``A_k mu_i / 2``.
    rng : numpy.random.Generator, int or None
        Randomness of the phases ``phi_k``, ``psi_i`` (SPEC 7).

    Returns
    -------
    numpy.ndarray
        float64, shape ``(n_samples,)``.
    """
    fs = _positive("sample_rate_Hz", sample_rate_Hz)
    fm = _positive("mesh_frequency_Hz", mesh_frequency_Hz)
    if len(shaft_frequencies_Hz) != len(modulation_depths):
        raise ValueError(f"`modulation_depths` must have one value per shaft frequency "
                         f"({len(shaft_frequencies_Hz)}), had {len(modulation_depths)}")
    if any(not 0 <= m < 1 for m in modulation_depths):
        raise ValueError(f"`modulation_depths` must lie in [0, 1), were {list(modulation_depths)}")
    if any(not (math.isfinite(a) and a >= 0) for a in amplitudes):
        raise ValueError(f"`amplitudes` must be finite and >= 0, were {list(amplitudes)}")
    gen = np.random.default_rng(rng)
    t = np.arange(int(n_samples)) / fs
    envelope = np.ones_like(t)
    for f_s, mu in zip(shaft_frequencies_Hz, modulation_depths, strict=True):
        envelope += mu * np.cos(2 * np.pi * _positive("shaft_frequencies_Hz", f_s) * t
                                + gen.uniform(0, 2 * np.pi))
    out = np.zeros_like(t)
    for k, a in enumerate(amplitudes, 1):
        out += a * np.sin(2 * np.pi * k * fm * t + gen.uniform(0, 2 * np.pi))
    return out * envelope


def add_sensor_noise(x: np.ndarray, snr_dB: float,
                     rng: np.random.Generator | int | None = None) -> tuple[np.ndarray, float]:
    """Add white Gaussian noise at a broadband signal-to-noise ratio.

    Parameters
    ----------
    x : numpy.ndarray
        Noiseless record.
    snr_dB : float
        ``20 log10(rms(x - mean(x)) / sigma)`` (dB).
    rng : numpy.random.Generator, int or None
        Randomness of the noise (SPEC 7).

    Returns
    -------
    numpy.ndarray
        ``x + noise``.
    float
        The noise standard deviation ``sigma`` (unit of ``x``).
    """
    if not math.isfinite(snr_dB):
        raise ValueError(f"`snr_dB` must be finite, was {snr_dB!r}")
    a = np.asarray(x, dtype=float)
    sigma = float(np.std(a)) * 10.0 ** (-float(snr_dB) / 20.0)
    gen = np.random.default_rng(rng)
    return a + gen.normal(0.0, sigma, a.shape), sigma


def quantise(x: np.ndarray, lsb: float) -> np.ndarray:
    """Round to a multiple of the acquisition's least significant bit ``lsb`` (unit of ``x``)."""
    step = _positive("lsb", lsb)
    return np.round(np.asarray(x, dtype=float) / step) * step
