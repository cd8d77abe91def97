"""Compiled kernels of the two-stage model (seed 001): RK4 over system periods and map rows.

All numba kernels of :mod:`models.dynamics.two_stage` and :mod:`models.dynamics.two_stage_maps`
live in this one file. numba's on-disk cache (``cache=True``) checks only the source file of
the function it loads: a map kernel in another file that inlines :func:`rk4_system_periods`
would keep running the old ``rk4_system_periods`` from its cache after it is edited. With every
kernel here, any edit of any kernel changes this file and invalidates all of them together (the
test suite checks that no cached kernel calls a compiled function from another file).

* :func:`rk4_system_periods`: fixed-step RK4 of the non-dimensional two-stage equations
  (module docstring of :mod:`models.dynamics.two_stage`) over ``n_sys`` system periods, with
  tables of ``kappa`` and ``eps`` at the half steps;
* :func:`_fill_row`: one temperature row of a peak-DTE map (steady response at every
  frequency, state carried along the row), with NaN-safe peaks and a divergence flag;
* :func:`map_rows_parallel` / :func:`map_rows_serial`: all rows, ``prange`` or serial (same
  row function, identical results), into the arrays of :func:`allocate_map_outputs`.

The kernels take the non-dimensional arrays that :mod:`models.dynamics.two_stage`
(``TwoStageModel.params``, ``TwoStageModel.tables``) and
:func:`models.dynamics.two_stage_maps.prepare_map_grid` build; they check nothing.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = [
    "allocate_map_outputs",
    "map_rows_parallel",
    "map_rows_serial",
    "rk4_system_periods",
]


@njit(cache=True)
def _dz(u, b):  # pragma: no cover - compiled
    if u > b:
        return u - b
    if u < -b:
        return u + b
    return 0.0


@njit(cache=True)
def _acc(x1, v1, x3, v3, k1, e1, k3, e3, P):  # pragma: no cover - compiled
    g1 = 2.0 * P[0] * v1 + k1 * _dz(x1 - e1, P[1])
    g3 = 2.0 * P[2] * P[6] * v3 + P[6] * P[6] * k3 * _dz(x3 - e3, P[3])
    return P[4] - g1 + P[7] * g3, P[5] - g3 + P[8] * g1


@njit(cache=True)
def rk4_system_periods(y, P, T, h, n_sys, rec):  # pragma: no cover - compiled
    """RK4 over ``n_sys`` system periods from the state ``y = (x1, x1', x3, x3')``.

    Parameters
    ----------
    y : numpy.ndarray
        Start state, shape ``(4,)`` (non-dimensional).
    P : numpy.ndarray
        Model parameters (``TwoStageModel.params()``), shape ``(9,)``.
    T : numpy.ndarray
        ``kappa_1, eps_1, kappa_3, eps_3`` at the ``2 m`` half steps of one system period
        (``TwoStageModel.tables(N)``), shape ``(4, 2 m)``.
    h : float
        RK4 step (non-dimensional time).
    n_sys : int
        System periods to run.
    rec : bool
        Record ``(x1, u1, x3, u3)`` at every step start.

    Returns
    -------
    pts : numpy.ndarray
        State at the end of each system period (Poincare points), shape ``(n_sys, 4)``.
    hist : numpy.ndarray
        The record, shape ``(n_sys m, 4)`` with ``rec``, else ``(0, 4)``.
    """
    m = T.shape[1] // 2
    x1, v1, x3, v3 = y[0], y[1], y[2], y[3]
    pts = np.empty((n_sys, 4))
    hist = np.empty((n_sys * m if rec else 0, 4))
    i = 0
    for s in range(n_sys):
        for j in range(m):
            j0 = 2 * j
            j1 = j0 + 1
            j2 = (j0 + 2) % (2 * m)
            if rec:
                hist[i, 0] = x1
                hist[i, 1] = x1 - T[1, j0]
                hist[i, 2] = x3
                hist[i, 3] = x3 - T[3, j0]
            a1, b1 = _acc(x1, v1, x3, v3, T[0, j0], T[1, j0], T[2, j0], T[3, j0], P)
            x1b = x1 + 0.5 * h * v1
            v1b = v1 + 0.5 * h * a1
            x3b = x3 + 0.5 * h * v3
            v3b = v3 + 0.5 * h * b1
            a2, b2 = _acc(x1b, v1b, x3b, v3b, T[0, j1], T[1, j1], T[2, j1], T[3, j1], P)
            x1c = x1 + 0.5 * h * v1b
            v1c = v1 + 0.5 * h * a2
            x3c = x3 + 0.5 * h * v3b
            v3c = v3 + 0.5 * h * b2
            a3, b3 = _acc(x1c, v1c, x3c, v3c, T[0, j1], T[1, j1], T[2, j1], T[3, j1], P)
            x1d = x1 + h * v1c
            v1d = v1 + h * a3
            x3d = x3 + h * v3c
            v3d = v3 + h * b3
            a4, b4 = _acc(x1d, v1d, x3d, v3d, T[0, j2], T[1, j2], T[2, j2], T[3, j2], P)
            x1n = x1 + h / 6.0 * (v1 + 2.0 * v1b + 2.0 * v1c + v1d)
            v1n = v1 + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            x3n = x3 + h / 6.0 * (v3 + 2.0 * v3b + 2.0 * v3c + v3d)
            v3n = v3 + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
            x1, v1, x3, v3 = x1n, v1n, x3n, v3n
            i += 1
        pts[s, 0] = x1
        pts[s, 1] = v1
        pts[s, 2] = x3
        pts[s, 3] = v3
    return pts, hist


@njit(cache=True)
def _finite4(y):  # pragma: no cover - compiled
    return np.isfinite(y[0]) and np.isfinite(y[1]) and np.isfinite(y[2]) and np.isfinite(y[3])


@njit(cache=True)
def _fill_row(
    i, Y0, P, T, M, H, order, carry, n_trans, n_rec, peak, peak_u, amp, loss, back, div, poinc
):  # pragma: no cover - compiled
    """Row ``i``: steady response at each frequency ``order[jj]`` (see ``peak_dte_map``).

    ``T[i, j, :, :M[j]]`` holds point ``(i, j)``'s tables (``M[j] = 2 q N_j`` half steps).
    A point whose state or record turns non-finite is flagged in ``div``, its results set
    to NaN, and the next point of the row starts again from its static state.
    """
    y = Y0[i, order[0]].copy()
    for jj in range(order.size):
        j = order[jj]
        if not carry:
            y = Y0[i, j].copy()
        Tij = np.ascontiguousarray(T[i, j, :, : M[j]])
        pts, _ = rk4_system_periods(y, P[i, j], Tij, H[j], n_trans, False)
        if n_trans > 0:
            y = pts[n_trans - 1].copy()
        pts2, hist = rk4_system_periods(y, P[i, j], Tij, H[j], n_rec, True)
        b1 = P[i, j, 1]
        b3 = P[i, j, 3]
        ok = _finite4(pts2[n_rec - 1])
        mx1 = 0.0
        mx3 = 0.0
        mu1 = 0.0
        mu3 = 0.0
        lo1 = hist[0, 0]
        hi1 = hist[0, 0]
        lo3 = hist[0, 2]
        hi3 = hist[0, 2]
        l1 = False
        l3 = False
        k1 = False
        k3 = False
        for r in range(hist.shape[0]):
            x1 = hist[r, 0]
            x3 = hist[r, 2]
            u1 = hist[r, 1]
            u3 = hist[r, 3]
            if not (np.isfinite(x1) and np.isfinite(x3)):
                ok = False
                break
            # written so that a NaN could never be skipped by max()
            if not abs(x1) <= mx1:
                mx1 = abs(x1)
            if not abs(x3) <= mx3:
                mx3 = abs(x3)
            if not abs(u1) <= mu1:
                mu1 = abs(u1)
            if not abs(u3) <= mu3:
                mu3 = abs(u3)
            lo1 = min(lo1, x1)
            hi1 = max(hi1, x1)
            lo3 = min(lo3, x3)
            hi3 = max(hi3, x3)
            if b1 > 0 and abs(u1) <= b1:
                l1 = True
            if b3 > 0 and abs(u3) <= b3:
                l3 = True
            if u1 < -b1:
                k1 = True
            if u3 < -b3:
                k3 = True
        if ok:
            peak[i, j, 0] = mx1
            peak[i, j, 1] = mx3
            peak_u[i, j, 0] = mu1
            peak_u[i, j, 1] = mu3
            amp[i, j, 0] = (hi1 - lo1) / 2
            amp[i, j, 1] = (hi3 - lo3) / 2
            loss[i, j, 0] = l1
            loss[i, j, 1] = l3
            back[i, j, 0] = k1
            back[i, j, 1] = k3
            div[i, j] = False
            for s in range(n_rec):
                poinc[i, j, s, 0] = pts2[s, 0]
                poinc[i, j, s, 1] = pts2[s, 2]
            y = pts2[n_rec - 1].copy()
        else:
            for st in range(2):
                peak[i, j, st] = np.nan
                peak_u[i, j, st] = np.nan
                amp[i, j, st] = np.nan
                loss[i, j, st] = False
                back[i, j, st] = False
                for s in range(n_rec):
                    poinc[i, j, s, st] = np.nan
            div[i, j] = True
            if jj + 1 < order.size:
                y = Y0[i, order[jj + 1]].copy()


@njit(parallel=True, cache=True)
def map_rows_parallel(
    Y0, P, T, M, H, order, carry, n_trans, n_rec, peak, peak_u, amp, loss, back, div, poinc
):  # pragma: no cover - compiled
    """All rows of a peak-DTE map, rows in parallel (``prange``); results into the outputs.

    ``Y0, P, T, M, H, order`` are ``MapGrid.kernel_args()``
    (:func:`~models.dynamics.two_stage_maps.prepare_map_grid`); ``carry`` carries the state
    along a row; ``n_trans`` and ``n_rec`` are the system periods dropped and recorded at each
    point; the rest are the arrays of :func:`allocate_map_outputs`, filled in place.
    """
    for i in prange(Y0.shape[0]):
        _fill_row(
            i,
            Y0,
            P,
            T,
            M,
            H,
            order,
            carry,
            n_trans,
            n_rec,
            peak,
            peak_u,
            amp,
            loss,
            back,
            div,
            poinc,
        )


@njit(cache=True)
def map_rows_serial(
    Y0, P, T, M, H, order, carry, n_trans, n_rec, peak, peak_u, amp, loss, back, div, poinc
):  # pragma: no cover - compiled
    """All rows of a peak-DTE map, one after the other: :func:`map_rows_parallel`'s results."""
    for i in range(Y0.shape[0]):
        _fill_row(
            i,
            Y0,
            P,
            T,
            M,
            H,
            order,
            carry,
            n_trans,
            n_rec,
            peak,
            peak_u,
            amp,
            loss,
            back,
            div,
            poinc,
        )


def allocate_map_outputs(n_t: int, n_f: int, n_rec: int):
    """Output arrays of the map kernels, for ``n_t`` temperatures and ``n_f`` frequencies.

    Parameters
    ----------
    n_t, n_f : int
        Rows (temperatures) and columns (frequencies) of the map.
    n_rec : int
        Recorded system periods per point.

    Returns
    -------
    tuple of numpy.ndarray
        ``peak, peak_u, amp`` (float, ``(n_t, n_f, 2)``), ``loss, back`` (bool,
        ``(n_t, n_f, 2)``), ``diverged`` (bool, ``(n_t, n_f)``) and ``poincare`` (float,
        ``(n_t, n_f, n_rec, 2)``), in the order the kernels take them.
    """
    return (
        np.empty((n_t, n_f, 2)),
        np.empty((n_t, n_f, 2)),
        np.empty((n_t, n_f, 2)),
        np.zeros((n_t, n_f, 2), dtype=np.bool_),
        np.zeros((n_t, n_f, 2), dtype=np.bool_),
        np.zeros((n_t, n_f), dtype=np.bool_),
        np.empty((n_t, n_f, n_rec, 2)),
    )
