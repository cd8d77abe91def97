r"""Compiled (numba) RK4 kernels of the single-coordinate models (SDOF and ITMS).

All numba kernels of :mod:`models.dynamics.integrate`, :mod:`models.dynamics.sweep` and
:mod:`models.dynamics.parallel` live in this one file. numba's on-disk cache (``cache=True``)
checks only the source file of the function it loads: a sweep kernel in another file that
inlines :func:`settle_kernel` or the RK4 step would keep running the old copy from its cache
after that file is edited. With every kernel here, any edit of any kernel invalidates all of
them together.

The kernels take the tables of :func:`models.dynamics.integrate.model_tables` (``kd``, ``ed``,
``kb``, ``eb`` at the ``2 N`` half steps of one mesh period, ``h = 2 pi / (Lambda N)``) and
check nothing. The classical RK4 stages are

.. math:: k_1 = g(t, y),\ k_2 = g(t + h/2, y + h k_1/2),\ k_3 = g(t + h/2, y + h k_2/2),
          \ k_4 = g(t + h, y + h k_3),\ y \leftarrow y + h (k_1 + 2 k_2 + 2 k_3 + k_4) / 6

with ``g`` the right-hand side ``x'' = F - 2 zeta x' - sum_j [kd_j max(x - ed_j - b, 0) +
kb_j min(x - eb_j + b, 0)]``: one tooth-pair column ``j`` per pair (ITMS, seed 003 Eq. 28), or
a single column with ``kd = kb = k``, ``ed = e`` and ``eb = e_b`` (FVMS / VVMS / LSTE, Eqs. 26,
30, 31), which for ``e_b = e`` is the dead zone ``k f(x - e)`` of
:func:`~models.dynamics.sdof.dead_zone`.

Steady state (:func:`settle_kernel`, behind :func:`~models.dynamics.integrate.settle_periodic`):
whole periods are run until the Poincare point (the state at phase 0) repeats with some period
``n`` in 1..8, i.e. ``max(|dx|, |dx'|)`` between the points ``n`` periods apart (the *repeat
distance* ``D``) is below ``tol`` three times running; the smallest such ``n`` is the period.
For ``n > 1`` a period-``d`` response still converging (``d`` a proper divisor of ``n``), whose
transient turns by about ``2 pi d / n`` per ``d`` periods or, near a flip bifurcation, changes
sign every period, also passes that test; two guards on the *split* ``s = |P_k - P_(k-d)|``
reject it:

1. **resolution**: ``s >= 100 tol`` (``_MIN_SPLIT``): a period-``n`` orbit split by less is not
   resolved at that tolerance;
2. **extrapolation**: ``s > 2 B`` with ``B = 2 D q / (1 - q)``, ``q = D_k / D_(k-n)`` the
   measured contraction of the repeat distance per ``n`` periods (``B`` infinite if ``q >= 1``,
   0 once ``D`` is at round-off): ``B`` bounds how much the split can still shrink if the
   transient keeps decaying geometrically, so a split that the transient itself will remove
   (a converging period-``d`` response has ``s ~ D / (1 - q)``) is not taken for a period-``n``
   orbit, however slowly it decays.

(A guard that only compared the split with its value ``n`` periods earlier is implied by the
resolution guard: ``D < tol`` at both ends changes ``s`` by less than ``2 tol <= 0.02 s``.)

``period`` is then ``n``; 0 when no ``n <= 8`` repeats within ``tol`` at ``max_periods``
(quasi-periodic, chaotic, or not settled); ``-n`` ("unresolved") when the points repeat
every ``n`` periods within ``tol`` but a guard still rejects the period at ``max_periods``: a
period-``n`` orbit split by less than ``100 tol`` (resolve it with a smaller ``tol``), or a
period-``d`` response converging too slowly to tell (a longer run decides).

Contact flags of the recorded periods (:func:`sweep_kernel`): each RK4 step is checked on the
cubic Hermite interpolant of ``x`` between its end points (values and slopes, third order),
minimised exactly against the offsets interpolated linearly between the half steps, so a
contact loss or impact shorter than a step is not missed.

The compiled sweep kernel :func:`sweep_kernel` (used by :func:`models.dynamics.sweep.sweep`
and, in parallel over sweeps (:func:`sweep_many_kernel`), by
:func:`models.dynamics.parallel.sweep_many`) does settle, record and the DFT of the first three
mesh harmonics for a whole sweep in one call.

Walker sweeps (:func:`walker_sweep_kernel`, behind :mod:`models.dynamics.walkers`): many
parameter sets of one single-column model, ``prange`` over them; each builds its tables from a
bank of curves at stiffness-scale nodes (4-point Lagrange in ``log s``, alternating parts
scaled) and runs its time-ordered path, each point by Newton shooting on the period-1 Poincare
map (:func:`_shoot`: RK4 on the state and the 2 x 2 variational equations, the same step as
:func:`_step`; accepted on residual, Jury stability, a continuation guard against the previous
point's orbit and a basin check in the orbit's Lyapunov metric along the first periods of the
transient) with :func:`_steady` as the fallback, or by :func:`_steady` alone. The first point,
and any point after a response that is not a settled period-1 orbit, is settled.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numba import njit, prange

__all__ = [
    "MAX_PERIOD",
    "SETTLE_RING",
    "periods_kernel",
    "settle_kernel",
    "sweep_kernel",
    "sweep_many_kernel",
    "walker_sweep_kernel",
]

#: Longest period (in mesh periods) that :func:`settle_kernel` recognises.
MAX_PERIOD: Final = 8
_REPEATS: Final = 3
_MIN_SPLIT: Final = 100.0
_EXTRAPOLATION_MARGIN: Final = 2.0
_ROUND_OFF: Final = 1e-13
#: Poincare points held while settling (enough for the guards of period 8: 2 * 8 + 3); the
#: ``ring`` of :func:`settle_kernel` has this many rows.
SETTLE_RING: Final = 32


@njit(cache=True)
def _accel(x, v, j, zeta, force, b, kd, ed, kb, eb):  # pragma: no cover - compiled
    f = 0.0
    for p in range(kd.shape[1]):
        u = x - ed[j, p]
        if u > b:
            f += kd[j, p] * (u - b)
        w = x - eb[j, p]
        if w < -b:
            f += kb[j, p] * (w + b)
    return force - 2.0 * zeta * v - f


@njit(cache=True)
def _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    n2 = kd.shape[0]
    j0 = 2 * j
    j1 = j0 + 1
    j2 = (j0 + 2) % n2
    a1 = _accel(x, v, j0, zeta, force, b, kd, ed, kb, eb)
    x2 = x + 0.5 * h * v
    v2 = v + 0.5 * h * a1
    a2 = _accel(x2, v2, j1, zeta, force, b, kd, ed, kb, eb)
    x3 = x + 0.5 * h * v2
    v3 = v + 0.5 * h * a2
    a3 = _accel(x3, v3, j1, zeta, force, b, kd, ed, kb, eb)
    x4 = x + h * v3
    v4 = v + h * a3
    a4 = _accel(x4, v4, j2, zeta, force, b, kd, ed, kb, eb)
    xn = x + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
    vn = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
    return xn, vn


@njit(cache=True)
def _period(x, v, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    """One mesh period of :func:`_step` from ``(x, v)``; returns the state at its end."""
    for j in range(kd.shape[0] // 2):
        x, v = _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
    return x, v


@njit(cache=True)
def periods_kernel(
    x, v, zeta, force, b, kd, ed, kb, eb, doff, h, n_periods, xs, us
):  # pragma: no cover - compiled
    """Run ``n_periods`` mesh periods; Poincare points ``(n_periods, 2)``.

    With ``xs.size > 0``, fills ``xs`` and ``us`` with ``x`` and ``x - doff`` at every step start.
    """
    n = kd.shape[0] // 2
    rec = xs.size > 0
    pts = np.empty((n_periods, 2))
    i = 0
    for p in range(n_periods):
        for j in range(n):
            if rec:
                xs[i] = x
                us[i] = x - doff[2 * j]
            x, v = _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
            i += 1
        pts[p, 0] = x
        pts[p, 1] = v
    return pts


@njit(cache=True)
def _dist(ring, a, c):  # pragma: no cover - compiled
    m = ring.shape[0]
    a %= m
    c %= m
    return max(abs(ring[a, 0] - ring[c, 0]), abs(ring[a, 1] - ring[c, 1]))


@njit(cache=True)
def _split_resolved(ring, a, n, d, tol):  # pragma: no cover - compiled
    """The two guards on the split ``s = |P_a - P_(a-d)|`` of a period-``n`` candidate."""
    split = _dist(ring, a, a - d)
    if split < _MIN_SPLIT * tol:
        return False
    dn = _dist(ring, a, a - n)
    dp = _dist(ring, a - n, a - 2 * n)
    m = ring.shape[0]
    scale = max(1.0, abs(ring[a % m, 0]), abs(ring[a % m, 1]))
    if dp <= _ROUND_OFF * scale:
        bound = dn  # converged to round-off
    elif dn >= dp:
        return False  # the repeat distance is not contracting: no bound
    else:
        q = dn / dp
        bound = 2.0 * dn * q / (1.0 - q)
    return split > _EXTRAPOLATION_MARGIN * bound


@njit(cache=True)
def _period_of(ring, count, tol, guarded):  # pragma: no cover - compiled
    """Smallest n in 1..MAX_PERIOD with the last 3 points n apart within tol, else 0.

    With ``guarded``, for ``n > 1`` the split to every proper divisor ``d`` must pass
    :func:`_split_resolved` (see the module notes); without, the distance test alone.
    """
    for n in range(1, MAX_PERIOD + 1):
        if count - 2 * n - _REPEATS + 1 < 0:
            return 0
        ok = True
        for i in range(_REPEATS):
            a = count - i
            if not _dist(ring, a, a - n) < tol:
                ok = False
                break
            if not guarded:
                continue
            for d in range(1, n):
                if n % d == 0 and not _split_resolved(ring, a, n, d, tol):
                    ok = False
                    break
            if not ok:
                break
        if ok:
            return n
    return 0


@njit(cache=True)
def settle_kernel(
    x, v, zeta, force, b, kd, ed, kb, eb, h, tol, min_periods, max_periods, ring
):  # pragma: no cover - compiled
    """Run periods until period-n repetition; ``ring`` holds Poincare points by count mod m.

    Returns ``(x, v, periods run, period)``, period ``-n`` when unresolved at the cap.
    """
    m = ring.shape[0]
    for i in range(m):
        ring[i, 0] = np.nan
        ring[i, 1] = np.nan
    ring[0, 0] = x
    ring[0, 1] = v
    count = 0
    period = 0
    while count < max_periods:
        x, v = _period(x, v, zeta, force, b, kd, ed, kb, eb, h)
        count += 1
        ring[count % m, 0] = x
        ring[count % m, 1] = v
        if count >= min_periods:
            period = _period_of(ring, count, tol, True)
            if period > 0:
                break
    if period == 0:
        period = -_period_of(ring, count, tol, False)
    return x, v, count, period


@njit(cache=True)
def _min_below(x0, v0, x1, v1, h, o0, o1, o2):  # pragma: no cover - compiled
    """Minimum over one step of ``H(t) - o(t)``: ``H`` the cubic Hermite interpolant of ``x``.

    ``t`` in [0, 1] over the step; ``o`` linear through ``o0``, ``o1``, ``o2`` at 0, 1/2, 1.
    """
    lo = min(x0 - o0, x1 - o2)
    if not (math.isfinite(o0) and math.isfinite(o1) and math.isfinite(o2)):
        return lo  # no pair on this side (offset +-inf)
    c3 = 2.0 * (x0 - x1) + h * (v0 + v1)
    c2 = 3.0 * (x1 - x0) - h * (2.0 * v0 + v1)
    c1 = h * v0
    for half in range(2):
        t0 = 0.5 * half
        oa = o0 if half == 0 else o1
        ob = o1 if half == 0 else o2
        slope = 2.0 * (ob - oa)  # d o / d t on this half
        # g'(t) = 3 c3 t^2 + 2 c2 t + c1 - slope
        qa = 3.0 * c3
        qb = 2.0 * c2
        qc = c1 - slope
        roots = np.empty(2)
        nr = 0
        if abs(qa) > 1e-300:
            disc = qb * qb - 4.0 * qa * qc
            if disc >= 0.0:
                sq = math.sqrt(disc)
                roots[0] = (-qb - sq) / (2.0 * qa)
                roots[1] = (-qb + sq) / (2.0 * qa)
                nr = 2
        elif abs(qb) > 1e-300:
            roots[0] = -qc / qb
            nr = 1
        for r in range(nr):
            t = roots[r]
            if t0 < t < t0 + 0.5:
                xt = ((c3 * t + c2) * t + c1) * t + x0
                ot = oa + slope * (t - t0)
                lo = min(lo, xt - ot)
        xm = ((c3 * 0.5 + c2) * 0.5 + c1) * 0.5 + x0
        lo = min(lo, xm - o1)
    return lo


@njit(cache=True)
def _steady(
    x,
    v,
    zeta,
    force,
    b,
    kd,
    ed,
    kb,
    eb,
    doff,
    boff,
    npair,
    cs,
    sn,
    h,
    tol,
    min_periods,
    max_periods,
    record_periods,
    ring,
    poinc,
    amps,
):  # pragma: no cover - compiled
    """Settle (:func:`settle_kernel`), then record (:func:`_record`); fills ``poinc``, ``amps``.

    At least ``record_periods`` periods are recorded, a whole number of response periods.
    ``poinc`` ``(K, 2)`` gets the last ``K`` Poincare points, oldest first.

    Returns ``(x, v, periods to settle, period, mean, loss, impact, partial)``, ``partial``
    the fraction of recorded step starts with ``0 < touching pairs < npair``.
    """
    x, v, count, period = settle_kernel(
        x, v, zeta, force, b, kd, ed, kb, eb, h, tol, min_periods, max_periods, ring
    )
    rec = record_periods
    if period > 0 and rec % period != 0:
        rec = (rec // period + 1) * period
    x, v, mean, loss, impact, partial, _, _ = _record(
        x, v, zeta, force, b, kd, ed, kb, eb, doff, boff, npair, cs, sn, h, rec, ring, count, amps
    )
    count += rec
    m = ring.shape[0]
    k = poinc.shape[0]
    for i in range(k):  # oldest first
        c = (count - k + 1 + i) % m
        poinc[i, 0] = ring[c, 0]
        poinc[i, 1] = ring[c, 1]
    return x, v, count - rec, period, mean, loss, impact, partial


@njit(cache=True)
def _record(
    x, v, zeta, force, b, kd, ed, kb, eb, doff, boff, npair, cs, sn, h, periods, ring, count,
    amps,
):  # pragma: no cover - compiled
    """Run and record ``periods`` mesh periods from ``(x, v)``; fills ``amps`` ``(3,)``.

    ``amps``: peak amplitudes of mesh harmonics 1-3 (DFT of ``x`` at the step starts). The
    Poincare point after each period goes to ``ring`` at the running count mod its rows
    (``count`` the periods run before). Contact flags: every step checked on the cubic Hermite
    interpolant (:func:`_min_below`), the drive side against the offsets ``doff`` (loss: no
    pair touches where ``x - doff < b``), the back side against ``boff`` (impact:
    ``x - boff < -b``).

    Returns ``(x, v, mean, loss, impact, partial, x range, v range)`` at the end: ``mean`` of
    ``x`` and ``partial`` the fraction of step starts with ``0 < touching pairs < npair``; the
    ranges (max - min over the step ends) size the walkers' continuation guard.
    """
    n = kd.shape[0] // 2
    n2 = 2 * n
    m = ring.shape[0]
    c1 = 0.0
    c2 = 0.0
    c3 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    total = 0.0
    loss = False
    impact = False
    partial = 0
    xlo = x
    xhi = x
    vlo = v
    vhi = v
    for _ in range(periods):
        for j in range(n):
            touching = 0
            for p in range(kd.shape[1]):
                if kd[2 * j, p] > 0.0 and x - ed[2 * j, p] > b:
                    touching += 1
            if 0 < touching < npair[2 * j]:
                partial += 1
            total += x
            c1 += x * cs[0, j]
            c2 += x * cs[1, j]
            c3 += x * cs[2, j]
            s1 += x * sn[0, j]
            s2 += x * sn[1, j]
            s3 += x * sn[2, j]
            xn, vn = _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
            j0 = 2 * j
            j2 = (j0 + 2) % n2
            if not loss:
                # drive side: no pair touches where x - drive offset < b
                if _min_below(x, v, xn, vn, h, doff[j0], doff[j0 + 1], doff[j2]) < b:
                    loss = True
            if not impact:
                # back side: x - back offset < -b
                if _min_below(x, v, xn, vn, h, boff[j0], boff[j0 + 1], boff[j2]) < -b:
                    impact = True
            x, v = xn, vn
            xlo = min(xlo, x)
            xhi = max(xhi, x)
            vlo = min(vlo, v)
            vhi = max(vhi, v)
        count += 1
        ring[count % m, 0] = x
        ring[count % m, 1] = v
    size = periods * n
    amps[0] = 2.0 * math.sqrt(c1 * c1 + s1 * s1) / size
    amps[1] = 2.0 * math.sqrt(c2 * c2 + s2 * s2) / size
    amps[2] = 2.0 * math.sqrt(c3 * c3 + s3 * s3) / size
    return x, v, total / size, loss, impact, partial / size, xhi - xlo, vhi - vlo


@njit(cache=True)
def sweep_kernel(
    x,
    v,
    zeta,
    force,
    b,
    kd,
    ed,
    kb,
    eb,
    doff,
    boff,
    npair,
    cs,
    sn,
    freqs,
    tol,
    min_periods,
    max_periods,
    record_periods,
    amps,
    mean,
    loss,
    impact,
    partial,
    periods_run,
    period,
    poinc,
    entry,
):  # pragma: no cover - compiled
    """One sweep in the order of ``freqs``, carrying the state; fills the output arrays.

    Outputs (first axis the sweep point): ``amps (M, 3)``, ``mean (M,)``, ``loss``/``impact``
    ``(M,)`` bool, ``partial (M,)`` fraction, ``periods_run``/``period`` ``(M,)`` int,
    ``poinc (M, K, 2)`` (the last ``K`` Poincare points), ``entry (M, 2)`` the state each point
    started from.
    Returns the final state.
    """
    n = kd.shape[0] // 2
    ring = np.empty((SETTLE_RING, 2))
    for i in range(freqs.size):
        entry[i, 0] = x
        entry[i, 1] = v
        h = 2.0 * math.pi / (freqs[i] * n)
        x, v, cnt, per, mu, lo, im, pa = _steady(
            x,
            v,
            zeta,
            force,
            b,
            kd,
            ed,
            kb,
            eb,
            doff,
            boff,
            npair,
            cs,
            sn,
            h,
            tol,
            min_periods,
            max_periods,
            record_periods,
            ring,
            poinc[i],
            amps[i],
        )
        mean[i] = mu
        loss[i] = lo
        impact[i] = im
        partial[i] = pa
        periods_run[i] = cnt
        period[i] = per
    return x, v


@njit(parallel=True, cache=True)
def sweep_many_kernel(
    x0,
    v0,
    zeta,
    force,
    b,
    kd,
    ed,
    kb,
    eb,
    doff,
    boff,
    npair,
    cs,
    sn,
    freqs,
    tol,
    min_periods,
    max_periods,
    record_periods,
    amps,
    mean,
    loss,
    impact,
    partial,
    periods_run,
    period,
    poinc,
    entry,
):  # pragma: no cover - compiled
    """:func:`sweep_kernel` for independent sweeps, in parallel over them (``numba.prange``).

    Every array but ``cs``, ``sn`` has the sweep index first; the scalars are shared.
    """
    for s in prange(freqs.shape[0]):
        sweep_kernel(
            x0[s],
            v0[s],
            zeta[s],
            force[s],
            b[s],
            kd[s],
            ed[s],
            kb[s],
            eb[s],
            doff[s],
            boff[s],
            npair[s],
            cs,
            sn,
            freqs[s],
            tol,
            min_periods,
            max_periods,
            record_periods,
            amps[s],
            mean[s],
            loss[s],
            impact[s],
            partial[s],
            periods_run[s],
            period[s],
            poinc[s],
            entry[s],
        )


# --- walker-vectorised sweeps (models.dynamics.walkers, which sets the method's parameters) -----
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

    ``y = (x, x', p11, p12, p21, p22)``: ``x'' = F - 2 zeta x' - f(x)`` as in :func:`_accel`
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

    The state update is :func:`_step`'s (same stages, same tables); returns
    ``(x, v, m11, m12, m21, m22)`` with ``M`` the monodromy matrix of the discrete map.
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
        x, v = _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
        xlo = min(xlo, x)
        xhi = max(xhi, x)
        vlo = min(vlo, v)
        vhi = max(vhi, v)
    return x, v, xhi - xlo, vhi - vlo


@njit(cache=True)
def _lyapunov_value(p11, p12, p22, dx, dv):  # pragma: no cover - compiled
    return p11 * dx * dx + 2.0 * p12 * dx * dv + p22 * dv * dv


@njit(cache=True)
def _shoot(
    x, v, zeta, force, b, kd, ed, kb, eb, h, tol, max_newton, guard_x, guard_v, basin_periods,
    basin_repeats,
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

    Returns ``(ok, x, v, periods)``: ``(x, v)`` is ``y*`` when accepted, else the state the
    settling fallback continues from (the entry state, or the transient's state after the
    periods followed); periods counted as plain-period equivalents (a variational period as 2).
    """
    xs = x
    vs = v
    cost = 0
    x1 = math.nan
    v1 = math.nan
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
            det = m11 * m22 - m12 * m21
            tr = m11 + m22
            if not (abs(det) < 1.0 and abs(tr) < 1.0 + det):
                return False, x, v, cost
            d0x = x - xs
            d0v = v - vs
            if not (abs(d0x) <= guard_x and abs(d0v) <= guard_v):
                return False, x, v, cost
            if max(abs(d0x), abs(d0v)) <= 10.0 * tol * scale:
                return True, xs, vs, cost
            p11, p12, p22 = _lyapunov_form(m11, m12, m21, m22)
            if not math.isfinite(p11):
                return False, x, v, cost
            q0 = _lyapunov_value(p11, p12, p22, d0x, d0v)
            q1 = _lyapunov_value(p11, p12, p22, x1 - xs, v1 - vs)
            near = (abs(d0x) <= _BASIN_NEAR * guard_x and abs(d0v) <= _BASIN_NEAR * guard_v)
            if (q1 <= q0 - _BASIN_DECREASE * (d0x * d0x + d0v * d0v)
                    and (near or q1 <= _BASIN_CONTRACTION * q0)):
                return True, xs, vs, cost
            # follow the physical transient from P(y0), one plain period at a time
            xa = x1
            va = v1
            good = 0
            for _ in range(basin_periods):
                dx = xa - xs
                dv = va - vs
                qa = _lyapunov_value(p11, p12, p22, dx, dv)
                xa, va = _period(xa, va, zeta, force, b, kd, ed, kb, eb, h)
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
        a11 = m11 - 1.0
        a22 = m22 - 1.0
        d = a11 * a22 - m12 * m21
        if d == 0.0 or not math.isfinite(d):
            break
        xs += (-r0 * a22 + m12 * r1) / d
        vs += (-a11 * r1 + m21 * r0) / d
        if not (math.isfinite(xs) and math.isfinite(vs)):
            break
    return False, x, v, cost


@njit(cache=True)
def _walker_path(
    x, v, zeta, force, b, kd, ed, kb, eb, npair, cs, sn, lam, tol, shoot, max_newton,
    min_periods, max_periods, guard, guard_floor, basin_periods, basin_repeats, ring, poinc,
    amps, loss, impact, converged, newton, periods_run,
):  # pragma: no cover - compiled
    """One walker's sweep along ``lam`` (time order), carrying the state; fills its rows.

    With ``shoot``, Newton is tried only where the entry state lies on a period-1 orbit of the
    previous point (Newton-accepted, or settled with period 1), whose ranges size the
    continuation guard (``guard`` times the range plus ``guard_floor``); the first point and
    the point after a period-n, aperiodic or unsettled response are settled.
    """
    n = kd.shape[0] // 2
    rx = -1.0  # orbit ranges of the previous point; < 0: no period-1 predictor
    rv = -1.0
    for i in range(lam.size):
        h = 2.0 * math.pi / (lam[i] * n)
        ok = False
        cost = 0
        xs = x
        vs = v
        if shoot and rx >= 0.0:
            ok, xs, vs, cost = _shoot(
                x, v, zeta, force, b, kd, ed, kb, eb, h, tol, max_newton,
                guard * rx + guard_floor, guard * rv + guard_floor, basin_periods,
                basin_repeats,
            )
        if ok:
            x, v, _mu, lo, im, _pa, rx, rv = _record(
                xs, vs, zeta, force, b, kd, ed, kb, eb, ed[:, 0], eb[:, 0], npair, cs, sn, h, 1,
                ring, 0, amps[i],
            )
            loss[i] = lo
            impact[i] = im
            converged[i] = True
            newton[i] = True
            periods_run[i] = cost + 1
        else:
            x, v, cnt, per, _mu, lo, im, _pa = _steady(
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
    max_newton, min_periods, max_periods, guard, guard_floor, basin_periods, basin_repeats, amps,
    loss, impact, converged, newton, periods_run,
):  # pragma: no cover - compiled
    """Every walker's sweep in one call, ``numba.prange`` over walkers.

    Per walker ``w``: tables interpolated from the bank at ``log_s[w]`` with the alternating
    parts scaled by ``eps[w]`` (:func:`_walker_tables`), start at the static state
    ``x = b + F + mean(e)``, ``x' = 0``, then the points of ``lam[w]`` (``(W, M)``, time order)
    each by Newton shooting (``shoot``) with the settling fallback, or by settling alone.
    Outputs ``(W, M[, 3])``.
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
            basin_periods, basin_repeats, ring, poinc, amps[w], loss[w], impact[w], converged[w],
            newton[w], periods_run[w],
        )
