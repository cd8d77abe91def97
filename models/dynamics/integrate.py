r"""Fixed-step RK4 for the SDOF and ITMS models, compiled (numba) and a pure-Python reference.

The step is a whole fraction of the mesh period, ``h = 2 pi / (Lambda N)``, and every period
starts at cycle phase 0, so the periodic stiffness and error tables are needed only at the
``2 N`` half steps of one period (:meth:`~models.dynamics.sdof.SDOFModel.pair_tables`); a step
costs a few multiplications, no cosine. The classical RK4 stages are

.. math:: k_1 = g(t, y),\ k_2 = g(t + h/2, y + h k_1/2),\ k_3 = g(t + h/2, y + h k_2/2),
          \ k_4 = g(t + h, y + h k_3),\ y \leftarrow y + h (k_1 + 2 k_2 + 2 k_3 + k_4) / 6

with ``g`` the right-hand side ``x'' = F - 2 zeta x' - sum_j [kd_j max(x - ed_j - b, 0) +
kb_j min(x - eb_j + b, 0)]``: one tooth-pair column ``j`` per pair (ITMS, seed 003 Eq. 28), or
a single column with ``kd = kb = k``, ``ed = e`` and ``eb = e_b`` (FVMS / VVMS / LSTE, Eqs. 26,
30, 31), which for ``e_b = e`` is the dead zone ``k f(x - e)`` of
:func:`~models.dynamics.sdof.dead_zone`.

The dead zone has a kink, so near contact loss the scheme is locally first order in the kink
crossings; ``N = 128`` per mesh period keeps the Arms within 1 % of an adaptive RK45 at rtol
1e-9 (benchmark ``tests/benchmarks/bench_sdof_sweep.py``). :func:`periods_reference` runs the
same operations in the same order in plain Python; :func:`periods_solve_ivp` is the adaptive
check.

Steady state (:func:`settle_periodic`): whole periods are run until the Poincare point (the
state at phase 0) repeats with some period ``n`` in 1..8, i.e. ``max(|dx|, |dx'|)`` between
the points ``n`` periods apart (the *repeat distance* ``D``) is below ``tol`` three times
running; the smallest such ``n`` is the period. For ``n > 1`` a period-``d`` response still
converging (``d`` a proper divisor of ``n``), whose transient turns by about ``2 pi d / n`` per
``d`` periods or, near a flip bifurcation, changes sign every period, also passes that test;
two guards on the *split* ``s = |P_k - P_(k-d)|`` reject it:

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

Error of a settled state: the test is period-to-period, so with a slowest Floquet multiplier
``mu`` (per period of the response) the distance of the last point from the true periodic orbit
is about ``tol / (1 - |mu|)``, not ``tol``: lightly damped responses (``|mu|`` close to 1, e.g.
``1 - |mu| ~ 2 pi zeta / Lambda`` in the linear range) need a ``tol`` smaller by that factor.

Contact flags of the recorded periods (:func:`sweep_kernel`): each RK4 step is checked on the
cubic Hermite interpolant of ``x`` between its end points (values and slopes, third order),
minimised exactly against the offsets interpolated linearly between the half steps, so a
contact loss or impact shorter than a step is not missed.

The compiled sweep kernel :func:`sweep_kernel` (used by :func:`models.dynamics.sweep.sweep`
and, in parallel over sweeps, by :func:`models.dynamics.parallel.sweep_many`) does settle,
record and the DFT of the first three mesh harmonics for a whole sweep in one call.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numba import njit, prange

from models.dynamics.checks import check_settle_args
from models.dynamics.sdof import DynamicModel

__all__ = [
    "MAX_PERIOD",
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
    "sweep_kernel",
    "sweep_many_kernel",
]

#: Longest period (in mesh periods) that :func:`settle_periodic` recognises.
MAX_PERIOD: Final = 8
#: Poincare points kept per steady state (the last ones, in time order).
POINCARE_POINTS: Final = 16
_REPEATS: Final = 3
_MIN_SPLIT: Final = 100.0
_EXTRAPOLATION_MARGIN: Final = 2.0
_ROUND_OFF: Final = 1e-13
#: Poincare points held while settling (enough for the guards of period 8: 2 * 8 + 3).
_RING: Final = 32


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


# --- compiled kernels ---------------------------------------------------------------------------
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
def _periods(x, v, zeta, force, b, kd, ed, kb, eb, doff, h, n_periods, xs, us):  # pragma: no cover
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
def _settle(
    x, v, zeta, force, b, kd, ed, kb, eb, h, tol, min_periods, max_periods, ring
):  # pragma: no cover - compiled
    """Run periods until period-n repetition; ``ring`` holds Poincare points by count mod m.

    Returns ``(x, v, periods run, period)``, period ``-n`` when unresolved at the cap.
    """
    n = kd.shape[0] // 2
    m = ring.shape[0]
    for i in range(m):
        ring[i, 0] = np.nan
        ring[i, 1] = np.nan
    ring[0, 0] = x
    ring[0, 1] = v
    count = 0
    period = 0
    while count < max_periods:
        for j in range(n):
            x, v = _step(x, v, j, zeta, force, b, kd, ed, kb, eb, h)
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
    """Settle, then record; fills ``poinc`` (POINCARE_POINTS, 2) and ``amps`` (3,).

    Returns ``(x, v, periods to settle, period, mean, loss, impact, partial)``, ``partial``
    the fraction of recorded step starts with ``0 < touching pairs < npair``.
    """
    n = kd.shape[0] // 2
    n2 = 2 * n
    m = ring.shape[0]
    x, v, count, period = _settle(
        x, v, zeta, force, b, kd, ed, kb, eb, h, tol, min_periods, max_periods, ring
    )
    rec = record_periods
    if period > 0 and rec % period != 0:
        rec = (rec // period + 1) * period
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
    for _ in range(rec):
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
        count += 1
        ring[count % m, 0] = x
        ring[count % m, 1] = v
    size = rec * n
    amps[0] = 2.0 * math.sqrt(c1 * c1 + s1 * s1) / size
    amps[1] = 2.0 * math.sqrt(c2 * c2 + s2 * s2) / size
    amps[2] = 2.0 * math.sqrt(c3 * c3 + s3 * s3) / size
    k = poinc.shape[0]
    for i in range(k):  # oldest first
        c = (count - k + 1 + i) % m
        poinc[i, 0] = ring[c, 0]
        poinc[i, 1] = ring[c, 1]
    return x, v, count - rec, period, total / size, loss, impact, partial / size


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
    ``poinc (M, POINCARE_POINTS, 2)``, ``entry (M, 2)`` the state each point started from.
    Returns the final state.
    """
    n = kd.shape[0] // 2
    ring = np.empty((_RING, 2))
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
    pts = _periods(
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
        the module notes).
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
    the module notes is the period (``-n`` if only unguarded repetition is found at
    ``max_periods``, 0 if none). At least ``min_periods``, at most ``max_periods`` periods.
    The settled state is within about ``tol / (1 - |mu|)`` of the periodic orbit (``mu`` the
    slowest Floquet multiplier), not ``tol``.
    """
    check_settle_args(tol, min_periods, max_periods)
    t = model_tables(model, steps_per_period)
    h = _step_size(frequency, t.steps_per_period)
    ring = np.empty((_RING, 2))
    x, v, n, per = _settle(
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
    idx = (np.arange(int(n) - k + 1, int(n) + 1)) % _RING
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
