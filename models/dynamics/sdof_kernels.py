r"""Compiled (numba) RK4 kernels of the single-coordinate models (SDOF and ITMS).

All numba kernels of :mod:`models.dynamics.integrate`, :mod:`models.dynamics.sweep` and
:mod:`models.dynamics.parallel` live in this file. numba's on-disk cache (``cache=True``)
checks only the source file of the function it loads: a kernel in another file that inlines
:func:`settle_kernel` or the RK4 step would keep running the old copy from its cache after this
file is edited. Within this file any edit invalidates every kernel together. The walker
kernels of :mod:`models.dynamics.walker_kernels` build on :func:`rk4_step`,
:func:`rk4_period`, :func:`record_kernel`, :func:`steady_kernel` and :data:`SETTLE_RING`; that
module ties its cache to this file (:func:`models.dynamics.kernel_cache.tie_cache`), so its
kernels are flushed from the cache whenever this file changes. A new module whose cached
kernels call these must do the same (``tests/models/test_two_stage.py`` checks it).

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

The walker-vectorised sweeps of :mod:`models.dynamics.walkers` (Newton shooting with the
settling of :func:`steady_kernel` as the fallback) are in :mod:`models.dynamics.walker_kernels`.
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
    "record_kernel",
    "rk4_period",
    "rk4_step",
    "settle_kernel",
    "steady_kernel",
    "sweep_kernel",
    "sweep_many_kernel",
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
def rk4_step(x, v, j, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    """One RK4 step ``j`` (of ``N`` per period, size ``h``) from ``(x, v)``; returns the new state.

    The stages read the tables at half steps ``2 j``, ``2 j + 1`` and ``2 j + 2`` (mod ``2 N``).
    """
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
def rk4_period(x, v, zeta, force, b, kd, ed, kb, eb, h):  # pragma: no cover - compiled
    """One mesh period of :func:`rk4_step` from ``(x, v)``; returns the state at its end."""
    for j in range(kd.shape[0] // 2):
        x, v = rk4_step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
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
            x, v = rk4_step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
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
        x, v = rk4_period(x, v, zeta, force, b, kd, ed, kb, eb, h)
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
def _min_below(x0, v0, x1, v1, h, o0, o1, o2, above):  # pragma: no cover - compiled
    """Minimum over one step of ``H(t) - o(t)``: ``H`` the cubic Hermite interpolant of ``x``.

    ``t`` in [0, 1] over the step; ``o`` linear through ``o0``, ``o1``, ``o2`` at 0, 1/2, 1.
    The caller only asks whether the minimum is below ``above``: a lower bound that clears it
    is returned instead of the minimum when one does (the flags are the same).
    """
    lo = min(x0 - o0, x1 - o2)
    if not (math.isfinite(o0) and math.isfinite(o1) and math.isfinite(o2)):
        return lo  # no pair on this side (offset +-inf)
    # H = h00 x0 + h01 x1 + h (h10 v0 + h11 v1), h00 + h01 = 1 (both in [0, 1]), h10 in
    # [0, 4/27], h11 in [-4/27, 0]: H - o >= min(x0, x1) - max(o) - (4/27) h (|v0| + |v1|).
    # When that clears ``above`` (by a margin far beyond round-off) the minimum cannot fall
    # below it, and the exact search (most of a recorded period's cost) is skipped.
    bound = min(x0, x1) - max(o0, o1, o2) - (4.0 / 27.0) * h * (abs(v0) + abs(v1))
    if bound - above > 1e-9 * (1.0 + abs(above) + abs(x0) + abs(x1)):
        return bound
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
        # the stationary points (no array: this runs for every step of every recorded period)
        r0 = math.nan
        r1 = math.nan
        if abs(qa) > 1e-300:
            disc = qb * qb - 4.0 * qa * qc
            if disc >= 0.0:
                sq = math.sqrt(disc)
                r0 = (-qb - sq) / (2.0 * qa)
                r1 = (-qb + sq) / (2.0 * qa)
        elif abs(qb) > 1e-300:
            r0 = -qc / qb
        for r in range(2):
            t = r0 if r == 0 else r1
            if t0 < t < t0 + 0.5:
                xt = ((c3 * t + c2) * t + c1) * t + x0
                ot = oa + slope * (t - t0)
                lo = min(lo, xt - ot)
        xm = ((c3 * 0.5 + c2) * 0.5 + c1) * 0.5 + x0
        lo = min(lo, xm - o1)
    return lo


@njit(cache=True)
def steady_kernel(
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
    """Settle (:func:`settle_kernel`), then record (:func:`record_kernel`) into ``amps``.

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
    x, v, mean, loss, impact, partial, _, _ = record_kernel(
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
def record_kernel(
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
            xn, vn = rk4_step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
            j0 = 2 * j
            j2 = (j0 + 2) % n2
            if not loss:
                # drive side: no pair touches where x - drive offset < b
                if _min_below(x, v, xn, vn, h, doff[j0], doff[j0 + 1], doff[j2], b) < b:
                    loss = True
            if not impact:
                # back side: x - back offset < -b
                if _min_below(x, v, xn, vn, h, boff[j0], boff[j0 + 1], boff[j2], -b) < -b:
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
        x, v, cnt, per, mu, lo, im, pa = steady_kernel(
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
