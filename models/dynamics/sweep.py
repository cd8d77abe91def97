r"""Frequency sweeps of the SDOF and ITMS models: steady state, Arms, contact loss, period.

Seed 003 Secs. 4-5. The sweep runs the frequencies in the given order (up or down) and
**carries the state** from one frequency to the next, so a branch is followed until it
disappears and the jumps and the hysteresis of the softening primary resonance appear. At
each frequency (all in one compiled call, :func:`~models.dynamics.sdof_kernels.sweep_kernel`):

1. transients are discarded by the convergence test of
   :func:`~models.dynamics.integrate.settle_periodic`: whole mesh periods until the Poincare
   point (state at phase 0) repeats with a period ``n`` in 1..8 to within ``tol`` for three
   periods running, at least ``min_periods``, at most ``max_periods``; ``period`` is ``n``,
   0 ("aperiodic": quasi-periodic, chaotic, or not settled within ``max_periods``), or
   ``-n`` ("unresolved": repeats every ``n`` periods but a guard against slowly converging
   transients and sub-tolerance splits still rejected it); the settled state is within about
   ``tol / (1 - |mu|)`` of the orbit (``mu`` the slowest Floquet multiplier);
2. ``record_periods`` whole periods are recorded (rounded up to a multiple of ``n``, so the
   record holds whole response periods), ``steps_per_period`` samples each, and the DTE
   amplitudes ``A_1..A_3`` of mesh harmonics 1-3 taken from their DFT (bin
   ``k * record_periods``; whole periods, no leakage), and

   .. math:: A_{rms} = \sqrt{A_1^2 + A_2^2 + A_3^2}

   (SEED-NOTES 17: the seed prints sqrt(sum A_i));
3. flags over the recorded periods: **contact loss** if no pair touches on the drive side
   (``u = x - e < b``; ITMS: ``e`` the smallest drive-side gap of the pairs), **back-side
   impact** if a back flank is reached (``x - e_b < -b``, ``e_b`` the largest back offset),
   each RK4 step checked on the cubic Hermite interpolant of ``x`` (a loss shorter than a step
   is not missed);
4. the last :data:`~models.dynamics.integrate.POINCARE_POINTS` Poincare points are kept (for
   bifurcation diagrams).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import ArrayLike

from models.dynamics.checks import check_settle_args
from models.dynamics.integrate import POINCARE_POINTS, TableSet, model_tables
from models.dynamics.sdof import DynamicModel
from models.dynamics.sdof_kernels import sweep_kernel
from models.errors import ModelError

__all__ = [
    "SweepResult",
    "hysteresis_band",
    "hysteresis_bands",
    "steady_state",
    "sweep",
    "sweep_up_down",
]


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
        Flags (bool); ``converged`` is ``period > 0``. The contact flags cover the recorded
        periods, each RK4 step checked on its cubic Hermite interpolant (not only the step
        starts).
    periods : numpy.ndarray
        Periods run to settle (int).
    length_scale_m : float
        ``L`` (m).
    period : numpy.ndarray
        Response period in mesh periods, 1..8; 0 aperiodic (no repetition within ``tol`` at
        ``max_periods``); ``-n`` unresolved (repeats every ``n`` periods within ``tol``, but
        the period could not be confirmed: see :mod:`models.dynamics.sdof_kernels`) (int).
    poincare : numpy.ndarray
        ``(n, POINCARE_POINTS, 2)`` last Poincare points ``(x, x')``, oldest first (units of
        ``L``); NaN where fewer periods were run.
    entry_state : numpy.ndarray
        ``(n, 2)`` state each point started from (the previous point's end state).
    partial_contact_loss : numpy.ndarray
        Fraction (0..1) of the recorded step starts with *partial* contact loss: at least one
        pair touches on the drive side, but fewer than carry load in the quasi-static solution
        at that phase (:func:`~models.dynamics.integrate.static_pair_count`) -- what the ITMS
        model adds (seed 003 Sec. 5.2); always 0 for the single-spring models. A fraction, not
        a flag: any vibration shifts the entry of a pair a little, so small fractions occur
        wherever a pair enters with little load.
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
    period: np.ndarray
    poincare: np.ndarray
    entry_state: np.ndarray
    partial_contact_loss: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        if np.size(self.partial_contact_loss) == 0 and np.size(self.frequency) > 0:
            object.__setattr__(
                self, "partial_contact_loss", np.zeros(np.shape(self.frequency), dtype=float)
            )

    @property
    def unresolved(self) -> np.ndarray:
        """``period < 0``: repetition within ``tol`` that the guards could not confirm."""
        return np.asarray(self.period < 0)

    @property
    def arms_m(self) -> np.ndarray:
        """Arms in metres."""
        return self.arms * self.length_scale_m

    def sorted(self) -> SweepResult:
        """The same points in increasing frequency."""
        o = np.argsort(self.frequency, kind="stable")
        return SweepResult(
            **{
                f.name: (
                    getattr(self, f.name)
                    if f.name == "length_scale_m"
                    else getattr(self, f.name)[o]
                )
                for f in fields(self)
            }
        )


def _check(tol: float, min_periods: int, max_periods: int, record_periods: int) -> None:
    check_settle_args(tol, min_periods, max_periods)
    if record_periods < 1:
        raise ValueError(f"`record_periods` must be >= 1, was {record_periods!r}")


def empty_outputs(shape: tuple[int, ...]) -> dict[str, np.ndarray]:
    """Output arrays of :func:`~models.dynamics.sdof_kernels.sweep_kernel` for ``shape`` points."""
    return dict(
        amps=np.zeros((*shape, 3)),
        mean=np.zeros(shape),
        loss=np.zeros(shape, dtype=np.bool_),
        impact=np.zeros(shape, dtype=np.bool_),
        partial=np.zeros(shape),
        periods_run=np.zeros(shape, dtype=np.int64),
        period=np.zeros(shape, dtype=np.int64),
        poinc=np.full((*shape, POINCARE_POINTS, 2), np.nan),
        entry=np.zeros((*shape, 2)),
    )


def result_from_outputs(
    freqs: np.ndarray, out: dict[str, np.ndarray], length_scale_m: float
) -> SweepResult:
    """Wrap kernel outputs (one sweep) as a :class:`SweepResult`."""
    amps = out["amps"]
    return SweepResult(
        frequency=freqs,
        amplitudes=amps,
        arms=np.sqrt(np.sum(amps**2, axis=-1)),
        mean_dte=out["mean"],
        contact_loss=out["loss"],
        backside_impact=out["impact"],
        converged=out["period"] > 0,
        periods=out["periods_run"],
        length_scale_m=float(length_scale_m),
        period=out["period"],
        poincare=out["poinc"],
        entry_state=out["entry"],
        partial_contact_loss=out["partial"],
    )


def _run(
    model: DynamicModel,
    t: TableSet,
    freqs: np.ndarray,
    y: tuple[float, float],
    tol: float,
    min_periods: int,
    max_periods: int,
    record_periods: int,
) -> tuple[SweepResult, tuple[float, float]]:
    if not (np.all(np.isfinite(freqs)) and np.all(freqs > 0)):
        raise ValueError("`frequencies` must be finite and > 0")
    out = empty_outputs((freqs.size,))
    x, v = sweep_kernel(
        float(y[0]),
        float(y[1]),
        float(model.zeta),
        float(model.force),
        float(model.backlash),
        t.kd,
        t.ed,
        t.kb,
        t.eb,
        t.drive_offset,
        t.back_offset,
        t.static_pairs,
        t.cos,
        t.sin,
        freqs,
        float(tol),
        int(min_periods),
        int(max_periods),
        int(record_periods),
        out["amps"],
        out["mean"],
        out["loss"],
        out["impact"],
        out["partial"],
        out["periods_run"],
        out["period"],
        out["poinc"],
        out["entry"],
    )
    return result_from_outputs(freqs, out, model.length_scale_m), (float(x), float(v))


def steady_state(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    *,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> tuple[tuple[float, float], dict]:
    """Settle, record, and analyse one frequency; returns the end state and the figures.

    The figures: ``amplitudes`` (3,), ``arms``, ``mean_dte``, ``contact_loss``,
    ``backside_impact``, ``partial_contact_loss`` (fraction), ``converged``, ``periods`` (run
    to settle), ``period`` (0 aperiodic, ``-n`` unresolved),
    ``poincare`` (POINCARE_POINTS, 2).
    """
    _check(tol, min_periods, max_periods, record_periods)
    t = model_tables(model, steps_per_period)
    r, y = _run(
        model, t, np.array([float(frequency)]), y0, tol, min_periods, max_periods, record_periods
    )
    figures = dict(
        amplitudes=r.amplitudes[0],
        arms=float(r.arms[0]),
        mean_dte=float(r.mean_dte[0]),
        contact_loss=bool(r.contact_loss[0]),
        backside_impact=bool(r.backside_impact[0]),
        partial_contact_loss=float(r.partial_contact_loss[0]),
        converged=bool(r.converged[0]),
        periods=int(r.periods[0]),
        period=int(r.period[0]),
        poincare=r.poincare[0],
    )
    return y, figures


def sweep(
    model: DynamicModel,
    frequencies: ArrayLike,
    *,
    y0: tuple[float, float] | None = None,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
    record_periods: int = 4,
) -> SweepResult:
    """Sweep ``Lambda`` in the order given, carrying the state; start at ``model.start_dte()``."""
    _check(tol, min_periods, max_periods, record_periods)
    freqs = np.ascontiguousarray(np.asarray(frequencies, dtype=float).ravel())
    y = (model.start_dte(), 0.0) if y0 is None else y0
    t = model_tables(model, steps_per_period)
    return _run(model, t, freqs, y, tol, min_periods, max_periods, record_periods)[0]


def sweep_up_down(
    model: DynamicModel, frequencies: ArrayLike, **kwargs
) -> tuple[SweepResult, SweepResult]:
    """Upward then downward sweep over the same frequencies (each from the static state).

    Both results are returned sorted by increasing frequency, so they compare point by point.
    """
    f = np.sort(np.asarray(frequencies, dtype=float))
    up = sweep(model, f, **kwargs)
    down = sweep(model, f[::-1], **kwargs)
    return up, down.sorted()


def _differ(up: SweepResult, down: SweepResult, rel_tol: float) -> tuple[np.ndarray, np.ndarray]:
    u, d = up.sorted(), down.sorted()
    if not np.array_equal(u.frequency, d.frequency):
        raise ModelError("`up` and `down` must share their frequency grid")
    diff = np.abs(d.arms - u.arms) > rel_tol * np.maximum(d.arms, u.arms)
    return u.frequency, diff


def hysteresis_bands(
    up: SweepResult, down: SweepResult, rel_tol: float = 0.1
) -> list[tuple[float, float]]:
    """Every run of consecutive grid points where the branches differ, as ``(lo, hi)``.

    The two sweeps are compared point by point in increasing ``Lambda`` (they must share the
    grid); a point differs where ``|A_down - A_up| > rel_tol * max(A_down, A_up)``. Separate
    regions (e.g. a super-harmonic near ``Lambda = 0.5`` and the primary resonance) give
    separate bands, in increasing frequency; a single differing point gives ``(f, f)``.

    Parameters
    ----------
    up, down : SweepResult
        Upward and downward sweeps over the same frequencies (:func:`sweep_up_down`).
    rel_tol : float
        Relative difference of ``A_rms`` above which the branches differ (-).

    Returns
    -------
    list of tuple of float
        ``(Lambda_lo, Lambda_hi)`` of each band (-), in increasing frequency.

    Raises
    ------
    ModelError
        If the two sweeps do not share their frequency grid.

    Examples
    --------
    Arms of 1 on the way up, 2 at ``Lambda`` 0.9 and 1.0 on the way down:

    >>> def result(arms):
    ...     n = len(arms)
    ...     z, b = np.zeros(n), np.zeros(n, dtype=bool)
    ...     return SweepResult(np.array([0.8, 0.9, 1.0, 1.1]), np.zeros((n, 3)),
    ...                        np.array(arms), z, b, b, ~b, z, 1.0, np.ones(n),
    ...                        np.zeros((n, 1, 2)), np.zeros((n, 2)))
    >>> hysteresis_bands(result([1.0, 1.0, 1.0, 1.0]), result([1.0, 2.0, 2.0, 1.0]))
    [(0.9, 1.0)]
    """
    f, diff = _differ(up, down, rel_tol)
    idx = np.flatnonzero(diff)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate(([idx[0]], idx[breaks + 1]))
    ends = np.concatenate((idx[breaks], [idx[-1]]))
    return [(float(f[i]), float(f[j])) for i, j in zip(starts, ends, strict=True)]


def hysteresis_band(
    up: SweepResult, down: SweepResult, rel_tol: float = 0.1
) -> tuple[float, float] | None:
    """``(Lambda_lo, Lambda_hi)`` spanning *all* points where the branches differ, or None.

    The envelope of :func:`hysteresis_bands` (which keeps separate regions apart; use it to
    draw or report jump bands).

    Parameters
    ----------
    up, down : SweepResult
        As :func:`hysteresis_bands`.
    rel_tol : float
        As :func:`hysteresis_bands`.

    Returns
    -------
    tuple of float or None
        ``(Lambda_lo, Lambda_hi)`` (-), None where the branches never differ.
    """
    bands = hysteresis_bands(up, down, rel_tol)
    if not bands:
        return None
    return bands[0][0], bands[-1][1]
