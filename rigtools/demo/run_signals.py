r"""The signals of one demo run: three accelerometer axes and the slow rig signals, from its truth.

A triaxial accelerometer on the pinion bearing cover (channels ``accel_x``, ``accel_y``,
``accel_z``) sees, per :mod:`rigtools.demo.modal_response`:

* the **mesh mode** of the run (:class:`~rigtools.demo.truth.RunTruth`: ``f_n`` from
  :mod:`models.thermal`, ``zeta = 0.03``) driven by the broadband dynamic mesh force, whose
  level grows with the load: peak PSD ``P_m (T / 302 N m)^0.66`` with ``P_m = 0.03
  (m/s^2)^2/Hz``, seen with the gains ``(1.0, 0.45, 0.75)`` on x, y, z;
* the **housing mode** (4.9 kHz, ``zeta = 0.012``), the same in every run, driven by an
  independent broadband rig force: peak PSD ``0.016 (m/s^2)^2/Hz`` with the gains
  ``(0.5, 1.0, 0.6)``. It is taller than the mesh mode on y in every run, on z below about
  60 N m and on x below about 15 N m: the tallest peak of the whole run at 3.3 and 35.3 N m,
  the mesh mode (on x) at 183.4 and 302 N m;
* **mesh harmonics** 1-3 at ``f_m = z_1 n_1 / 60`` (400 Hz at 1500 rpm) with amplitudes
  ``A_1 = 0.5 + 4.5 T / 302 N m`` (m/s^2), ``A_2 = 0.45 A_1``, ``A_3 = 0.25 A_1``, amplitude-
  modulated by the pinion (12 %) and wheel (8 %) shaft rates (sidebands at ``k f_m +- f_shaft``),
  with the gains ``(1.0, 0.3, 0.6)``;
* white **sensor noise** 20 dB below the noiseless signal's RMS (broadband SNR), then rounding
  to the acquisition's least significant bit.

Slow signals at 10 Hz, quantised as a rig PLC logs them: ``PinionSpeed_rpm`` (0.3 rpm
scatter), ``Torque_Nm`` (0.2 % scatter), ``BulkTemp_C`` and ``OilTemp_C`` (a slow drift of
0.01 K/s centred on the run's value, 0.02 K scatter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from models.geometry import mesh_frequency_Hz
from rigtools.demo.modal_response import (
    add_sensor_noise,
    mesh_tones,
    mode_acceleration,
    quantise,
)
from rigtools.demo.truth import HousingMode, RunTruth

__all__ = ["REFERENCE_TORQUE_NM", "RunSignals", "SignalLevels", "run_signals"]

#: Torque at which the mesh-mode and mesh-tone levels are stated (N m; FZG load stage 9).
REFERENCE_TORQUE_NM: Final[float] = 302.0


@dataclass(frozen=True)
class SignalLevels:
    """Levels and mode shapes of the demo signals (module notes).

    Attributes
    ----------
    mesh_peak_psd : float
        Mesh-mode peak PSD at :data:`REFERENCE_TORQUE_NM` ((m/s^2)^2/Hz).
    mesh_load_exponent : float
        The mesh-mode peak PSD scales as ``(T / T_ref)`` to this power.
    housing_peak_psd : float
        Housing-mode peak PSD ((m/s^2)^2/Hz).
    mesh_gains, housing_gains, tone_gains : tuple of float
        Amplitude gain of each channel (x, y, z) for the mesh mode, the housing mode and the
        mesh tones.
    a1_floor_m_s2, a1_load_m_s2 : float
        ``A_1 = a1_floor + a1_load T / T_ref`` (m/s^2).
    harmonic_ratios : tuple of float
        ``A_k / A_1`` for k = 1, 2, 3.
    modulation_depths : tuple of float
        Amplitude modulation by the pinion and the wheel shaft rate (-).
    snr_dB : float
        Broadband signal-to-noise ratio of each channel (dB).
    """

    mesh_peak_psd: float = 0.03
    mesh_load_exponent: float = 0.66
    housing_peak_psd: float = 0.016
    mesh_gains: tuple[float, ...] = (1.0, 0.45, 0.75)
    housing_gains: tuple[float, ...] = (0.5, 1.0, 0.6)
    tone_gains: tuple[float, ...] = (1.0, 0.3, 0.6)
    a1_floor_m_s2: float = 0.5
    a1_load_m_s2: float = 4.5
    harmonic_ratios: tuple[float, ...] = (1.0, 0.45, 0.25)
    modulation_depths: tuple[float, float] = (0.12, 0.08)
    snr_dB: float = 20.0

    def mesh_peak(self, torque_Nm: float) -> float:
        """Mesh-mode peak PSD at a torque before the channel gains ((m/s^2)^2/Hz)."""
        return self.mesh_peak_psd * (float(torque_Nm) / REFERENCE_TORQUE_NM) ** (
            self.mesh_load_exponent)

    def tone_amplitudes(self, torque_Nm: float) -> tuple[float, ...]:
        """``A_1, A_2, A_3`` at a torque before the channel gains (m/s^2)."""
        a1 = self.a1_floor_m_s2 + self.a1_load_m_s2 * float(torque_Nm) / REFERENCE_TORQUE_NM
        return tuple(a1 * r for r in self.harmonic_ratios)


@dataclass(frozen=True)
class RunSignals:
    """What one demo run's sensors give.

    Attributes
    ----------
    channels : dict of str to numpy.ndarray
        ``accel_x``, ``accel_y``, ``accel_z`` (m/s^2), quantised to ``lsb_m_s2``.
    sample_rate_Hz : float
    start_time_s : float
        Logger time of sample 0 (s since the epoch).
    slow : dict of str to (numpy.ndarray, numpy.ndarray, str)
        Slow signal -> ``(time_s, values, unit)``.
    mesh_peak_psd, housing_peak_psd : dict of str to float
        Expected PSD of each mode at its peak on each channel ((m/s^2)^2/Hz).
    noise_sigma_m_s2 : dict of str to float
        Sensor-noise standard deviation of each channel (m/s^2).
    mesh_frequency_Hz : float
    lsb_m_s2 : float
    """

    channels: dict[str, np.ndarray]
    sample_rate_Hz: float
    start_time_s: float
    slow: dict[str, tuple[np.ndarray, np.ndarray, str]]
    mesh_peak_psd: dict[str, float] = field(default_factory=dict)
    housing_peak_psd: dict[str, float] = field(default_factory=dict)
    noise_sigma_m_s2: dict[str, float] = field(default_factory=dict)
    mesh_frequency_Hz: float = math.nan
    lsb_m_s2: float = math.nan

    def housing_taller_on(self) -> tuple[str, ...]:
        """Channels on which the housing mode's peak is taller than the mesh mode's."""
        return tuple(c for c in self.channels
                     if self.housing_peak_psd[c] > self.mesh_peak_psd[c])


def _quantised(x: np.ndarray, step: float) -> np.ndarray:
    return np.round(np.asarray(x, dtype=float) / step) * step


def run_signals(run: RunTruth, housing: HousingMode, *, z1: int, z2: int, duration_s: float,
                sample_rate_Hz: float = 25_600.0, lsb_m_s2: float, start_time_s: float,
                channels: tuple[str, ...] = ("accel_x", "accel_y", "accel_z"),
                levels: SignalLevels | None = None, slow_rate_Hz: float = 10.0,
                rng: np.random.Generator | int | None = None) -> RunSignals:
    """Synthesise one run's accelerometer and slow signals (module notes).

    Parameters
    ----------
    run : RunTruth
        Conditions and mesh mode of the run.
    housing : HousingMode
    z1, z2 : int
        Teeth of pinion and wheel.
    duration_s : float
        Length (s).
    sample_rate_Hz : float
        Accelerometer rate (Hz).
    lsb_m_s2 : float
        Least significant bit of the acquisition (m/s^2).
    start_time_s : float
        Logger time of sample 0.
    channels : tuple of str
        Names of the axes (as many as the gains of ``levels``).
    levels : SignalLevels, optional
    slow_rate_Hz : float
        Rate of the slow signals (Hz).
    rng : numpy.random.Generator, int or None
        Randomness (SPEC 7).

    Returns
    -------
    RunSignals
    """
    lv = levels or SignalLevels()
    if len(channels) != len(lv.mesh_gains):
        raise ValueError(f"`channels` must name {len(lv.mesh_gains)} axes, named {channels}")
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"`duration_s` must be > 0, was {duration_s!r}")
    gen = np.random.default_rng(rng)
    fs = float(sample_rate_Hz)
    n = round(duration_s * fs)
    f_mesh = float(mesh_frequency_Hz(run.speed_rpm, z1))
    shafts = (f_mesh / z1, f_mesh / z2)
    p_mesh = lv.mesh_peak(run.torque_Nm)
    mesh = mode_acceleration(n, fs, run.mesh.f_n_Hz, run.mesh_zeta, p_mesh, gen)
    house = mode_acceleration(n, fs, housing.f_n_Hz, housing.zeta, lv.housing_peak_psd, gen)
    tones = mesh_tones(n, fs, f_mesh, lv.tone_amplitudes(run.torque_Nm),
                       shaft_frequencies_Hz=shafts, modulation_depths=lv.modulation_depths,
                       rng=gen)
    out: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    for c, gm, gh, gt in zip(channels, lv.mesh_gains, lv.housing_gains, lv.tone_gains,
                             strict=True):
        noisy, sigma = add_sensor_noise(gm * mesh + gh * house + gt * tones, lv.snr_dB, gen)
        out[c] = quantise(noisy, lsb_m_s2)
        sigmas[c] = sigma
    ts = np.arange(max(1, math.ceil(duration_s * slow_rate_Hz - 1e-9))) / slow_rate_Hz
    drift = 0.01 * (ts - ts.mean())
    t_slow = start_time_s + ts
    slow = {
        "PinionSpeed_rpm": (t_slow, _quantised(run.speed_rpm + gen.normal(0, 0.3, ts.size), 0.1),
                            "rpm"),
        "Torque_Nm": (t_slow, _quantised(run.torque_Nm * (1 + gen.normal(0, 0.002, ts.size)),
                                         0.02), "N.m"),
        "BulkTemp_C": (t_slow, _quantised(run.bulk_temperature_C + drift
                                          + gen.normal(0, 0.02, ts.size), 0.01), "degC"),
        "OilTemp_C": (t_slow, _quantised(run.oil_temperature_C + drift
                                         + gen.normal(0, 0.02, ts.size), 0.01), "degC"),
    }
    return RunSignals(
        channels=out, sample_rate_Hz=fs, start_time_s=float(start_time_s), slow=slow,
        mesh_peak_psd={c: g * g * p_mesh for c, g in zip(channels, lv.mesh_gains, strict=True)},
        housing_peak_psd={c: g * g * lv.housing_peak_psd
                          for c, g in zip(channels, lv.housing_gains, strict=True)},
        noise_sigma_m_s2=sigmas, mesh_frequency_Hz=f_mesh, lsb_m_s2=float(lsb_m_s2))
