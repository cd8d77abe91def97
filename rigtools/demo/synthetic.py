"""A synthetic rig run: accelerometer signals with mesh harmonics and a damped resonance.

Physically plausible, with every ingredient known exactly, so that analysis results can be
checked against the truth: the pinion of an FZG type C pair (z1 = 16) at 1500 rpm meshes at
f_m = z1 n1 / 60 = 400 Hz; the bearing-cover accelerometers see mesh harmonics 1..3 plus the
response of a structural mode (f_n = 3.15 kHz, between mesh harmonics 7 and 8, zeta = 0.02)
to broadband excitation, plus
sensor noise. Values are quantised to the reference DBC's int16 step (0.015 m/s^2) so that a
CAN round trip is exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import signal as sps

from models.geometry import mesh_frequency_Hz

__all__ = ["SyntheticRun", "synthetic_run"]

ACCEL_LSB_M_S2 = 0.015  # data_schemas/rig_reference.dbc, Acc*_S* scale


@dataclass(frozen=True)
class SyntheticRun:
    """A synthetic run and the truth it was made from.

    Attributes
    ----------
    channels : dict
        name -> accelerometer samples (m/s^2), float64, quantised to ``ACCEL_LSB_M_S2``.
    sample_rate_Hz : float
    start_time_s : float
        Logger time of sample 0 (s, UNIX epoch).
    slow : dict
        name -> (time_s, values, unit) of speed, torque and temperatures.
    truth : dict
        Mesh frequency (Hz), harmonic amplitudes (m/s^2), natural frequency (Hz), damping ratio.
    metadata : dict
        Run metadata (run id, rig, gear set, conditions).
    """

    channels: dict[str, np.ndarray]
    sample_rate_Hz: float
    start_time_s: float
    slow: dict[str, tuple[np.ndarray, np.ndarray, str]]
    truth: dict[str, float] = field(default_factory=dict)
    metadata: dict[str, Any] = field(default_factory=dict)


def synthetic_run(
    duration_s: float = 4.0,
    sample_rate_Hz: float = 25_600.0,
    n_channels: int = 4,
    speed_rpm: float = 1500.0,
    z1: int = 16,
    z2: int = 24,
    torque_Nm: float = 302.0,
    bulk_temperature_C: float = 90.0,
    f_n_Hz: float = 3150.0,
    zeta: float = 0.02,
    rng: np.random.Generator | int | None = 0,
    start_time_s: float = 1_763_800_000.0,
    multiple_of: int = 3,
) -> SyntheticRun:
    """Make a synthetic run (see the module docstring for what it contains).

    Parameters
    ----------
    duration_s : float
        Length (s).
    sample_rate_Hz : float
        Accelerometer rate (Hz).
    n_channels : int
        Number of accelerometers, named ``accel_1`` ... .
    speed_rpm : float
        Pinion speed (rpm); mesh frequency ``z1 * speed_rpm / 60``.
    z1, z2 : int
        Pinion and wheel teeth (FZG type C: 16 and 24).
    torque_Nm, bulk_temperature_C : float
        Logged conditions (slow signals and metadata).
    f_n_Hz, zeta : float
        Structural mode: natural frequency (Hz) and damping ratio.
    rng : numpy.random.Generator, int or None
        Randomness (SPEC 7).
    start_time_s : float
        Logger time of sample 0.
    multiple_of : int
        The sample count is rounded down to a multiple of this (3: whole reference CAN frames).
    """
    gen = np.random.default_rng(rng)
    fs = float(sample_rate_Hz)
    n = round(duration_s * fs) // multiple_of * multiple_of
    t = np.arange(n) / fs
    f_mesh = float(mesh_frequency_Hz(speed_rpm, z1))
    amps = (4.0, 1.5, 0.8)
    # Second-order resonance as a digital filter with the SDOF's poles mapped exactly
    # (impulse invariance, z = exp(s T)): peak at f_n sqrt(1 - 2 zeta^2) and half-power damping
    # zeta, unlike a bilinear transform, which narrows the bandwidth by sin(2 theta) / (2 theta).
    wn = 2 * np.pi * f_n_Hz
    wd = wn * np.sqrt(1 - zeta**2)
    r = np.exp(-zeta * wn / fs)
    a = np.array([1.0, -2 * r * np.cos(wd / fs), r * r])
    # Acceleration response (the accelerometers' unit): the displacement filter times a second
    # difference, zero at DC, scaled to the displacement filter's gain at f_n (the accelerance
    # -w^2 H of the analogue SDOF, up to that constant).
    b = a.sum() / (4 * np.sin(wn / fs / 2) ** 2) * np.array([1.0, -2.0, 1.0])
    channels = {}
    for k in range(n_channels):
        gain = 1.0 / (1 + 0.3 * k)
        phases = gen.uniform(0, 2 * np.pi, 3)
        mesh = sum(A * np.sin(2 * np.pi * (h + 1) * f_mesh * t + ph)
                   for h, (A, ph) in enumerate(zip(amps, phases, strict=True)))
        reson = sps.lfilter(b, a, gen.normal(0.0, 6.0, n))
        x = gain * (mesh + reson) + gen.normal(0.0, 0.2, n)
        channels[f"accel_{k + 1}"] = np.round(x / ACCEL_LSB_M_S2) * ACCEL_LSB_M_S2
    ts = np.arange(0.0, duration_s, 0.1)
    t_slow = start_time_s + ts

    def quantised(x: np.ndarray, step: float) -> np.ndarray:  # to the DBC resolution
        return np.round(np.asarray(x, float) / step) * step

    drift = 0.01 * ts  # gear bodies warming slowly (K)
    slow = {
        "PinionSpeed_rpm": (t_slow, quantised(speed_rpm + gen.normal(0, 0.5, ts.size), 0.25),
                            "rpm"),
        "WheelSpeed_rpm": (t_slow, quantised(np.full(ts.size, speed_rpm * z1 / z2), 0.25), "rpm"),
        "Torque_Nm": (t_slow, quantised(torque_Nm + gen.normal(0, 0.5, ts.size), 0.05), "N.m"),
        "BulkTemp_C": (t_slow, quantised(bulk_temperature_C + drift, 0.01), "degC"),
        "OilTemp_C": (t_slow, quantised(bulk_temperature_C - 2 + drift, 0.01), "degC"),
        "PinionTemp_C": (t_slow, quantised(bulk_temperature_C + 1.5 + drift, 0.01), "degC"),
        "WheelTemp_C": (t_slow, quantised(bulk_temperature_C + 0.8 + drift, 0.01), "degC"),
    }
    truth = {"mesh_frequency_Hz": f_mesh, "A1": amps[0], "A2": amps[1], "A3": amps[2],
             "f_n_Hz": f_n_Hz, "zeta": zeta}
    metadata = {"run_id": "demo-LS9-90C", "rig": "FZG back-to-back (synthetic)",
                "gear_set": "fzg-c", "z1": z1,
                "conditions": {"torque_Nm": torque_Nm, "bulk_temperature_C": bulk_temperature_C,
                               "speed_rpm": speed_rpm}}
    return SyntheticRun(channels, fs, float(start_time_s), slow, truth, metadata)
