r"""Fixed-step RK4 for the SDOF model, compiled (numba) and a pure-Python reference.

The step is a whole fraction of the mesh period, ``h = 2 pi / (Lambda N)``, and every period
starts at cycle phase 0, so the periodic ``tilde k`` and ``tilde e`` are needed only at the
``2 N`` half steps of one period (:meth:`~models.dynamics.sdof.SDOFModel.tables`); a step costs
a few multiplications, no cosine. The classical RK4 stages are

.. math:: k_1 = g(t, y),\ k_2 = g(t + h/2, y + h k_1/2),\ k_3 = g(t + h/2, y + h k_2/2),
          \ k_4 = g(t + h, y + h k_3),\ y \leftarrow y + h (k_1 + 2 k_2 + 2 k_3 + k_4) / 6

with ``g`` the SDOF right-hand side (dead-zone backlash). The dead zone has a kink, so near
contact loss the scheme is locally first order in the kink crossings; ``N = 128`` per mesh
period keeps the Arms within 1 % of an adaptive RK45 at rtol 1e-9 (benchmark
``tests/benchmarks/bench_sdof_sweep.py``). :func:`periods_reference` runs the same operations
in the same order in plain Python; :func:`periods_solve_ivp` is the adaptive check.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from models.dynamics.sdof import SDOFModel

__all__ = ["periods", "periods_reference", "periods_solve_ivp", "settle"]


@njit(cache=True)
def _accel(x, v, k, e, zeta, force, b):  # pragma: no cover - compiled
    u = x - e
    if u > b:
        f = u - b
    elif u < -b:
        f = u + b
    else:
        f = 0.0
    return force - 2.0 * zeta * v - k * f


@njit(cache=True)
def _step(x, v, j, zeta, force, b, ktab, etab, h):  # pragma: no cover - compiled
    n2 = ktab.size
    j0 = 2 * j
    j1 = j0 + 1
    j2 = (j0 + 2) % n2
    a1 = _accel(x, v, ktab[j0], etab[j0], zeta, force, b)
    x2 = x + 0.5 * h * v
    v2 = v + 0.5 * h * a1
    a2 = _accel(x2, v2, ktab[j1], etab[j1], zeta, force, b)
    x3 = x + 0.5 * h * v2
    v3 = v + 0.5 * h * a2
    a3 = _accel(x3, v3, ktab[j1], etab[j1], zeta, force, b)
    x4 = x + h * v3
    v4 = v + h * a3
    a4 = _accel(x4, v4, ktab[j2], etab[j2], zeta, force, b)
    xn = x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
    vn = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    return xn, vn


@njit(cache=True)
def _periods(x, v, zeta, force, b, ktab, etab, h, n_periods, xs, us):  # pragma: no cover
    n = ktab.size // 2
    rec = xs.size > 0
    pts = np.empty((n_periods, 2))
    i = 0
    for p in range(n_periods):
        for j in range(n):
            if rec:
                xs[i] = x
                us[i] = x - etab[2 * j]
            x, v = _step(x, v, j, zeta, force, b, ktab, etab, h)
            i += 1
        pts[p, 0] = x
        pts[p, 1] = v
    return pts


@njit(cache=True)
def _settle(x, v, zeta, force, b, ktab, etab, h, tol, min_periods, max_periods):  # pragma: no cover
    n = ktab.size // 2
    count = 0
    streak = 0
    converged = False
    while count < max_periods:
        px = x
        pv = v
        for j in range(n):
            x, v = _step(x, v, j, zeta, force, b, ktab, etab, h)
        count += 1
        d = max(abs(x - px), abs(v - pv))
        if d < tol:
            streak += 1
        else:
            streak = 0
        if count >= min_periods and streak >= 3:
            converged = True
            break
    return x, v, count, converged


def _setup(model: SDOFModel, frequency: float, steps_per_period: int):
    if not frequency > 0 or steps_per_period < 4:
        raise ValueError("need frequency > 0 and steps_per_period >= 4")
    ktab, etab = model.tables(frequency, steps_per_period)
    h = 2.0 * math.pi / (frequency * steps_per_period)
    return ktab, etab, h


def periods(
    model: SDOFModel,
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
    (``n_periods * steps_per_period`` samples, whole periods).
    """
    ktab, etab, h = _setup(model, frequency, steps_per_period)
    size = n_periods * steps_per_period if record else 0
    xs, us = np.empty(size), np.empty(size)
    pts = _periods(
        float(y0[0]),
        float(y0[1]),
        model.zeta,
        model.force,
        model.backlash,
        ktab,
        etab,
        h,
        int(n_periods),
        xs,
        us,
    )
    return pts, (xs if record else None), (us if record else None)


def settle(
    model: SDOFModel,
    frequency: float,
    y0: tuple[float, float],
    *,
    steps_per_period: int = 128,
    tol: float = 1e-6,
    min_periods: int = 10,
    max_periods: int = 1000,
) -> tuple[tuple[float, float], int, bool]:
    """Run whole periods until the Poincare point moves less than ``tol`` for 3 periods running.

    ``max(|dx|, |dx'|)`` between successive periods (units of ``L``), at least
    ``min_periods``, at most ``max_periods``. Returns the state, the periods run and whether
    it converged (a period-n or chaotic response never does and stops at the cap).
    """
    ktab, etab, h = _setup(model, frequency, steps_per_period)
    x, v, n, ok = _settle(
        float(y0[0]),
        float(y0[1]),
        model.zeta,
        model.force,
        model.backlash,
        ktab,
        etab,
        h,
        float(tol),
        int(min_periods),
        int(max_periods),
    )
    return (x, v), int(n), bool(ok)


def periods_reference(
    model: SDOFModel,
    frequency: float,
    y0: tuple[float, float],
    n_periods: int,
    *,
    steps_per_period: int = 128,
) -> np.ndarray:
    """Same scheme, same operation order, plain Python: Poincare points ``(n_periods, 2)``."""
    ktab, etab, h = _setup(model, frequency, steps_per_period)
    zeta, force, b = model.zeta, model.force, model.backlash
    kt, et = ktab.tolist(), etab.tolist()
    n2 = len(kt)

    def accel(x, v, k, e):
        u = x - e
        f = u - b if u > b else (u + b if u < -b else 0.0)
        return force - 2.0 * zeta * v - k * f

    x, v = float(y0[0]), float(y0[1])
    pts = np.empty((n_periods, 2))
    for p in range(n_periods):
        for j in range(steps_per_period):
            j0, j1, j2 = 2 * j, 2 * j + 1, (2 * j + 2) % n2
            a1 = accel(x, v, kt[j0], et[j0])
            x2 = x + 0.5 * h * v
            v2 = v + 0.5 * h * a1
            a2 = accel(x2, v2, kt[j1], et[j1])
            x3 = x + 0.5 * h * v2
            v3 = v + 0.5 * h * a2
            a3 = accel(x3, v3, kt[j1], et[j1])
            x4 = x + h * v3
            v4 = v + h * a3
            a4 = accel(x4, v4, kt[j2], et[j2])
            x, v = (
                x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4),
                v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            )
        pts[p] = (x, v)
    return pts


def periods_solve_ivp(
    model: SDOFModel,
    frequency: float,
    y0: tuple[float, float],
    n_periods: int,
    *,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    record_points: int = 0,
):
    """Adaptive RK45 check (``scipy.integrate.solve_ivp``): Poincare points ``(n_periods, 2)``.

    With ``record_points > 0``, also ``x`` at that many equally spaced points per period
    (dense output), as the second return value.
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
