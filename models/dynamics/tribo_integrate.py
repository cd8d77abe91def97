r"""Time integration of the six-DOF tribo-dynamic model of seed 002: compiled RK4 and reference.

The model, its equations and tables are in :mod:`models.dynamics.tribo`.

Integrator: classical RK4 with the step a whole fraction of the mesh period, ``h = T_m / N``,
the tables sampled at the ``2N`` half steps (as :mod:`models.dynamics.integrate`); compiled with
numba (:func:`tribo_periods`, :func:`tribo_settle`) and a plain-Python reference with the same
operations in the same order (:func:`tribo_periods_reference`);
:meth:`~models.dynamics.tribo.TriboDynamics.ode` (tables interpolated linearly and
periodically) serves ``scipy.integrate.solve_ivp``.

All compiled kernels of the tribo-dynamic model live in this one file: numba's on-disk cache
(``cache=True``) checks only the source file of the function it loads, so a cached kernel
calling a compiled function of another file would keep a stale copy of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from models.dynamics.tribo import N_STATE, TriboDynamics, static_state, tribo_rhs
from models.errors import ModelError

__all__ = [
    "TriboRecord",
    "tribo_periods",
    "tribo_periods_reference",
    "tribo_settle",
]


@dataclass(frozen=True)
class TriboRecord:
    """One mesh period of the response, at the ``N`` step starts (SI units).

    Attributes
    ----------
    time_s : numpy.ndarray
        Time from the start of the period (s), ``(N,)``.
    state : numpy.ndarray
        ``(N, 10)`` states ``(q, x_p, x_g, y_p, y_g)`` and their velocities (m, m/s).
    dte_m : numpy.ndarray
        DTE ``delta = q + x_p - x_g`` (m).
    mesh_force_N : numpy.ndarray
        Dynamic mesh force ``sum N_i`` (N).
    pair_load_N : numpy.ndarray
        ``N_i`` per slot, ``(N, n_slots)`` (N); 0 for slots out of contact.
    friction_force_N : numpy.ndarray
        ``sum F_fi`` across the line of action (N).
    """

    time_s: np.ndarray
    state: np.ndarray
    dte_m: np.ndarray
    mesh_force_N: np.ndarray
    pair_load_N: np.ndarray
    friction_force_N: np.ndarray


# ----------------------------------------------------------------------------- kernels
@njit(cache=True)
def _dead_zone(u, b):  # pragma: no cover - compiled
    """Continuous dead zone ``D(u; b)`` (:func:`models.dynamics.sdof.dead_zone`)."""
    if u > b:
        return u - b
    if u < -b:
        return u + b
    return 0.0


@njit(cache=True)
def _rhs(y, j, K, MU, A1, A2, E, ED, p, dy):  # pragma: no cover - compiled
    W0, me, r1, r2, I1, I2 = p[0], p[1], p[2], p[3], p[4], p[5]
    mp, mg, kbx, kby, cbx, cby, cm, b = p[6], p[7], p[8], p[9], p[10], p[11], p[12], p[13]
    d = y[0] + y[1] - y[2]
    dd = y[5] + y[6] - y[7] - ED[j]
    u = d - E[j]
    f = _dead_zone(u, b)
    ns = K.shape[1]
    ksum = 0.0
    for i in range(ns):
        ksum += K[j, i]
    ftot = 0.0
    ffr = 0.0
    tfr = 0.0
    for i in range(ns):
        ki = K[j, i]
        if ki > 0.0:
            ni = ki * f + cm * ki / ksum * dd
            ftot += ni
            if ni > 0.0:
                fr = MU[j, i] * ni
                ffr += fr
                tfr += fr * (r1 * A1[j, i] / I1 + r2 * A2[j, i] / I2)
    for i in range(5):
        dy[i] = y[i + 5]
    dy[5] = (W0 - ftot) / me - tfr
    if p[14] > 0.5:
        dy[6] = 0.0
        dy[7] = 0.0
        dy[8] = 0.0
        dy[9] = 0.0
    else:
        dy[6] = (-cbx * y[6] - kbx * y[1] - ftot) / mp
        dy[7] = (-cbx * y[7] - kbx * y[2] + ftot) / mg
        dy[8] = (-cby * y[8] - kby * y[3] - ffr) / mp
        dy[9] = (-cby * y[9] - kby * y[4] + ffr) / mg


@njit(cache=True)
def _loads(y, j, K, MU, E, ED, p, out):  # pragma: no cover - compiled
    """Per-slot loads into ``out``; returns (total, friction force)."""
    b = p[13]
    cm = p[12]
    u = y[0] + y[1] - y[2] - E[j]
    dd = y[5] + y[6] - y[7] - ED[j]
    f = _dead_zone(u, b)
    ksum = 0.0
    for i in range(K.shape[1]):
        ksum += K[j, i]
    ftot = 0.0
    ffr = 0.0
    for i in range(K.shape[1]):
        ki = K[j, i]
        ni = 0.0
        if ki > 0.0:
            ni = ki * f + cm * ki / ksum * dd
            if ni > 0.0:
                ffr += MU[j, i] * ni
        out[i] = ni
        ftot += ni
    return ftot, ffr


@njit(cache=True)
def _step(y, j, K, MU, A1, A2, E, ED, p, h, k1, k2, k3, k4, tmp):  # pragma: no cover - compiled
    n2 = E.shape[0]
    j0 = 2 * j
    j1 = j0 + 1
    j2 = (j0 + 2) % n2
    _rhs(y, j0, K, MU, A1, A2, E, ED, p, k1)
    for i in range(10):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    _rhs(tmp, j1, K, MU, A1, A2, E, ED, p, k2)
    for i in range(10):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    _rhs(tmp, j1, K, MU, A1, A2, E, ED, p, k3)
    for i in range(10):
        tmp[i] = y[i] + h * k3[i]
    _rhs(tmp, j2, K, MU, A1, A2, E, ED, p, k4)
    for i in range(10):
        y[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True)
def _periods(y, n_periods, K, MU, A1, A2, E, ED, p, h, rec, loads, fric):  # pragma: no cover
    """Run ``n_periods``; Poincare points; record the last period if ``rec.shape[0] > 0``."""
    n = E.shape[0] // 2
    k1 = np.empty(10)
    k2 = np.empty(10)
    k3 = np.empty(10)
    k4 = np.empty(10)
    tmp = np.empty(10)
    pts = np.empty((n_periods, 10))
    out = np.empty(K.shape[1])
    for per in range(n_periods):
        last = per == n_periods - 1
        for j in range(n):
            if last and rec.shape[0] > 0:
                for i in range(10):
                    rec[j, i] = y[i]
                ftot, ffr = _loads(y, 2 * j, K, MU, E, ED, p, out)
                for i in range(K.shape[1]):
                    loads[j, i] = out[i]
                fric[j, 0] = ftot
                fric[j, 1] = ffr
            _step(y, j, K, MU, A1, A2, E, ED, p, h, k1, k2, k3, k4, tmp)
        for i in range(10):
            pts[per, i] = y[i]
    return pts


@njit(cache=True)
def _settle(
    y, K, MU, A1, A2, E, ED, p, h, scale, tol, min_periods, max_periods
):  # pragma: no cover
    n = E.shape[0] // 2
    k1 = np.empty(10)
    k2 = np.empty(10)
    k3 = np.empty(10)
    k4 = np.empty(10)
    tmp = np.empty(10)
    prev = np.empty(10)
    count = 0
    streak = 0
    converged = False
    while count < max_periods:
        for i in range(10):
            prev[i] = y[i]
        for j in range(n):
            _step(y, j, K, MU, A1, A2, E, ED, p, h, k1, k2, k3, k4, tmp)
        count += 1
        d = 0.0
        for i in range(10):
            r = abs(y[i] - prev[i]) / scale[i]
            if r > d:
                d = r
        if d < tol:
            streak += 1
        else:
            streak = 0
        if count >= min_periods and streak >= 3:
            converged = True
            break
    return count, converged


# ----------------------------------------------------------------------------- wrappers
def _check_state(y0: np.ndarray | None, model: TriboDynamics) -> np.ndarray:
    y = static_state(model) if y0 is None else np.array(y0, dtype=float)
    if y.shape != (N_STATE,) or not np.all(np.isfinite(y)):
        raise ModelError(f"initial state must be {N_STATE} finite numbers")
    return y


def _record(
    model: TriboDynamics, rec: np.ndarray, loads: np.ndarray, fric: np.ndarray
) -> TriboRecord:
    n = model.steps_per_period
    return TriboRecord(
        time_s=np.arange(n) * model.step_s,
        state=rec,
        dte_m=rec[:, 0] + rec[:, 1] - rec[:, 2],
        mesh_force_N=fric[:, 0].copy(),
        pair_load_N=loads,
        friction_force_N=fric[:, 1].copy(),
    )


def tribo_periods(
    model: TriboDynamics,
    n_periods: int,
    y0: np.ndarray | None = None,
    *,
    record: bool = False,
) -> tuple[np.ndarray, TriboRecord | None]:
    """Integrate ``n_periods`` mesh periods from phase 0 with the compiled RK4.

    Parameters
    ----------
    model : TriboDynamics
    n_periods : int
        Whole mesh periods, >= 1.
    y0 : array_like, optional
        Initial state (10,) (m, m/s); default :func:`static_state`.
    record : bool
        Also return the last period at every step start.

    Returns
    -------
    tuple
        Poincare points ``(n_periods, 10)`` (state at the end of each period) and the
        :class:`TriboRecord` of the last period (or None).
    """
    if int(n_periods) != n_periods or n_periods < 1:
        raise ModelError(f"`n_periods` must be an integer >= 1, was {n_periods!r}")
    y = _check_state(y0, model)
    n = model.steps_per_period
    ns = np.shape(model.mesh_stiffness_N_m)[1]
    rec = np.empty((n if record else 0, N_STATE))
    loads = np.empty((n if record else 0, ns))
    fric = np.empty((n if record else 0, 2))
    K, MU, A1, A2, E, ED = model.tables()
    pts = _periods(
        y, int(n_periods), K, MU, A1, A2, E, ED, model.params(), model.step_s, rec, loads, fric
    )
    return pts, (_record(model, rec, loads, fric) if record else None)


def tribo_settle(
    model: TriboDynamics,
    y0: np.ndarray | None = None,
    *,
    tol: float = 1e-7,
    min_periods: int = 5,
    max_periods: int = 2000,
) -> tuple[np.ndarray, int, TriboRecord]:
    """Run whole periods to the periodic steady state, then record one more period.

    The Poincare point (state at phase 0) must move by less than ``tol`` times its scale for
    3 periods running: displacements scaled by the static mesh deflection ``W_0 / k_mean``,
    velocities by that times ``2 pi / T_m``.

    Returns
    -------
    tuple
        The state at the start of the recorded period, the periods run before it, and the
        :class:`TriboRecord`.

    Raises
    ------
    ModelError
        Not periodic within ``max_periods`` (period-n or chaotic response).
    """
    y = _check_state(y0, model)
    k_mean = float(np.mean(model.combined_stiffness_N_m.sum(axis=1)))
    xs = model.load_N / k_mean
    scale = np.concatenate([np.full(5, xs), np.full(5, xs * 2 * math.pi / model.mesh_period_s)])
    K, MU, A1, A2, E, ED = model.tables()
    count, ok = _settle(
        y,
        K,
        MU,
        A1,
        A2,
        E,
        ED,
        model.params(),
        model.step_s,
        scale,
        float(tol),
        int(min_periods),
        int(max_periods),
    )
    if not ok:
        raise ModelError(
            f"the response did not become periodic within {max_periods} mesh "
            f"periods (tolerance {tol:g}); it may be period-n or chaotic"
        )
    start = y.copy()
    _, rec = tribo_periods(model, 1, y, record=True)
    assert rec is not None
    return start, int(count), rec


def tribo_periods_reference(
    model: TriboDynamics, n_periods: int, y0: np.ndarray | None = None
) -> np.ndarray:
    """Same RK4, same operation order, plain Python: Poincare points ``(n_periods, 10)``."""
    y = _check_state(y0, model).tolist()
    K, MU, A1, A2, E, ED = (a.tolist() for a in model.tables())
    p = model.params().tolist()
    h = model.step_s
    n2 = len(E)
    n = n2 // 2
    k1, k2, k3, k4 = ([0.0] * 10 for _ in range(4))
    pts = np.empty((int(n_periods), N_STATE))
    for per in range(int(n_periods)):
        for j in range(n):
            j0, j1, j2 = 2 * j, 2 * j + 1, (2 * j + 2) % n2
            tribo_rhs(y, j0, K, MU, A1, A2, E, ED, p, k1)
            tmp = [y[i] + 0.5 * h * k1[i] for i in range(10)]
            tribo_rhs(tmp, j1, K, MU, A1, A2, E, ED, p, k2)
            tmp = [y[i] + 0.5 * h * k2[i] for i in range(10)]
            tribo_rhs(tmp, j1, K, MU, A1, A2, E, ED, p, k3)
            tmp = [y[i] + h * k3[i] for i in range(10)]
            tribo_rhs(tmp, j2, K, MU, A1, A2, E, ED, p, k4)
            y = [y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) for i in range(10)]
        pts[per] = y
    return pts
