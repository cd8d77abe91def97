r"""The response of an SDOF gear-pair model along a speed ramp, integrated in time (non-stationary).

The demo's run-up recording (:mod:`rigtools.demo.runup`) is made by *another route* than the
one the run-up calibration takes: the calibration sweeps the model through periodic steady
states, one mesh frequency at a time (:func:`models.dynamics.sweep.sweep` and its compiled
walker sweeps), while this module integrates the same equation once, in time, along the actual
speed ramp, the mesh phase advancing with the instantaneous speed. Where the ramp is slow
against the mode's settling time the two agree (checked in ``tests/demo/test_demo_runup.py``);
where it is not (right after a jump) the time integration is the truth the rig would show.

The equation (:mod:`models.dynamics.sdof`, one tooth-pair column for FVMS / VVMS / LSTE, one
per pair for ITMS), in the real time ``t``:

.. math::

    \ddot x + 2 \zeta \omega_n \dot x + \omega_n^2 \sum_j \big[k_{d,j}(\varphi)
    \max(x - e_{d,j}(\varphi) - b, 0) + k_{b,j}(\varphi) \min(x - e_{b,j}(\varphi) + b, 0)\big]
    = \omega_n^2 F

with ``x`` the DTE in units of the model's length scale ``L``, ``omega_n = sqrt(k_0 / m_e)``
(rad/s), and the tables ``k``, ``e`` of :meth:`~models.dynamics.sdof.SDOFModel.pair_tables`
over the mesh-cycle phase ``phi`` (cycles), interpolated linearly in phase. The phase is the
integral of the mesh frequency along the ramp,

.. math:: \varphi(t) = \int_0^t f_m(t')\, dt', \qquad f_m = z_1 n_1 / 60 ,

with ``f_m(t)`` piecewise linear between knots (so ``phi`` is piecewise quadratic and exact at
every RK4 stage). Classical fixed-step RK4 with ``steps_per_sample`` steps per output sample,
chosen by :func:`runup_response` so that the highest mesh frequency gets at least
``steps_per_period`` steps per mesh period. The output per sample: the DTE, its acceleration
(from the equation of motion at the sample, no differencing), the phase, and drive-side
contact loss / back-side impact at the samples.

The dynamic mesh force ``W = c x' + k f(x - e) = F_0 - m_e \ddot\delta`` has the alternating
part ``-m_e`` times the DTE acceleration (rigid shafts, the bearing force is the mesh force),
so a housing with a flat accelerance sees the DTE acceleration times a gain: that is what
:mod:`rigtools.demo.runup` records.

Checked (``tests/demo/test_demo_runup.py``): along a ramp through the resonance of the demo's
VVMS truth, the harmonics 1-3 of windows of 40 mesh cycles match the periodic steady sweep of
:func:`models.dynamics.sweep` along the same path to a median 0.05 % in the Arms form and
within 2.3 % off the jumps (the ramp's lag, largest right after a jump); the recorded
acceleration is ``(2 pi h f_m)^2`` times the DTE harmonic; with constant stiffness and no
contact loss the response is the linear FRF (0.5 % off the resonance, the ramp's lag of 1.7 %
at its peak at a sweep-rate parameter ``(df/dt) / (zeta f_n)^2 = 0.16``); undamped free
vibration through the dead zone keeps its energy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from models.dynamics import DynamicModel

__all__ = [
    "RunUpResponse",
    "integrate_ramp",
    "mesh_phase",
    "runup_response",
]


@njit(cache=True)
def _segment(t: float, lo: int, knot_t: np.ndarray) -> int:
    """Index of the knot interval holding ``t``, searched forward from ``lo`` (clamped)."""
    n = knot_t.size
    while lo < n - 2 and t >= knot_t[lo + 1]:
        lo += 1
    return lo


@njit(cache=True)
def _phase(t: float, lo: int, knot_t: np.ndarray, knot_f: np.ndarray,
           knot_phi: np.ndarray) -> float:
    """Mesh phase (cycles) at ``t`` in knot interval ``lo``: the integral of the linear ``f_m``.

    Exact inside the interval; outside the knots, the end intervals extended.
    """
    lo = _segment(t, lo, knot_t)
    dt = t - knot_t[lo]
    slope = (knot_f[lo + 1] - knot_f[lo]) / (knot_t[lo + 1] - knot_t[lo])
    return knot_phi[lo] + knot_f[lo] * dt + 0.5 * slope * dt * dt


@njit(cache=True)
def _cell(phi: float, m: int) -> tuple[int, int, float]:
    """Table rows either side of phase ``phi`` (cycles) in a table of ``m`` rows per cycle.

    Returns ``(i, i1, w)``: the row at or below, the next one (wrapping), and the weight of
    ``i1`` (0..1) that interpolates linearly between them.
    """
    u = (phi - math.floor(phi)) * m
    i = int(u)
    if i >= m:
        i = m - 1
    w = u - i
    i1 = i + 1 if i + 1 < m else 0
    return i, i1, w


@njit(cache=True)
def _restoring(x: float, phi: float, b: float, kd: np.ndarray, ed: np.ndarray, kb: np.ndarray,
               eb: np.ndarray) -> float:
    """``sum_j kd_j max(x - ed_j - b, 0) + kb_j min(x - eb_j + b, 0)``, tables linear in phase."""
    i, i1, w = _cell(phi, kd.shape[0])
    f = 0.0
    for j in range(kd.shape[1]):
        k_d = (1.0 - w) * kd[i, j] + w * kd[i1, j]
        e_d = (1.0 - w) * ed[i, j] + w * ed[i1, j]
        k_b = (1.0 - w) * kb[i, j] + w * kb[i1, j]
        e_b = (1.0 - w) * eb[i, j] + w * eb[i1, j]
        d = x - e_d - b
        if d > 0.0:
            f += k_d * d
        c = x - e_b + b
        if c < 0.0:
            f += k_b * c
    return f


@njit(cache=True)
def _offsets(phi: float, ed: np.ndarray, eb: np.ndarray) -> tuple[float, float]:
    """Smallest drive offset and largest back offset at ``phi`` (linear in phase)."""
    i, i1, w = _cell(phi, ed.shape[0])
    lo = np.inf
    hi = -np.inf
    for j in range(ed.shape[1]):
        e_d = (1.0 - w) * ed[i, j] + w * ed[i1, j]
        e_b = (1.0 - w) * eb[i, j] + w * eb[i1, j]
        lo = min(lo, e_d)
        hi = max(hi, e_b)
    return lo, hi


@njit(cache=True)
def integrate_ramp(x0: float, v0: float, zeta: float, force: float, backlash: float,
                   omega_n: float, kd: np.ndarray, ed: np.ndarray, kb: np.ndarray,
                   eb: np.ndarray, knot_t: np.ndarray, knot_f: np.ndarray,
                   knot_phi: np.ndarray, t0: float, sample_dt: float, steps_per_sample: int,
                   x_out: np.ndarray, a_out: np.ndarray, phi_out: np.ndarray,
                   loss_out: np.ndarray, impact_out: np.ndarray) -> tuple[float, float]:
    """Fixed-step RK4 of the module's equation along the ramp; fills the per-sample outputs.

    Parameters
    ----------
    x0, v0 : float
        DTE (units of ``L``) and its rate (units of ``L`` per second) at ``t0``.
    zeta, force, backlash : float
        Damping ratio, ``tilde F`` and the half gap ``tilde b`` of the model (-).
    omega_n : float
        Natural frequency of the scaling (rad/s).
    kd, ed, kb, eb : numpy.ndarray
        ``(M, P)`` tables over the phases ``i / M`` of one mesh cycle (-).
    knot_t, knot_f, knot_phi : numpy.ndarray
        Knots of the piecewise-linear mesh frequency: times (s), ``f_m`` (Hz), phase (cycles).
    t0, sample_dt : float
        Time of sample 0 and the sample interval (s).
    steps_per_sample : int
        RK4 steps per sample.
    x_out, a_out, phi_out : numpy.ndarray
        ``(n,)`` outputs: DTE (units of ``L``), DTE acceleration (units of ``L`` per s^2),
        phase (cycles) at each sample.
    loss_out, impact_out : numpy.ndarray
        ``(n,)`` bool outputs: drive-side contact loss / back-side impact at the sample.

    Returns
    -------
    tuple of float
        The end state ``(x, v)`` (units of ``L``, and ``L`` per s).
    """
    w2 = omega_n * omega_n
    c = 2.0 * zeta * omega_n
    h = sample_dt / steps_per_sample
    x = x0
    v = v0
    n = x_out.size
    seg = 0
    for s in range(n):
        t = t0 + s * sample_dt
        seg = _segment(t, seg, knot_t)
        phi = _phase(t, seg, knot_t, knot_f, knot_phi)
        x_out[s] = x
        phi_out[s] = phi
        a_out[s] = w2 * (force - _restoring(x, phi, backlash, kd, ed, kb, eb)) - c * v
        lo, hi = _offsets(phi, ed, eb)
        loss_out[s] = x - lo - backlash < 0.0
        impact_out[s] = x - hi + backlash < 0.0
        for k in range(steps_per_sample):
            ts = t + k * h
            p0 = phi if k == 0 else _phase(ts, seg, knot_t, knot_f, knot_phi)
            ph = _phase(ts + 0.5 * h, seg, knot_t, knot_f, knot_phi)
            p1 = _phase(ts + h, seg, knot_t, knot_f, knot_phi)
            a1 = w2 * (force - _restoring(x, p0, backlash, kd, ed, kb, eb)) - c * v
            x2 = x + 0.5 * h * v
            v2 = v + 0.5 * h * a1
            a2 = w2 * (force - _restoring(x2, ph, backlash, kd, ed, kb, eb)) - c * v2
            x3 = x + 0.5 * h * v2
            v3 = v + 0.5 * h * a2
            a3 = w2 * (force - _restoring(x3, ph, backlash, kd, ed, kb, eb)) - c * v3
            x4 = x + h * v3
            v4 = v + h * a3
            a4 = w2 * (force - _restoring(x4, p1, backlash, kd, ed, kb, eb)) - c * v4
            x = x + h * (v + 2.0 * v2 + 2.0 * v3 + v4) / 6.0
            v = v + h * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
    return x, v


def mesh_phase(knot_time_s: ArrayLike, knot_mesh_frequency_Hz: ArrayLike) -> np.ndarray:
    """Mesh phase (cycles) at the knots of a piecewise-linear mesh frequency, 0 at the first.

    Parameters
    ----------
    knot_time_s : array_like
        ``(K,)`` increasing times (s).
    knot_mesh_frequency_Hz : array_like
        ``(K,)`` mesh frequency at the knots (Hz), > 0.

    Returns
    -------
    numpy.ndarray
        ``(K,)`` the integral of ``f_m`` from the first knot (trapezoid rule, exact for a
        piecewise-linear ``f_m``).
    """
    t = np.asarray(knot_time_s, dtype=float)
    f = np.asarray(knot_mesh_frequency_Hz, dtype=float)
    return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))])


@dataclass(frozen=True, eq=False)
class RunUpResponse:
    """The model's response along a ramp, per sample.

    Attributes
    ----------
    time_s : numpy.ndarray
        ``(n,)`` sample times (s), from the ramp's first knot.
    mesh_frequency_Hz : numpy.ndarray
        ``(n,)`` instantaneous mesh frequency (Hz).
    mesh_phase : numpy.ndarray
        ``(n,)`` mesh phase (cycles) from the first knot.
    dte_m : numpy.ndarray
        ``(n,)`` dynamic transmission error ``L x`` (m).
    dte_acceleration_m_s2 : numpy.ndarray
        ``(n,)`` its second time derivative (m/s^2), from the equation of motion.
    contact_loss, backside_impact : numpy.ndarray
        ``(n,)`` bool: drive-side contact loss / back-side impact at the sample.
    steps_per_sample : int
        RK4 steps per sample.
    sample_rate_Hz : float
    omega_n_rad_s : float
        ``omega_n`` of the model's scaling (rad/s).
    """

    time_s: np.ndarray
    mesh_frequency_Hz: np.ndarray
    mesh_phase: np.ndarray
    dte_m: np.ndarray
    dte_acceleration_m_s2: np.ndarray
    contact_loss: np.ndarray
    backside_impact: np.ndarray
    steps_per_sample: int
    sample_rate_Hz: float
    omega_n_rad_s: float


def _check_path(t: np.ndarray, f: np.ndarray) -> None:
    if t.ndim != 1 or t.shape != f.shape or t.size < 2:
        raise ValueError(f"`knot_time_s` and `knot_mesh_frequency_Hz` must be 1-D of the same "
                         f"length >= 2, were {t.shape} and {f.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise ValueError("`knot_time_s` must be finite and increasing")
    if not (np.all(np.isfinite(f)) and np.all(f > 0)):
        raise ValueError("`knot_mesh_frequency_Hz` must be finite and > 0")


def runup_response(model: DynamicModel, omega_n_rad_s: float, knot_time_s: ArrayLike,
                   knot_mesh_frequency_Hz: ArrayLike, *, sample_rate_Hz: float,
                   steps_per_period: int = 128, table_points: int = 4096,
                   y0: tuple[float, float] | None = None) -> RunUpResponse:
    """Integrate ``model`` in time along a piecewise-linear mesh-frequency ramp (module notes).

    Parameters
    ----------
    model : DynamicModel
        An SDOF model (:func:`models.dynamics.sdof_from_mesh_cycle`) or any model with
        ``pair_tables``; its ``zeta``, ``force`` and ``backlash`` are non-dimensional with
        respect to ``omega_n_rad_s`` and its ``length_scale_m``.
    omega_n_rad_s : float
        ``omega_n = sqrt(k_0 / m_e)`` of the model's scaling (rad/s).
    knot_time_s, knot_mesh_frequency_Hz : array_like
        The ramp: mesh frequency (Hz) at increasing times (s), linear in between.
    sample_rate_Hz : float
        Output rate (Hz); samples at ``t_0 + i / fs`` up to the last knot.
    steps_per_period : int
        RK4 steps per mesh period at least, at the highest mesh frequency (>= 16).
    table_points : int
        Phases per mesh cycle of the stiffness and error tables (even, >= 64).
    y0 : tuple of float, optional
        ``(x, x')`` at the first knot in the model's non-dimensional units; default the
        static state ``(model.start_dte(), 0)``, as :func:`models.dynamics.sweep.sweep`.

    Returns
    -------
    RunUpResponse

    Raises
    ------
    ValueError
        A bad ramp (not increasing, non-positive frequency), rate or step count.
    """
    t = np.ascontiguousarray(knot_time_s, dtype=float)
    f = np.ascontiguousarray(knot_mesh_frequency_Hz, dtype=float)
    _check_path(t, f)
    fs = float(sample_rate_Hz)
    if not (math.isfinite(fs) and fs > 0):
        raise ValueError(f"`sample_rate_Hz` must be > 0, was {sample_rate_Hz!r}")
    wn = float(omega_n_rad_s)
    if not (math.isfinite(wn) and wn > 0):
        raise ValueError(f"`omega_n_rad_s` must be > 0, was {omega_n_rad_s!r}")
    if int(steps_per_period) != steps_per_period or steps_per_period < 16:
        raise ValueError(f"`steps_per_period` must be an integer >= 16, was "
                         f"{steps_per_period!r}")
    if int(table_points) != table_points or table_points < 64 or table_points % 2:
        raise ValueError(f"`table_points` must be an even integer >= 64, was {table_points!r}")
    kd, ed, kb, eb = (np.ascontiguousarray(a, dtype=float)
                      for a in model.pair_tables(int(table_points) // 2))
    n = math.floor((t[-1] - t[0]) * fs + 1e-9) + 1
    m = max(1, math.ceil(int(steps_per_period) * float(f.max()) / fs))
    x = np.empty(n)
    a = np.empty(n)
    phi = np.empty(n)
    loss = np.zeros(n, dtype=np.bool_)
    impact = np.zeros(n, dtype=np.bool_)
    x0, v0 = (model.start_dte(), 0.0) if y0 is None else (float(y0[0]), float(y0[1]))
    integrate_ramp(float(x0), float(v0) * wn, float(model.zeta), float(model.force),
                   float(model.backlash), wn, kd, ed, kb, eb, t, f, mesh_phase(t, f),
                   float(t[0]), 1.0 / fs, int(m), x, a, phi, loss, impact)
    time = t[0] + np.arange(n) / fs
    L = float(model.length_scale_m)
    return RunUpResponse(
        time_s=time, mesh_frequency_Hz=np.interp(time, t, f), mesh_phase=phi, dte_m=L * x,
        dte_acceleration_m_s2=L * a, contact_loss=loss, backside_impact=impact,
        steps_per_sample=int(m), sample_rate_Hz=fs, omega_n_rad_s=wn)
