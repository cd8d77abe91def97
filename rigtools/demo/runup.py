r"""The demo's run-up run: a speed ramp through the mesh resonance of a known SDOF model.

One recording of the demo campaign (:mod:`rigtools.demo.campaign`) on another gear pair than
the FZG-C backlash study: the **Kahraman-Blankenship** pair (``[[run]] gear_set =
"kahraman-blankenship"``), whose mesh resonance a rig reaches (``f_m = f_n`` at about 3700 rpm;
FZG-C's at about 20 000 rpm, which no FZG rig runs). The run ramps the pinion speed
600 -> 5000 -> 600 rpm linearly, with no dwell anywhere (a plateau of
``[analysis] min_step_duration_s`` would turn the run's Arms rows into step rows), and the
accelerometers see the DTE acceleration of the model along that ramp.

The truth (``truth.json`` ``"runup"``, :class:`~rigtools.demo.truth.RunUpTruth`)
-------------------------------------------------------------------------------
The VVMS model of seed 003 (:func:`models.dynamics.sdof_from_mesh_cycle`, dead-zone backlash)
of the pair at the run's torque, in the run-up calibration's parametrisation (issue 20
contract):

* stiffness scale ``s``: every tooth compliance is ``C / s``; exactly the mesh cycle at
  ``T / s`` (error-free involutes, corner contact, potential-energy compliance with Hertz:
  :func:`models.stiffness.pair_compliance`, 200 phases) with its stiffnesses times ``s``;
* reference stiffness ``k_ref = s kbar_F0`` (``kbar_F0`` the error-free mean FVMS at the
  torque, load independent), ``m_e`` from :func:`models.geometry.inertia.pair_equivalent_mass`,
  ``omega_n = sqrt(k_ref / m_e)``, ``mesh_natural_frequency_Hz = omega_n / 2 pi``, ``zeta``
  relative to ``k_ref``;
* fluctuation scale ``eps``: multiplies the alternating part of the VVMS;
* ``backlash``: the total ``2 b`` on the line of action (136 um, the pair's stated value);
* channel gains ``G_c``: housing acceleration = ``G_c`` times the DTE acceleration
  (:mod:`rigtools.demo.runup_signal`: the alternating mesh force is ``-m_e`` times the DTE
  acceleration, the housing accelerance is flat), so that mesh harmonic ``h`` appears with
  ``a_{c,h} = G_c (2 pi h f_m)^2 D_h`` (``D_h`` the DTE amplitude, peak): the contract's
  observation model, by another route than its derivation;
* white sensor noise ``snr_dB`` below each channel's noiseless RMS, then the MCAP logger's
  24-bit step.

Values: ``T = 300 N m``, ``zeta = 0.025``, ``s = 0.9``, ``eps = 1``, ``2 b = 136 um``,
``G = (1e-2, 4e-3, 7e-3)`` on x, y, z. Then ``f_n = 2957 Hz`` (``k_ref``), the VVMS's own mean
stiffness at ``T / s`` puts the linear resonance at 3086 Hz (3703 rpm with ``z_1 = 50``); the
drive flanks separate near the resonance (softening: the up sweep jumps down, the down sweep
jumps up, at different speeds), the back flanks are not reached
(``truth["runup"]["backside_impact"]``), so the run-up does not identify the backlash.

The ramp, and why its response is quasi-static
----------------------------------------------
Speed linear in time, 600 -> 5000 rpm in ``ramp_duration_s`` and back (6 s each way for
``"ci"``, 16 s for ``"full"``). Near the resonance the mesh frequency moves at
``z_1 (5000 - 600) / 60 / ramp`` Hz/s (611 Hz/s for 6 s), so it crosses the half-power band
``2 zeta f_n`` (about 154 Hz) in 0.25 s, against the mode's settling time
``1 / (zeta omega_n) = 2.1 ms``: over 100 settling times (:attr:`RunUpSpec.crossing_ratio`,
checked > 50 when a spec is made). A jump settles within about ``5 / (zeta omega_n)`` = 10 ms,
in which ``f_m`` moves 6 Hz (0.2 %).

No plateau: :func:`rigtools.analysis.speed.detect_speed_steps` (1 % band, 1 s) sees none, the
top included: a 1 s window centred on the top spreads over ``rate / 2`` (367 rpm for ci,
137 rpm for full, whose 16 s per direction keep that 39 % above the band's 99 rpm; a 20 s
ramp would keep only 11 %).

Signals: 51.2 kHz (at 25.6 kHz the resampler's passband would cut the third mesh harmonic
above ``f_m = 3.58`` kHz), channels ``accel_x``, ``accel_y``, ``accel_z`` as the FZG runs,
``PinionSpeed_rpm`` logged at 100 Hz (0.3 rpm scatter, 0.1 rpm steps, as the demo logs
speed), ``Torque_Nm``, ``BulkTemp_C``, ``OilTemp_C`` at 10 Hz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np

from models.dynamics import SDOFModel, sdof_from_mesh_cycle, sweep
from models.geometry import GearSet, load_gear_set, mesh_frequency_Hz
from models.geometry.inertia import pair_equivalent_mass
from models.stiffness import Harmonics, pair_compliance, prepare_mesh_cycle, tabulate_compliance
from rigtools.calibration.runup_forward import jump_frequencies
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.modal_response import add_sensor_noise, quantise
from rigtools.demo.runup_signal import RunUpResponse, runup_response
from rigtools.demo.truth import RunUpTruth
from rigtools.ingest import RunMetadata

__all__ = [
    "RUNUP_CALIBRATION",
    "RUNUP_GEAR_SET",
    "RunUpModel",
    "RunUpSignals",
    "RunUpSpec",
    "crossing_ratio",
    "runup_arms_path",
    "runup_campaign_lines",
    "runup_model",
    "runup_signals",
    "runup_spec",
    "runup_truth",
    "speed_ramp",
    "write_runup_recording",
]

#: The shipped gear set of the run-up run.
RUNUP_GEAR_SET: Final[str] = "kahraman-blankenship"
#: ``[calibration.runup]`` settings of the generated campaign, by demo size (contract keys).
RUNUP_CALIBRATION: Final[dict[str, dict[str, int]]] = {
    "ci": {"walkers": 16, "max_steps": 600, "max_speed_points": 40},
    # 16 walkers, 30 windows per direction and at most 800 steps: the three models calibrate
    # in minutes, not hours. A log-probability sweeps the whole ramp through continuation
    # nodes 0.3 % apart (those far from a fold skipped); VVMS's tau is 35-50 steps after the
    # warm-up (6 free parameters; 2700 steps, 9.5 min, to the rule at 50 windows), so the
    # report says the chains are not converged.
    "full": {"walkers": 16, "max_speed_points": 30, "max_steps": 800},
}
#: The SDOF models the demo campaign calibrates against the run-up.
_MODELS: Final[tuple[str, ...]] = ("fvms", "vvms", "lste")
_RAMP_S: Final[dict[str, float]] = {"ci": 6.0, "full": 16.0}
_N_PHASES: Final[int] = 200      # phases of the mesh cycle (as the calibration's cycle bank)
_MIN_CROSSING_RATIO: Final[float] = 50.0
_RIG: Final[str] = "Kahraman-Blankenship rig (synthetic demo run-up)"


@dataclass(frozen=True)
class RunUpSpec:
    """What the run-up run is made from (module notes).

    Attributes
    ----------
    run_id : str
    gear_set : str
        Shipped gear set.
    torque_Nm : float
        Pinion torque (N m).
    speed_low_rpm, speed_high_rpm : float
        Pinion speed at the start and end, and at the top of the ramp (rpm).
    ramp_duration_s : float
        Duration of the run-up, and of the run-down (s).
    zeta : float
        Damping ratio relative to ``k_ref = s kbar_F0`` (-).
    stiffness_scale : float
        ``s`` (-).
    fluctuation_scale : float
        ``eps`` (-).
    backlash_m : float
        Total backlash ``2 b`` on the line of action (m).
    gains : tuple of float
        ``G_c`` of ``accel_x``, ``accel_y``, ``accel_z`` (-).
    snr_dB : float
        Broadband signal-to-noise ratio of each channel (dB).
    sample_rate_Hz : float
        Accelerometer rate (Hz).
    speed_rate_Hz : float
        Rate of the logged speed (Hz).
    bulk_temperature_C, oil_temperature_C : float
        Logged conditions (degC).
    channels : tuple of str
    """

    run_id: str = "KB-runup-300Nm"
    gear_set: str = RUNUP_GEAR_SET
    torque_Nm: float = 300.0
    speed_low_rpm: float = 600.0
    speed_high_rpm: float = 5000.0
    ramp_duration_s: float = 20.0
    zeta: float = 0.025
    stiffness_scale: float = 0.9
    fluctuation_scale: float = 1.0
    backlash_m: float = 136e-6
    gains: tuple[float, ...] = (1e-2, 4e-3, 7e-3)
    snr_dB: float = 30.0
    sample_rate_Hz: float = 51_200.0
    speed_rate_Hz: float = 100.0
    bulk_temperature_C: float = 45.0
    oil_temperature_C: float = 40.0
    channels: tuple[str, ...] = ("accel_x", "accel_y", "accel_z")

    @property
    def duration_s(self) -> float:
        """Length of the recording (s): up and down."""
        return 2.0 * self.ramp_duration_s

    def check(self) -> None:
        """Raise ``ValueError`` on a spec the demo cannot make (module notes)."""
        for name in ("torque_Nm", "speed_low_rpm", "ramp_duration_s", "zeta", "stiffness_scale",
                     "sample_rate_Hz", "speed_rate_Hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"`{name}` must be finite and > 0, was {v!r}")
        if not self.speed_high_rpm > self.speed_low_rpm:
            raise ValueError(f"`speed_high_rpm` must be > `speed_low_rpm`, were "
                             f"{self.speed_high_rpm!r} and {self.speed_low_rpm!r}")
        if not (math.isfinite(self.backlash_m) and self.backlash_m > 0):
            raise ValueError(f"`backlash_m` must be finite and > 0, was {self.backlash_m!r}")
        if not (math.isfinite(self.fluctuation_scale) and self.fluctuation_scale >= 0):
            raise ValueError(f"`fluctuation_scale` must be >= 0, was {self.fluctuation_scale!r}")
        if len(self.gains) != len(self.channels):
            raise ValueError(f"`gains` must give one gain per channel of {self.channels}, gave "
                             f"{len(self.gains)}")


def runup_spec(size: Literal["full", "ci"] = "full") -> RunUpSpec:
    """The run-up run of a demo size: one torque (300 N m), 2 x 6 s (ci) or 2 x 16 s (full)."""
    if size not in _RAMP_S:
        raise ValueError(f"`size` must be one of {tuple(_RAMP_S)}, was {size!r}")
    return RunUpSpec(ramp_duration_s=_RAMP_S[size])


def speed_ramp(spec: RunUpSpec) -> tuple[np.ndarray, np.ndarray]:
    """Knots of the pinion speed: ``(time_s, speed_rpm)``, linear in between (from t = 0)."""
    T = spec.ramp_duration_s
    return (np.array([0.0, T, 2.0 * T]),
            np.array([spec.speed_low_rpm, spec.speed_high_rpm, spec.speed_low_rpm]))


@dataclass(frozen=True, eq=False)
class RunUpModel:
    """The true SDOF model of the run-up and its scaling.

    Attributes
    ----------
    model : SDOFModel
        VVMS of the cycle at ``T / s``, ``reference_stiffness = kbar_F0``, fluctuation scaled.
    gear : GearSet
    equivalent_mass_kg : float
        ``m_e`` (kg).
    reference_stiffness_N_m : float
        ``kbar_F0`` (N/m).
    omega_n_rad_s : float
        ``sqrt(s kbar_F0 / m_e)`` (rad/s).
    model_natural_frequency_Hz : float
        With the model's own mean stiffness: ``sqrt(s kbar_V(T/s) / m_e) / 2 pi`` (Hz), where
        the linear resonance is.
    """

    model: SDOFModel
    gear: GearSet
    equivalent_mass_kg: float
    reference_stiffness_N_m: float
    omega_n_rad_s: float
    model_natural_frequency_Hz: float

    @property
    def natural_frequency_Hz(self) -> float:  # noqa: N802 (unit in the name)
        """``mesh_natural_frequency_Hz = omega_n / 2 pi`` (Hz), the contract's definition."""
        return self.omega_n_rad_s / (2 * math.pi)

    @property
    def z1(self) -> int:
        """Pinion teeth."""
        return int(self.gear.pair.pinion.teeth)


def _fluctuation(h: object, eps: float) -> Harmonics:
    if not isinstance(h, Harmonics):
        raise TypeError(f"expected the cycle's Fourier series, got {type(h).__name__}")
    return Harmonics(h.mean, np.asarray(h.amplitude) * eps, np.asarray(h.phase_rad))


def runup_model(spec: RunUpSpec, *, kind: str = "vvms") -> RunUpModel:
    """The true model of ``spec`` (module notes); ``kind`` another SDOF model for checks.

    Parameters
    ----------
    spec : RunUpSpec
    kind : {"vvms", "fvms", "lste"}
        The model (the truth is VVMS).

    Returns
    -------
    RunUpModel
    """
    spec.check()
    gear = load_gear_set(spec.gear_set)
    pair = gear.pair
    comp = tabulate_compliance(pair, lambda s: pair_compliance(pair, s).total_m_per_N)
    geo = prepare_mesh_cycle(pair, comp, n_phases=_N_PHASES)
    s = spec.stiffness_scale
    k_f0 = float(geo.solve(spec.torque_Nm).fvms_harmonics.mean)
    m_e = float(pair_equivalent_mass(pair))
    base = sdof_from_mesh_cycle(geo.solve(spec.torque_Nm / s), kind, zeta=spec.zeta,
                                backlash_m=0.5 * spec.backlash_m, reference_stiffness=k_f0)
    eps = spec.fluctuation_scale
    model = SDOFModel(
        zeta=base.zeta, force=base.force, backlash=base.backlash,
        stiffness=_fluctuation(base.stiffness, eps), error=_fluctuation(base.error, eps),
        length_scale_m=base.length_scale_m, mean_stiffness_N_m=base.mean_stiffness_N_m,
        kind=base.kind,
        back_error=None if base.back_error is None else _fluctuation(base.back_error, eps))
    wn = math.sqrt(s * k_f0 / m_e)
    return RunUpModel(model=model, gear=gear, equivalent_mass_kg=m_e,
                      reference_stiffness_N_m=k_f0, omega_n_rad_s=wn,
                      model_natural_frequency_Hz=wn * math.sqrt(model.stiffness.mean)
                      / (2 * math.pi))


def runup_arms_path(spec: RunUpSpec, z1: int, points: int = 300) -> np.ndarray:
    """Mesh frequencies (Hz) of the ramp in time order: ``points`` up, then the same down."""
    lo, hi = (float(mesh_frequency_Hz(v, z1)) for v in (spec.speed_low_rpm, spec.speed_high_rpm))
    up = np.linspace(lo, hi, int(points))
    return np.concatenate([up, up[::-1]])


def runup_truth(spec: RunUpSpec, rm: RunUpModel | None = None, *,
                points: int = 300) -> RunUpTruth:
    """The truth of the run-up: parameters, ``f_n``, and the steady sweep's jumps and flags.

    The jump frequencies and the flank flags are the model's periodic steady states along the
    ramp's path in time order (:func:`models.dynamics.sweep.sweep`, ``points`` per direction,
    128 steps per period, the state carried through the top), what a calibration's model gives
    at the true parameters; a jump is where a direction leaves the hysteresis band
    (:func:`rigtools.calibration.runup_forward.jump_frequencies`, the calibration's own
    definition, on ``log Arms`` of the housing form ``(2 pi f_m)^2 sqrt(sum h^4 D_h^2)``), at
    the geometric mean of its two points.

    Parameters
    ----------
    spec : RunUpSpec
    rm : RunUpModel, optional
        :func:`runup_model` of ``spec`` (made when not given).
    points : int
        Sweep points per direction.

    Returns
    -------
    RunUpTruth
    """
    rm = runup_model(spec) if rm is None else rm
    ratio = crossing_ratio(spec, rm)
    if ratio < _MIN_CROSSING_RATIO:
        raise ValueError(f"the ramp crosses the resonance in {ratio:.0f} settling times, under "
                         f"{_MIN_CROSSING_RATIO:g}: not quasi-static (a longer "
                         f"`ramp_duration_s` than {spec.ramp_duration_s!r} s)")
    path = runup_arms_path(spec, rm.z1, points)
    res = sweep(rm.model, 2 * math.pi * path / rm.omega_n_rad_s)
    h = np.arange(1, 4)
    arms = (2 * math.pi * path) ** 2 * res.length_scale_m * np.sqrt(
        (h ** 4 * res.amplitudes ** 2).sum(axis=1))
    n = int(points)
    jumps = jump_frequencies(np.log(arms), path, np.array(["up"] * n + ["down"] * n, dtype=object))
    up, down = float(jumps["up"]), float(jumps["down"])
    return RunUpTruth(
        run_id=spec.run_id, gear_set=spec.gear_set, model=rm.model.kind,
        torque_Nm=spec.torque_Nm, zeta=spec.zeta, stiffness_scale=spec.stiffness_scale,
        fluctuation_scale=spec.fluctuation_scale, backlash_m=spec.backlash_m,
        gains=dict(zip(spec.channels, (float(g) for g in spec.gains), strict=True)),
        mesh_natural_frequency_Hz=rm.natural_frequency_Hz,
        model_natural_frequency_Hz=rm.model_natural_frequency_Hz,
        reference_stiffness_N_m=rm.reference_stiffness_N_m,
        equivalent_mass_kg=rm.equivalent_mass_kg, pinion_teeth=rm.z1,
        jump_frequency_up_Hz=up, jump_frequency_down_Hz=down,
        contact_loss=bool(res.contact_loss.any()),
        backside_impact=bool(res.backside_impact.any()),
        speed_low_rpm=spec.speed_low_rpm, speed_high_rpm=spec.speed_high_rpm,
        ramp_duration_s=spec.ramp_duration_s, settling_time_s=1.0 / (spec.zeta
                                                                     * rm.omega_n_rad_s),
        crossing_ratio=ratio)


def crossing_ratio(spec: RunUpSpec, rm: RunUpModel) -> float:
    """Time to cross the half-power band ``2 zeta f_n`` over the settling time ``1/(zeta w_n)``.

    At the ramp's rate of mesh frequency (constant: a linear ramp), with ``f_n`` the model's
    own linear resonance. Quasi-static when large (module notes).
    """
    rate = rm.z1 * (spec.speed_high_rpm - spec.speed_low_rpm) / 60.0 / spec.ramp_duration_s
    crossing = 2 * spec.zeta * rm.model_natural_frequency_Hz / rate
    return crossing * spec.zeta * rm.omega_n_rad_s


@dataclass(frozen=True, eq=False)
class RunUpSignals:
    """The run-up's sensor signals.

    Attributes
    ----------
    channels : dict of str to numpy.ndarray
        Accelerometer samples (m/s^2), noisy and quantised.
    sample_rate_Hz : float
    start_time_s : float
        Logger time of sample 0 (s since the epoch).
    slow : dict of str to (numpy.ndarray, numpy.ndarray, str)
        ``(time_s, values, unit)`` of the slow signals.
    noise_sigma_m_s2 : dict of str to float
    response : RunUpResponse
        The noiseless model response (DTE, its acceleration, phase, flags).
    """

    channels: dict[str, np.ndarray]
    sample_rate_Hz: float
    start_time_s: float
    slow: dict[str, tuple[np.ndarray, np.ndarray, str]]
    noise_sigma_m_s2: dict[str, float]
    response: RunUpResponse


def _quantised(x: np.ndarray, step: float) -> np.ndarray:
    return np.round(np.asarray(x, dtype=float) / step) * step


def runup_signals(spec: RunUpSpec, rm: RunUpModel, *, start_time_s: float, lsb_m_s2: float,
                  rng: np.random.Generator | int | None = None,
                  steps_per_period: int = 128) -> RunUpSignals:
    """Integrate the model along the ramp and make the sensor signals (module notes).

    Parameters
    ----------
    spec : RunUpSpec
    rm : RunUpModel
    start_time_s : float
        Logger time of sample 0 (s).
    lsb_m_s2 : float
        Acquisition step (m/s^2).
    rng : numpy.random.Generator, int or None
        Randomness of the noise and slow-signal scatter (SPEC 7).
    steps_per_period : int
        RK4 steps per mesh period at the top speed at least.

    Returns
    -------
    RunUpSignals
    """
    gen = np.random.default_rng(rng)
    t_k, n_k = speed_ramp(spec)
    resp = runup_response(rm.model, rm.omega_n_rad_s, t_k, mesh_frequency_Hz(n_k, rm.z1),
                          sample_rate_Hz=spec.sample_rate_Hz, steps_per_period=steps_per_period)
    out: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    for c, g in zip(spec.channels, spec.gains, strict=True):
        noisy, sigma = add_sensor_noise(g * resp.dte_acceleration_m_s2, spec.snr_dB, gen)
        out[c] = quantise(noisy, lsb_m_s2)
        sigmas[c] = sigma
    t_fast = np.arange(max(1, math.ceil(spec.duration_s * spec.speed_rate_Hz - 1e-9))
                       ) / spec.speed_rate_Hz
    t_slow = np.arange(max(1, math.ceil(spec.duration_s * 10.0 - 1e-9))) / 10.0
    speed = np.interp(t_fast, t_k, n_k)
    drift = 0.01 * (t_slow - t_slow.mean())
    slow = {
        "PinionSpeed_rpm": (start_time_s + t_fast,
                            _quantised(speed + gen.normal(0, 0.3, t_fast.size), 0.1), "rpm"),
        "Torque_Nm": (start_time_s + t_slow, _quantised(
            spec.torque_Nm * (1 + gen.normal(0, 0.002, t_slow.size)), 0.02), "N.m"),
        "BulkTemp_C": (start_time_s + t_slow, _quantised(
            spec.bulk_temperature_C + drift + gen.normal(0, 0.02, t_slow.size), 0.01), "degC"),
        "OilTemp_C": (start_time_s + t_slow, _quantised(
            spec.oil_temperature_C + drift + gen.normal(0, 0.02, t_slow.size), 0.01), "degC"),
    }
    return RunUpSignals(channels=out, sample_rate_Hz=spec.sample_rate_Hz,
                        start_time_s=float(start_time_s), slow=slow, noise_sigma_m_s2=sigmas,
                        response=resp)


def write_runup_recording(path: str | Path, spec: RunUpSpec, sig: RunUpSignals) -> Path:
    """Write the run-up as an MCAP file (``rigtools.AccelBatch``, protobuf, zstd)."""
    md = RunMetadata(run_id=spec.run_id, rig=_RIG, gear_set=spec.gear_set, conditions={
        "torque_Nm": spec.torque_Nm, "bulk_temperature_C": spec.bulk_temperature_C,
        "oil_temperature_C": spec.oil_temperature_C})
    return write_accel_mcap(
        path, {c: (v, sig.sample_rate_Hz, "m/s^2", 0, sig.start_time_s)
               for c, v in sig.channels.items()},
        sig.slow, md, encoding="protobuf", compression="zstd")


def _toml(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return repr(v)


def runup_campaign_lines(spec: RunUpSpec, file: str, size: str) -> tuple[list[str], list[str]]:
    """TOML of the run-up: the ``[calibration]`` tables, and its ``[[run]]``.

    Parameters
    ----------
    spec : RunUpSpec
    file : str
        The recording, relative to the campaign file.
    size : {'full', 'ci'}
        Picks :data:`RUNUP_CALIBRATION`.

    Returns
    -------
    tuple of list of str
        ``(calibration lines, run lines)``.
    """
    cal = [
        "[calibration]",
        "# The SDOF models (seed 003: FVMS, VVMS, LSTE) calibrated against the Arms run-up",
        f"# curves of the run-up run ({spec.run_id}); the natural-frequency calibration uses",
        "# the FZG-C runs only (the runs on the campaign's gear set).",
        "models = " + _toml(list(_MODELS)),
        "",
        "[calibration.runup]",
        f"# sized for the {size!r} demo",
    ]
    cal += [f"{k} = {_toml(v)}" for k, v in RUNUP_CALIBRATION[size].items()]
    run = [
        "[[run]]",
        f"id = {_toml(spec.run_id)}",
        f"file = {_toml(file)}",
        f"gear_set = {_toml(spec.gear_set)}",
        f"torque_Nm = {spec.torque_Nm!r}",
        f"bulk_temperature_C = {spec.bulk_temperature_C!r}",
        f"oil_temperature_C = {spec.oil_temperature_C!r}",
        "notes = " + _toml(
            f"MCAP, run-up {spec.speed_low_rpm:g} -> {spec.speed_high_rpm:g} -> "
            f"{spec.speed_low_rpm:g} rpm in 2 x {spec.ramp_duration_s:g} s at "
            f"{spec.sample_rate_Hz / 1e3:g} kHz, speed logged at {spec.speed_rate_Hz:g} Hz"),
    ]
    return cal, run
