r"""Compiled (numba) walker sweeps: many parameter sets of one SDOF model along one path.

The kernel behind :mod:`models.dynamics.walkers` (which sets the method's parameters and
documents the method and its error contract). :func:`walker_sweep_kernel` sweeps many
parameter sets ("walkers") of one single-column model (FVMS / VVMS / LSTE), ``prange`` over
them. Each walker builds its tables from a bank of curves at stiffness-scale nodes (4-point
Lagrange in ``log s``, alternating parts scaled; :func:`_walker_tables`) and runs its
time-ordered path (:func:`_walker_path`), each point by Newton shooting on the period-1
Poincare map (:func:`_shoot`) with the settling of
:func:`~models.dynamics.sdof_kernels.steady_kernel` as the fallback, or by settling alone. The
first point, and any point after a response that is not a settled period-1 orbit, is settled.

Newton shooting runs RK4 on the state and its 2 x 2 variational equations
(:func:`_period_monodromy`, the same stages and tables as
:func:`~models.dynamics.sdof_kernels.rk4_step`, so the state it follows is the settling
kernel's to the bit) and accepts a fixed point on its residual, Jury stability of the
monodromy matrix ``M``, a continuation guard against the previous point's orbit, and a basin
check in the orbit's Lyapunov metric ``V(d) = d^T P d``, ``P - M^T P M = I``
(:func:`_lyapunov_form`), along the first periods of the transient. Each Newton iterate is
verified by the recorded plain period from it (:func:`~models.dynamics.sdof_kernels.record_kernel`,
whose end state is the Poincare map), conditions 2-4 then judged with the monodromy of the
previous iterate (:func:`_shoot`, ``verify_record``; 3 period-equivalents per accepted point
instead of 5); continuation nodes may be skipped far from folds (:func:`_walker_path`,
``record``, :func:`_far_from_fold` and a bound on the orbit's predicted move). The measured
effect of both is in :mod:`models.dynamics.walkers` ("Methods").

The kernels here call the compiled RK4 step, period, recorder and settling of
:mod:`models.dynamics.sdof_kernels`, which numba inlines into this file's cached kernels; the
cache of every kernel here is therefore tied to that file
(:func:`models.dynamics.kernel_cache.tie_cache`, at the bottom): an edit of
``sdof_kernels.py`` flushes them.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numba import njit, prange

from models.dynamics.kernel_cache import tie_cache
from models.dynamics.sdof_kernels import (
    SETTLE_RING,
    record_kernel,
    rk4_period,
    rk4_step,
    steady_kernel,
)

__all__ = ["walker_sweep_kernel"]

#: Fraction of the linearised decrease of the orbit's Lyapunov function that one plain period
#: from the entry state must achieve for a Newton orbit to be accepted (see walkers.py).
_BASIN_DECREASE: Final = 0.5
#: Fraction of its entry value the Lyapunov function must have fallen to before the orbit is
#: accepted (decrease alone let entry states beyond the basin boundary through) ...
_BASIN_CONTRACTION: Final = 0.1
#: ... unless the entry state lies within this fraction of the continuation guard of the orbit
#: (a small step of the path: the linear neighbourhood), where one period's decrease suffices.
_BASIN_NEAR: Final = 0.05


@njit(cache=True)
def _bank_weights(log_nodes, log_s, wts):  # pragma: no cover - compiled
    """4-point Lagrange weights in ``log s``; returns the first node index (``wts`` filled)."""
    m = log_nodes.size
    i = 0
    while i < m - 2 and log_nodes[i + 1] <= log_s:
        i += 1
    i0 = min(max(i - 1, 0), m - 4)
    for a in range(4):
        w = 1.0
        for c in range(4):
            if c != a:
                w *= (log_s - log_nodes[i0 + c]) / (log_nodes[i0 + a] - log_nodes[i0 + c])
        wts[a] = w
    return i0


@njit(cache=True)
def _walker_tables(log_nodes, kbank, ebank, bbank, log_s, eps, kd, ed, kb, eb):  # pragma: no cover
    """Fill one walker's ``(2 N, 1)`` tables from the bank rows; returns ``mean(e)``.

    ``kbank``, ``ebank``, ``bbank`` are ``(J, 2 N)``: ``tilde k``, ``tilde e`` and the back
    offset at the nodes; the alternating parts (about each interpolated row's mean) are
    multiplied by ``eps``.
    """
    wts = np.empty(4)
    i0 = _bank_weights(log_nodes, log_s, wts)
    n2 = kbank.shape[1]
    km = 0.0
    em = 0.0
    bm = 0.0
    for j in range(n2):
        k = 0.0
        e = 0.0
        g = 0.0
        for a in range(4):
            k += wts[a] * kbank[i0 + a, j]
            e += wts[a] * ebank[i0 + a, j]
            g += wts[a] * bbank[i0 + a, j]
        kd[j, 0] = k
        ed[j, 0] = e
        eb[j, 0] = g
        km += k
        em += e
        bm += g
    km /= n2
    em /= n2
    bm /= n2
    for j in range(n2):
        kd[j, 0] = km + eps * (kd[j, 0] - km)
        kb[j, 0] = kd[j, 0]
        ed[j, 0] = em + eps * (ed[j, 0] - em)
        eb[j, 0] = bm + eps * (eb[j, 0] - bm)
    return em


@njit(cache=True)
def _tangent_rhs(y, j, zeta, force, b, kd, ed, kb, eb):  # pragma: no cover - compiled
    """Right-hand side of the state and its 2 x 2 variational equations (one-column model).

    ``y = (x, x', p11, p12, p21, p22)``: ``x'' = F - 2 zeta x' - f(x)`` as in the right-hand side of
    :func:`~models.dynamics.sdof_kernels.rk4_step`
    at half step ``j`` (column 0 only) and ``P' = [[0, 1], [-f'(x), -2 zeta]] P``, ``f'`` the
    tangent stiffness ``d(contact force)/dx``.
    """
    x = y[0]
    u = x - ed[j, 0]
    w = x - eb[j, 0]
    f = 0.0
    kk = 0.0
    if u > b:
        f += kd[j, 0] * (u - b)
        kk += kd[j, 0]
    if w < -b:
        f += kb[j, 0] * (w + b)
        kk += kb[j, 0]
    tz = 2.0 * zeta
    return (
        y[1], force - 2.0 * zeta * y[1] - f,
        y[4], y[5], -kk * y[2] - tz * y[4], -kk * y[3] - tz * y[5],
    )


@njit(cache=True)
def _stage(y, c, k):  # pragma: no cover - compiled
    """``y + c k`` for the 6-tuples of :func:`_tangent_rhs` (an RK4 stage's argument)."""
    return (
        y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2],
        y[3] + c * k[3], y[4] + c * k[4], y[5] + c * k[5],
    )


@njit(cache=True)
def _rk4_update(y, h, k1, k2, k3, k4):  # pragma: no cover - compiled
    """``y + h (k1 + 2 k2 + 2 k3 + k4) / 6`` for the 6-tuples of :func:`_tangent_rhs`."""
    g = h / 6.0
    return (
        y[0] + g * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        y[1] + g * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
        y[2] + g * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
        y[3] + g * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]),
        y[4] + g * (k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4]),
        y[5] + g * (k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5]),
    )


@njit(cache=True)
def _period_monodromy(x, v, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    """One period from ``(x, v)`` with RK4 on the state and its 2 x 2 variational equations.

    The state update is :func:`~models.dynamics.sdof_kernels.rk4_step`'s (same stages, same
    tables); returns ``(x, v, m11, m12, m21, m22)`` with ``M`` the monodromy matrix of the
    discrete map.
    """
    n2 = kd.shape[0]
    y = (x, v, 1.0, 0.0, 0.0, 1.0)
    for j in range(n2 // 2):
        j0 = 2 * j
        k1 = _tangent_rhs(y, j0, zeta, force, b, kd, ed, kb, eb)
        k2 = _tangent_rhs(_stage(y, 0.5 * h, k1), j0 + 1, zeta, force, b, kd, ed, kb, eb)
        k3 = _tangent_rhs(_stage(y, 0.5 * h, k2), j0 + 1, zeta, force, b, kd, ed, kb, eb)
        k4 = _tangent_rhs(_stage(y, h, k3), (j0 + 2) % n2, zeta, force, b, kd, ed, kb, eb)
        y = _rk4_update(y, h, k1, k2, k3, k4)
    return y


@njit(cache=True)
def _lyapunov_form(a, b, c, d):  # pragma: no cover - compiled
    """``P`` (symmetric, ``(p11, p12, p22)``) of ``P - M^T P M = I`` for ``M = [[a, b], [c, d]]``.

    Returns NaNs when the 3 x 3 system is singular (a multiplier on the unit circle).
    """
    # rows: (1,1), (1,2), (2,2) of P - M^T P M = I in the unknowns p11, p12, p22
    m00 = 1.0 - a * a
    m01 = -2.0 * a * c
    m02 = -c * c
    m10 = -a * b
    m11 = 1.0 - (a * d + b * c)
    m12 = -c * d
    m20 = -b * b
    m21 = -2.0 * b * d
    m22 = 1.0 - d * d
    det = (m00 * (m11 * m22 - m12 * m21) - m01 * (m10 * m22 - m12 * m20)
           + m02 * (m10 * m21 - m11 * m20))
    if det == 0.0 or not math.isfinite(det):
        return math.nan, math.nan, math.nan
    # right-hand side (1, 0, 1), Cramer's rule
    p11 = (1.0 * (m11 * m22 - m12 * m21) - m01 * (0.0 * m22 - m12 * 1.0)
           + m02 * (0.0 * m21 - m11 * 1.0)) / det
    p12 = (m00 * (0.0 * m22 - m12 * 1.0) - 1.0 * (m10 * m22 - m12 * m20)
           + m02 * (m10 * 1.0 - 0.0 * m20)) / det
    p22 = (m00 * (m11 * 1.0 - 0.0 * m21) - m01 * (m10 * 1.0 - 0.0 * m20)
           + 1.0 * (m10 * m21 - m11 * m20)) / det
    return p11, p12, p22


@njit(cache=True)
def _orbit_range(x, v, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    """One plain period from ``(x, v)``: ``(x, v, x range, v range)`` (max - min, step ends)."""
    n = kd.shape[0] // 2
    xlo = x
    xhi = x
    vlo = v
    vhi = v
    for j in range(n):
        x, v = rk4_step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
        xlo = min(xlo, x)
        xhi = max(xhi, x)
        vlo = min(vlo, v)
        vhi = max(vhi, v)
    return x, v, xhi - xlo, vhi - vlo


@njit(cache=True)
def _lyapunov_value(p11, p12, p22, dx, dv):  # pragma: no cover - compiled
    return p11 * dx * dx + 2.0 * p12 * dx * dv + p22 * dv * dv


@njit(cache=True)
def _accept(
    x, v, xs, vs, x1, v1, m11, m12, m21, m22, zeta, force, b, kd, ed, kb, eb, h, tol, scale,
    guard_x, guard_v, basin_periods, basin_repeats,
):  # pragma: no cover - compiled
    """Conditions 2-4 of :func:`_shoot` for the fixed point ``y* = (xs, vs)`` (1 holds).

    ``(x, v)`` is the entry state ``y0``, ``(x1, v1) = P(y0)``, ``M`` the monodromy matrix the
    conditions are judged with. Returns ``(ok, x, v, periods)``: ``(x, v)`` the state the
    settling fallback continues from when rejected (the entry state, or the transient's state
    after the periods followed).
    """
    det = m11 * m22 - m12 * m21
    tr = m11 + m22
    if not (abs(det) < 1.0 and abs(tr) < 1.0 + det):
        return False, x, v, 0
    d0x = x - xs
    d0v = v - vs
    if not (abs(d0x) <= guard_x and abs(d0v) <= guard_v):
        return False, x, v, 0
    if max(abs(d0x), abs(d0v)) <= 10.0 * tol * scale:
        return True, xs, vs, 0
    p11, p12, p22 = _lyapunov_form(m11, m12, m21, m22)
    if not math.isfinite(p11):
        return False, x, v, 0
    q0 = _lyapunov_value(p11, p12, p22, d0x, d0v)
    q1 = _lyapunov_value(p11, p12, p22, x1 - xs, v1 - vs)
    near = (abs(d0x) <= _BASIN_NEAR * guard_x and abs(d0v) <= _BASIN_NEAR * guard_v)
    if (q1 <= q0 - _BASIN_DECREASE * (d0x * d0x + d0v * d0v)
            and (near or q1 <= _BASIN_CONTRACTION * q0)):
        return True, xs, vs, 0
    # follow the physical transient from P(y0), one plain period at a time
    cost = 0
    xa = x1
    va = v1
    good = 0
    for _ in range(basin_periods):
        dx = xa - xs
        dv = va - vs
        qa = _lyapunov_value(p11, p12, p22, dx, dv)
        xa, va = rk4_period(xa, va, zeta, force, b, kd, ed, kb, eb, h)
        cost += 1
        if not (math.isfinite(xa) and math.isfinite(va)):
            return False, x, v, cost
        qb = _lyapunov_value(p11, p12, p22, xa - xs, va - vs)
        if qb <= qa - _BASIN_DECREASE * (dx * dx + dv * dv):
            good += 1
            if good >= basin_repeats and qb <= _BASIN_CONTRACTION * q0:
                return True, xs, vs, cost
        else:
            good = 0
    return False, xa, va, cost


@njit(cache=True)
def _shoot(
    x, v, zeta, force, b, kd, ed, kb, eb, h, tol, max_newton, guard_x, guard_v, basin_periods,
    basin_repeats, verify_record, npair, cs, sn, ring, amps,
):  # pragma: no cover - compiled
    """Newton on the period-1 Poincare map from the entry state ``y0 = (x, v)``.

    Accepts the fixed point ``y*`` when (1) ``|P(y) - y| < tol`` (max norm), (2) both Floquet
    multipliers lie inside the unit circle (Jury test on the monodromy matrix ``M``), (3) the
    *continuation guard*: ``|x* - x0| <= guard_x`` and ``|v* - v0| <= guard_v`` (the orbit
    continues the branch the entry state is on), and (4) the *basin check* in the orbit's
    quadratic Lyapunov function ``V(d) = d^T P d`` (``P - M^T P M = I``) of ``d = y - y*``: a
    period from ``y_k`` decreases it by at least half of what the linearised map gives,
    ``V(d_(k+1)) <= V(d_k) - |d_k|^2 / 2``, either at once from the entry state (``k = 0``) or
    for ``basin_repeats`` consecutive periods of the physical transient followed for at most
    ``basin_periods`` plain periods. Entry states within ``10 tol`` of ``y*`` pass (4) at once.

    Without ``verify_record`` every iterate ``y_k`` gets a variational period (``P(y_k)`` and
    ``M(y_k)``), and (1)-(4) are judged at the first iterate whose residual is below ``tol``
    with its own ``M``; the caller then records a period from ``y*``. With ``verify_record``
    (the default of :mod:`models.dynamics.walkers`) each Newton iterate ``y_(k+1)`` is checked
    by the *recorded* plain period from it (:func:`~models.dynamics.sdof_kernels.record_kernel`
    into ``amps``: its end state is ``P(y_(k+1))``), and (2)-(4) are judged with
    ``M(y_k)``, the monodromy of the last Newton iterate (off by ``O(|y_(k+1) - y_k|)``); a
    residual above ``tol`` continues Newton from ``y_(k+1)``. An accepted point then costs
    one variational and one plain period (3 equivalents) instead of two and one (5).

    Returns ``(status, x, v, periods, loss, impact, x range, v range, trace, det)``: status 0
    rejected (``(x, v)`` the state the settling fallback continues from: the entry state, or
    the transient's after the periods followed), 1 accepted with ``(x, v) = y*`` (not
    recorded), 2 accepted and recorded (``(x, v)`` the recorded period's end state, ``amps``
    filled, flags and ranges returned); periods counted as plain-period equivalents (a
    variational period as 2); ``trace`` and ``det`` those of the ``M`` the point was judged
    with (NaN unless accepted).
    """
    xs = x
    vs = v
    cost = 0
    x1 = math.nan
    v1 = math.nan
    nan = math.nan
    for it in range(max_newton):
        xp, vp, m11, m12, m21, m22 = _period_monodromy(xs, vs, zeta, force, b, kd, ed, kb, eb, h)
        cost += 2
        if it == 0:
            x1 = xp
            v1 = vp
        r0 = xp - xs
        r1 = vp - vs
        scale = max(1.0, abs(xs), abs(vs))
        if max(abs(r0), abs(r1)) < tol * scale:
            ok, xf, vf, c = _accept(
                x, v, xs, vs, x1, v1, m11, m12, m21, m22, zeta, force, b, kd, ed, kb, eb, h,
                tol, scale, guard_x, guard_v, basin_periods, basin_repeats,
            )
            if ok:
                return 1, xf, vf, cost + c, False, False, nan, nan, m11 + m22, m11 * m22 - m12 * m21
            return 0, xf, vf, cost + c, False, False, nan, nan, nan, nan
        a11 = m11 - 1.0
        a22 = m22 - 1.0
        d = a11 * a22 - m12 * m21
        if d == 0.0 or not math.isfinite(d):
            break
        xs += (-r0 * a22 + m12 * r1) / d
        vs += (-a11 * r1 + m21 * r0) / d
        if not (math.isfinite(xs) and math.isfinite(vs)):
            break
        if verify_record:
            xe, ve, _mu, lo, im, _pa, rx, rv = record_kernel(
                xs, vs, zeta, force, b, kd, ed, kb, eb, ed[:, 0], eb[:, 0], npair, cs, sn, h, 1,
                ring, 0, amps,
            )
            cost += 1
            scale = max(1.0, abs(xs), abs(vs))
            if max(abs(xe - xs), abs(ve - vs)) < tol * scale:
                ok, xf, vf, c = _accept(
                    x, v, xs, vs, x1, v1, m11, m12, m21, m22, zeta, force, b, kd, ed, kb, eb,
                    h, tol, scale, guard_x, guard_v, basin_periods, basin_repeats,
                )
                if ok:
                    return 2, xe, ve, cost + c, lo, im, rx, rv, m11 + m22, m11 * m22 - m12 * m21
                return 0, xf, vf, cost + c, False, False, nan, nan, nan, nan
    return 0, x, v, cost, False, False, nan, nan, nan, nan


@njit(cache=True)
def _far_from_fold(tr, det, margin):  # pragma: no cover - compiled
    """Whether the multipliers of ``M`` (trace ``tr``, determinant ``det``) are clear of +-1.

    Clear of 1 and -1 (a fold or a flip): ``|det(M -+ I)| >= margin (1 - sqrt(det M))^2``.

    ``det(M - I) = (1 - mu_1)(1 - mu_2) = 1 - tr + det`` (``1 + tr + det`` for -1). For a
    complex pair ``r e^(+-i theta)`` it is ``(1 - r)^2 + 2 r (1 -+ cos theta)``: with
    ``r = sqrt(det)`` the orbit's contraction per period, the ratio to ``(1 - r)^2`` is 1 when
    the pair meets on the real axis and grows with the angle from it; a real pair splitting
    towards 1 (a fold) or -1 (a flip) drives it to 0. Since ``theta`` is the phase the free
    oscillation turns per mesh period, small ratios flag the resonances, where the folds are.
    """
    if not (math.isfinite(tr) and math.isfinite(det)) or det <= 0.0:
        return False
    c = 1.0 - math.sqrt(det)
    return min(1.0 - tr + det, 1.0 + tr + det) >= margin * c * c


@njit(cache=True)
def _walker_path(
    x, v, zeta, force, b, kd, ed, kb, eb, npair, cs, sn, lam, tol, shoot, max_newton,
    min_periods, max_periods, guard, guard_floor, basin_periods, basin_repeats, verify_record,
    record, skip_step, skip_move, fold_margin, ring, poinc, amps, loss, impact, converged,
    newton, periods_run, solved,
):  # pragma: no cover - compiled
    """One walker's sweep along ``lam`` (time order), carrying the state; fills its rows.

    With ``shoot``, Newton is tried only where the entry state lies on a period-1 orbit of the
    previous point (Newton-accepted, or settled with period 1), whose ranges size the
    continuation guard (``guard`` times the range plus ``guard_floor``); the first point and
    the point after a period-n, aperiodic or unsettled response are settled.

    A node with ``record[i]`` False (a continuation node) is skipped when the last solved node
    was a Newton orbit far from a fold (:func:`_far_from_fold` with ``fold_margin``) and the
    next node lies within ``skip_step`` of it in ``ln lam`` (``skip_step <= 0``: never): no
    solve, the state is carried unchanged, its outputs are the last solved node's with
    ``periods_run`` 0 and ``solved`` False. The last node is never skipped.
    """
    n = kd.shape[0] // 2
    rx = -1.0  # orbit ranges of the previous point; < 0: no period-1 predictor
    rv = -1.0
    far = False  # the last solved node is a Newton orbit far from a fold
    rate = 0.0  # its orbit's move from the entry state per unit ln lam, in guards
    last = -1  # index of the last solved node
    for i in range(lam.size):
        step = abs(math.log(lam[i + 1] / lam[last])) if far and i + 1 < lam.size else math.inf
        if not record[i] and step <= skip_step and rate * step <= skip_move:
            for k in range(amps.shape[1]):
                amps[i, k] = amps[last, k]
            loss[i] = loss[last]
            impact[i] = impact[last]
            converged[i] = converged[last]
            newton[i] = False
            periods_run[i] = 0
            solved[i] = False
            continue
        solved[i] = True
        step = abs(math.log(lam[i] / lam[last])) if last >= 0 else 0.0
        last = i
        far = False
        h = 2.0 * math.pi / (lam[i] * n)
        status = 0
        cost = 0
        xs = x
        vs = v
        if shoot and rx >= 0.0:
            status, xs, vs, cost, lo, im, rx2, rv2, tr, det = _shoot(
                x, v, zeta, force, b, kd, ed, kb, eb, h, tol, max_newton,
                guard * rx + guard_floor, guard * rv + guard_floor, basin_periods,
                basin_repeats, verify_record, npair, cs, sn, ring, amps[i],
            )
            if status > 0 and skip_step > 0.0:
                far = _far_from_fold(tr, det, fold_margin) and step > 0.0
                rate = max(abs(x - xs) / (guard * rx + guard_floor),
                           abs(v - vs) / (guard * rv + guard_floor)) / max(step, 1e-300)
        if status == 2:
            x = xs
            v = vs
            rx = rx2
            rv = rv2
            loss[i] = lo
            impact[i] = im
            converged[i] = True
            newton[i] = True
            periods_run[i] = cost
        elif status == 1:
            x, v, _mu, lo, im, _pa, rx, rv = record_kernel(
                xs, vs, zeta, force, b, kd, ed, kb, eb, ed[:, 0], eb[:, 0], npair, cs, sn, h, 1,
                ring, 0, amps[i],
            )
            loss[i] = lo
            impact[i] = im
            converged[i] = True
            newton[i] = True
            periods_run[i] = cost + 1
        else:
            x, v, cnt, per, _mu, lo, im, _pa = steady_kernel(
                xs, vs, zeta, force, b, kd, ed, kb, eb, ed[:, 0], eb[:, 0], npair, cs, sn, h,
                tol, min_periods, max_periods, 1, ring, poinc, amps[i],
            )
            loss[i] = lo
            impact[i] = im
            converged[i] = per > 0
            newton[i] = False
            periods_run[i] = cost + cnt + (per if per > 0 else 1)
            rx = -1.0
            rv = -1.0
            if shoot and per == 1:
                x, v, rx, rv = _orbit_range(x, v, zeta, force, b, kd, ed, kb, eb, h)
                periods_run[i] += 1
    return x, v


@njit(parallel=True, cache=True)
def walker_sweep_kernel(
    log_nodes, kbank, ebank, bbank, log_s, eps, zeta, force, b, lam, cs, sn, tol, shoot,
    max_newton, min_periods, max_periods, guard, guard_floor, basin_periods, basin_repeats,
    verify_record, record, skip_step, skip_move, fold_margin, amps, loss, impact, converged,
    newton, periods_run, solved,
):  # pragma: no cover - compiled
    """Every walker's sweep in one call, ``numba.prange`` over walkers.

    Per walker ``w``: tables interpolated from the bank at ``log_s[w]`` with the alternating
    parts scaled by ``eps[w]`` (:func:`_walker_tables`), start at the static state
    ``x = b + F + mean(e)``, ``x' = 0``, then the points of ``lam[w]`` (``(W, M)``, time order)
    each by Newton shooting (``shoot``) with the settling fallback, or by settling alone;
    ``verify_record``, ``record`` (``(M,)`` bool), ``skip_step`` and ``fold_margin`` as in
    :func:`_shoot` and :func:`_walker_path`. Outputs ``(W, M[, 3])``.
    """
    n2 = kbank.shape[1]
    for w in prange(lam.shape[0]):
        kd = np.empty((n2, 1))
        ed = np.empty((n2, 1))
        kb = np.empty((n2, 1))
        eb = np.empty((n2, 1))
        em = _walker_tables(log_nodes, kbank, ebank, bbank, log_s[w], eps[w], kd, ed, kb, eb)
        npair = np.ones(n2, dtype=np.int64)
        ring = np.empty((SETTLE_RING, 2))
        poinc = np.empty((1, 2))
        _walker_path(
            b[w] + force[w] + em, 0.0, zeta[w], force[w], b[w], kd, ed, kb, eb, npair, cs, sn,
            lam[w], tol, shoot, max_newton, min_periods, max_periods, guard, guard_floor,
            basin_periods, basin_repeats, verify_record, record, skip_step, skip_move,
            fold_margin, ring, poinc, amps[w], loss[w], impact[w], converged[w], newton[w],
            periods_run[w], solved[w],
        )


# numba inlines the sdof_kernels functions above into this file's cached kernels; flush them
# from the disk cache whenever that file changes (numba checks only this file).
tie_cache(__name__, ["models.dynamics.sdof_kernels"])
