r"""Fixed-step RK4 for the SDOF and ITMS models: tables, runs, steady state, references.

The step is a whole fraction of the mesh period, ``h = 2 pi / (Lambda N)``, and every period
starts at cycle phase 0, so the periodic stiffness and error tables are needed only at the
``2 N`` half steps of one period (:meth:`~models.dynamics.sdof.SDOFModel.pair_tables`,
gathered by :func:`model_tables`); a step costs a few multiplications, no cosine. The compiled
RK4, the steady-state detection and the sweep kernels are in :mod:`models.dynamics.sdof_kernels`
(the scheme, the period guards and the contact flags are described there); this module runs
them for one model from Python.

The dead zone has a kink, so near contact loss the scheme is locally first order in the kink
crossings; ``N = 128`` per mesh period keeps the Arms within 1 % of an adaptive RK45 at rtol
1e-9 (benchmark ``tests/benchmarks/bench_sdof_sweep.py``). :func:`periods_reference` runs the
same operations in the same order in plain Python; :func:`periods_solve_ivp` is the adaptive
check.

Steady state (:func:`settle_periodic`): whole periods are run until the Poincare point (the
state at phase 0) repeats with some period ``n`` in 1..8 (guarded against a period-``d``
response still converging, see :mod:`models.dynamics.sdof_kernels`).

Error of a settled state: the test is period-to-period, so with a slowest Floquet multiplier
``mu`` (per period of the response) the distance of the last point from the true periodic orbit
is about ``tol / (1 - |mu|)``, not ``tol``: lightly damped responses (``|mu|`` close to 1, e.g.
``1 - |mu| ~ 2 pi zeta / Lambda`` in the linear range) need a ``tol`` smaller by that factor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from models.dynamics.checks import check_settle_args
from models.dynamics.sdof import DynamicModel
from models.dynamics.sdof_kernels import SETTLE_RING, periods_kernel, settle_kernel

__all__ = [
    "POINCARE_POINTS",
    "Settled",
    "TableSet",
    "model_tables",
    "periods",
    "periods_reference",
    "periods_solve_ivp",
    "settle",
    "settle_periodic",
    "static_pair_count",
]

#: Poincare points kept per steady state (the last ones, in time order).
POINCARE_POINTS: Final = 16


@dataclass(frozen=True)
class TableSet:
    """Everything the compiled kernels need from a model at ``N`` steps per period.

    Attributes
    ----------
    kd, ed, kb, eb : numpy.ndarray
        ``(2 N, P)`` drive-side stiffness and offset, back-side stiffness and offset at the
        half steps (-), C-contiguous.
    drive_offset, back_offset : numpy.ndarray
        ``(2 N,)`` smallest ``ed`` over the pairs with ``kd > 0`` and largest ``eb`` over the
        pairs with ``kb > 0`` (-): contact loss is ``x - drive_offset < b`` (no pair touches
        on the drive side), back-side impact ``x - back_offset < -b``.
    cos, sin : numpy.ndarray
        ``(3, N)`` ``cos(2 pi k j / N)``, ``sin(...)``, ``k = 1..3``: the DFT of the mesh
        harmonics.
    steps_per_period : int
    static_pairs : numpy.ndarray
        ``(2 N,)`` number of pairs carrying load in the quasi-static drive-side solution
        (:func:`static_pair_count`); a sample with fewer pairs touching, but at least one, is a
        partial contact loss.
    """

    kd: np.ndarray
    ed: np.ndarray
    kb: np.ndarray
    eb: np.ndarray
    drive_offset: np.ndarray
    back_offset: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    steps_per_period: int
    static_pairs: np.ndarray


def model_tables(model: DynamicModel, steps_per_period: int) -> TableSet:
    """Tables of ``model`` at ``steps_per_period`` RK4 steps per mesh period (>= 4)."""
    if int(steps_per_period) != steps_per_period or steps_per_period < 4:
        raise ValueError(f"`steps_per_period` must be an integer >= 4, was {steps_per_period!r}")
    n = int(steps_per_period)
    kd, ed, kb, eb = (np.ascontiguousarray(a, dtype=float) for a in model.pair_tables(n))
    if not (kd.shape == ed.shape == kb.shape == eb.shape and kd.shape[0] == 2 * n):
        raise ValueError("`pair_tables` must return four (2 N, P) arrays")
    with np.errstate(invalid="ignore"):
        drive = np.where(kd > 0, ed, np.inf).min(axis=1)
        back = np.where(kb > 0, eb, -np.inf).max(axis=1)
    j = np.arange(n)
    arg = 2 * np.pi * np.arange(1, 4)[:, None] * j[None, :] / n
    return TableSet(
        kd,
        ed,
        kb,
        eb,
        np.ascontiguousarray(drive),
        np.ascontiguousarray(back),
        np.ascontiguousarray(np.cos(arg)),
        np.ascontiguousarray(np.sin(arg)),
        n,
        static_pair_count(kd, ed, float(model.force)),
    )


def static_pair_count(kd: np.ndarray, ed: np.ndarray, force: float) -> np.ndarray:
    """Pairs carrying load in the quasi-static solution of ``sum_j kd_j max(y - ed_j, 0) = F``.

    Per row of the ``(rows, P)`` tables, ``y = x - b``; a pair carries load where
    ``y - ed_j > 1e-12 max(1, |y|)``. Rows with no stiffness, or ``F <= 0``, count 0.
    """
    kd = np.asarray(kd, dtype=float)
    ed = np.asarray(ed, dtype=float)
    out = np.zeros(kd.shape[0], dtype=np.int64)
    if not force > 0:
        return out
    for i in range(kd.shape[0]):
        on = kd[i] > 0
        if not on.any():
            continue
        k, g = kd[i][on], ed[i][on]
        o = np.argsort(g)
        k, g = k[o], g[o]
        y = (force + np.cumsum(k * g)) / np.cumsum(k)
        nxt = np.append(g[1:], np.inf)
        yy = y[int(np.argmax(y <= nxt))]
        out[i] = int(np.sum(yy - g > 1e-12 * max(1.0, abs(yy))))
    return out


# --- Python entry points -----------------------------------------------------------------------
def _step_size(frequency: float, steps_per_period: int) -> float:
    if not (math.isfinite(frequency) and frequency > 0):
        raise ValueError(f"`frequency` must be finite and > 0, was {frequency!r}")
    return 2.0 * math.pi / (frequency * steps_per_period)


def periods(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    n_periods: int,
    *,
    steps_per_period: int = 128,
    record: bool = False,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Integrate ``n_periods`` mesh periods from phase 0 with the compiled RK4.

    Returns the Poincare points ``(n_periods, 2)`` (state ``(x, x')`` at the end of each
    period) and, with ``record``, ``x`` and ``u = x - e`` at every step start
    (``n_periods * steps_per_period`` samples, whole periods; for the ITMS model ``e`` is the
    smallest drive-side offset of the pairs, so ``u < b`` means that no pair touches).
    """
    t = model_tables(model, steps_per_period)
    h = _step_size(frequency, t.steps_per_period)
    size = n_periods * steps_per_period if record else 0
    xs, us = np.empty(size), np.empty(size)
    pts = periods_kernel(
        float(y0[0]),
        float(y0[1]),
        model.zeta,
        model.force,
        model.backlash,
        t.kd,
        t.ed,
        t.kb,
        t.eb,
        t.drive_offset,
        h,
        int(n_periods),
        xs,
        us,
    )
    return pts, (xs if record else None), (us if record else None)


@dataclass(frozen=True)
class Settled:
    """Outcome of :func:`settle_periodic`.

    Attributes
    ----------
    state : tuple of float
        ``(x, x')`` at phase 0 after the last period run (units of ``L``).
    periods_run : int
        Mesh periods run.
    period : int
        Detected period in mesh periods (1..8); 0 when no ``n <= 8`` repeats within ``tol``
        at ``max_periods`` (aperiodic: quasi-periodic or chaotic, or not yet settled); ``-n``
        when the points repeat every ``n`` periods within ``tol`` but the period could not be
        confirmed (unresolved: a split below ``100 tol``, or a transient too slow to tell; see
        :mod:`models.dynamics.sdof_kernels`).
    poincare : numpy.ndarray
        ``(k, 2)`` the last ``k = min(POINCARE_POINTS, periods_run + 1)`` Poincare points,
        oldest first.
    """

    state: tuple[float, float]
    periods_run: int
    period: int
    poincare: np.ndarray

    @property
    def converged(self) -> bool:
        """Whether a period 1..8 was detected."""
        return self.period > 0

    @property
    def unresolved(self) -> bool:
        """Whether the points repeat within ``tol`` but the period was not confirmed."""
        return self.period < 0


def settle_periodic(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    *,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
) -> Settled:
    """Run whole periods until the Poincare point repeats with a period ``n <= 8``.

    ``max(|dx|, |dx'|)`` (units of ``L``) between the Poincare points ``n`` periods apart below
    ``tol`` for three consecutive periods; the smallest such ``n`` that passes the guards of
    :mod:`models.dynamics.sdof_kernels` is the period (``-n`` if only unguarded repetition is
    found at ``max_periods``, 0 if none). At least ``min_periods``, at most ``max_periods`` periods.
    The settled state is within about ``tol / (1 - |mu|)`` of the periodic orbit (``mu`` the
    slowest Floquet multiplier), not ``tol``.
    """
    check_settle_args(tol, min_periods, max_periods)
    t = model_tables(model, steps_per_period)
    h = _step_size(frequency, t.steps_per_period)
    ring = np.empty((SETTLE_RING, 2))
    x, v, n, per = settle_kernel(
        float(y0[0]),
        float(y0[1]),
        model.zeta,
        model.force,
        model.backlash,
        t.kd,
        t.ed,
        t.kb,
        t.eb,
        h,
        float(tol),
        int(min_periods),
        int(max_periods),
        ring,
    )
    k = min(POINCARE_POINTS, int(n) + 1)
    idx = (np.arange(int(n) - k + 1, int(n) + 1)) % SETTLE_RING
    return Settled((float(x), float(v)), int(n), int(per), ring[idx].copy())


def settle(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    *,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
) -> tuple[tuple[float, float], int, bool]:
    """:func:`settle_periodic` as ``(state, periods run, converged)``.

    Converged means a period 1..8 was detected (a period-2 response converges as well).
    """
    s = settle_periodic(
        model,
        frequency,
        y0,
        steps_per_period=steps_per_period,
        tol=tol,
        min_periods=min_periods,
        max_periods=max_periods,
    )
    return s.state, s.periods_run, s.converged


def periods_reference(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    n_periods: int,
    *,
    steps_per_period: int = 128,
) -> np.ndarray:
    """Same scheme, same operation order, plain Python: Poincare points ``(n_periods, 2)``."""
    t = model_tables(model, steps_per_period)
    h = _step_size(frequency, t.steps_per_period)
    zeta, force, b = model.zeta, model.force, model.backlash
    kd, ed, kb, eb = (a.tolist() for a in (t.kd, t.ed, t.kb, t.eb))
    n2 = len(kd)

    def accel(x: float, v: float, j: int) -> float:
        f = 0.0
        for p in range(len(kd[j])):
            u = x - ed[j][p]
            if u > b:
                f += kd[j][p] * (u - b)
            w = x - eb[j][p]
            if w < -b:
                f += kb[j][p] * (w + b)
        return force - 2.0 * zeta * v - f

    x, v = float(y0[0]), float(y0[1])
    pts = np.empty((n_periods, 2))
    for p in range(n_periods):
        for j in range(steps_per_period):
            j0, j1, j2 = 2 * j, 2 * j + 1, (2 * j + 2) % n2
            a1 = accel(x, v, j0)
            x2 = x + 0.5 * h * v
            v2 = v + 0.5 * h * a1
            a2 = accel(x2, v2, j1)
            x3 = x + 0.5 * h * v2
            v3 = v + 0.5 * h * a2
            a3 = accel(x3, v3, j1)
            x4 = x + h * v3
            v4 = v + h * a3
            a4 = accel(x4, v4, j2)
            x, v = (
                x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4),
                v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            )
        pts[p] = (x, v)
    return pts


def periods_solve_ivp(
    model: DynamicModel,
    frequency: float,
    y0: tuple[float, float],
    n_periods: int,
    *,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    record_points: int = 0,
):
    """Adaptive RK45 check (``scipy.integrate.solve_ivp``): Poincare points ``(n_periods, 2)``.

    The right-hand side is the model's continuous-time one (:meth:`rhs`: Fourier series, or
    periodic interpolation of curves), independent of the RK4 tables. With
    ``record_points > 0``, also ``x`` at that many equally spaced points per period (dense
    output), as the second return value.
    """
    from scipy.integrate import solve_ivp

    T = 2 * math.pi / frequency
    t_eval = np.arange(1, n_periods + 1) * T
    if record_points:
        t_eval = np.unique(
            np.concatenate([t_eval, np.arange(n_periods * record_points) * T / record_points])
        )
    sol = solve_ivp(
        model.rhs,
        (0.0, n_periods * T),
        [float(y0[0]), float(y0[1])],
        method="RK45",
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
        args=(frequency,),
    )
    if not sol.success:  # pragma: no cover
        raise RuntimeError(sol.message)
    idx = np.searchsorted(sol.t, np.arange(1, n_periods + 1) * T - 1e-9 * T)
    pts = sol.y[:, idx].T
    if not record_points:
        return pts
    grid = np.arange(n_periods * record_points) * T / record_points
    return pts, sol.y[0, np.searchsorted(sol.t, grid - 1e-9 * T)]
