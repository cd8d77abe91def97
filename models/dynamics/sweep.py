r"""Frequency sweeps of the SDOF model: steady state, Arms, contact loss (seed 003 Secs. 4-5).

The sweep runs the frequencies in the given order (up or down) and **carries the state**
from one frequency to the next, so a branch is followed until it disappears and the jumps
and the hysteresis of the softening primary resonance appear. At each frequency:

1. transients are discarded by :func:`~models.dynamics.integrate.settle`: whole mesh periods
   until the Poincare point (state at phase 0) moves less than ``tol`` for three periods
   running, at least ``min_periods``, at most ``max_periods`` (``converged`` says which);
2. ``record_periods`` whole periods are recorded (``steps_per_period`` samples each) and
   the DTE amplitudes ``A_1..A_3`` of mesh harmonics 1-3 taken from their FFT (bin
   ``k * record_periods``; whole periods, so no leakage), and

   .. math:: A_{rms} = \sqrt{A_1^2 + A_2^2 + A_3^2}

   (SEED-NOTES 17: the seed prints sqrt(sum A_i));
3. flags: **contact loss** if ``u = x - e`` enters the gap (``u < b``) at a sample, **back-side
   impact** if it reaches the back flank (``u < -b``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.integrate import periods, settle
from models.dynamics.sdof import SDOFModel

__all__ = ["SweepResult", "steady_state", "sweep", "sweep_up_down"]


@dataclass(frozen=True)
class SweepResult:
    """One sweep, arrays in sweep order.

    Attributes
    ----------
    frequency : numpy.ndarray
        ``Lambda`` (-), in the order run.
    amplitudes : numpy.ndarray
        ``(n, 3)`` DTE amplitudes of mesh harmonics 1-3 (units of ``L``).
    arms : numpy.ndarray
        ``sqrt(A_1^2 + A_2^2 + A_3^2)`` (units of ``L``).
    mean_dte : numpy.ndarray
        Mean DTE (units of ``L``).
    contact_loss, backside_impact, converged : numpy.ndarray
        Flags (bool).
    periods : numpy.ndarray
        Periods run to settle (int).
    length_scale_m : float
        ``L`` (m).
    """

    frequency: np.ndarray
    amplitudes: np.ndarray
    arms: np.ndarray
    mean_dte: np.ndarray
    contact_loss: np.ndarray
    backside_impact: np.ndarray
    converged: np.ndarray
    periods: np.ndarray
    length_scale_m: float

    @property
    def arms_m(self) -> np.ndarray:
        """Arms in metres."""
        return self.arms * self.length_scale_m

    def sorted(self) -> SweepResult:
        """The same points in increasing frequency."""
        o = np.argsort(self.frequency, kind="stable")
        return SweepResult(
            self.frequency[o],
            self.amplitudes[o],
            self.arms[o],
            self.mean_dte[o],
            self.contact_loss[o],
            self.backside_impact[o],
            self.converged[o],
            self.periods[o],
            self.length_scale_m,
        )


def steady_state(
    model: SDOFModel,
    frequency: float,
    y0: tuple[float, float],
    *,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> tuple[tuple[float, float], dict]:
    """Settle, record, and analyse one frequency; returns the end state and the figures."""
    y, n, ok = settle(
        model,
        frequency,
        y0,
        steps_per_period=steps_per_period,
        tol=tol,
        min_periods=min_periods,
        max_periods=max_periods,
    )
    pts, xs, us = periods(
        model, frequency, y, record_periods, steps_per_period=steps_per_period, record=True
    )
    assert xs is not None and us is not None
    c = np.fft.rfft(xs) / xs.size
    amps = 2.0 * np.abs(c[[record_periods * k for k in (1, 2, 3)]])
    b = model.backlash
    figures = dict(
        amplitudes=amps,
        arms=float(np.sqrt(np.sum(amps**2))),
        mean_dte=float(c[0].real),
        contact_loss=bool(us.min() < b),
        backside_impact=bool(us.min() < -b),
        converged=ok,
        periods=n,
    )
    return (float(pts[-1, 0]), float(pts[-1, 1])), figures


def sweep(
    model: SDOFModel,
    frequencies: ArrayLike,
    *,
    y0: tuple[float, float] | None = None,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> SweepResult:
    """Sweep ``Lambda`` in the order given, carrying the state; start at the static state."""
    freqs = np.asarray(frequencies, dtype=float)
    y = (model.static_dte() + model.error.mean, 0.0) if y0 is None else y0
    rows = []
    for lam in freqs:
        y, fig = steady_state(
            model,
            float(lam),
            y,
            steps_per_period=steps_per_period,
            tol=tol,
            min_periods=min_periods,
            max_periods=max_periods,
            record_periods=record_periods,
        )
        rows.append(fig)
    col = lambda key, dt=float: np.array([r[key] for r in rows], dtype=dt)  # noqa: E731
    return SweepResult(
        frequency=freqs,
        amplitudes=np.array([r["amplitudes"] for r in rows]).reshape(-1, 3),
        arms=col("arms"),
        mean_dte=col("mean_dte"),
        contact_loss=col("contact_loss", bool),
        backside_impact=col("backside_impact", bool),
        converged=col("converged", bool),
        periods=col("periods", int),
        length_scale_m=model.length_scale_m,
    )


def sweep_up_down(
    model: SDOFModel, frequencies: ArrayLike, **kwargs
) -> tuple[SweepResult, SweepResult]:
    """Upward then downward sweep over the same frequencies (each from the static state).

    Both results are returned sorted by increasing frequency, so they compare point by point.
    """
    f = np.sort(np.asarray(frequencies, dtype=float))
    up = sweep(model, f, **kwargs)
    down = sweep(model, f[::-1], **kwargs)
    return up, down.sorted()
