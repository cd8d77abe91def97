"""Sample indices of MCAP payloads from their stamps: Imu grids and AccelBatch counter restarts.

Two cases where the logger stamps, not a sample counter, decide where samples go:

* a ROS 2 ``sensor_msgs/msg/Imu`` carries a header stamp and no counter: :func:`stamp_grid`
  estimates the rate and lays the messages on a grid of slots, tolerant of stamp jitter;
* a ``rigtools.AccelBatch`` counter that goes back while the stamps go on has restarted (the
  sensor rebooted): :func:`resync_counter_restarts` moves the restarted run to where its
  stamps say it belongs, so none of its samples collide with the run before.

Both are pure functions on arrays; the MCAP handlers (:mod:`rigtools.ingest.mcap.handlers`)
report what they find.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal

import numpy as np

__all__ = [
    "DUPLICATE_FRACTION",
    "NICE_RATE_RTOL",
    "PLAIN_RATE_RTOL",
    "RESTART_LOOKAHEAD",
    "CounterRestart",
    "StampGrid",
    "estimate_rate",
    "nominal_rate",
    "resync_counter_restarts",
    "stamp_grid",
]

#: A rate estimate is replaced by the nearest value with 3 significant digits (200, 400,
#: 1000, 25600 Hz) only when that moves it by at most this fraction (0.1 %).
NICE_RATE_RTOL: Final = 1e-3
#: Otherwise it is written with as few digits as keep it within this fraction (1 ppm).
PLAIN_RATE_RTOL: Final = 1e-6
#: Two messages whose stamps fall into one slot are duplicates only when the stamps lie
#: within this fraction of the period of each other; otherwise one moves to a free
#: neighbouring slot (stamp jitter).
DUPLICATE_FRACTION: Final = 0.1
#: In message order, a stamp this many periods off the fitted line means a message is missing.
_ORDER_MAX_OFF: Final = 0.75
#: A grid fit starts on this many stamps and grows by half each round.
_FIRST_WINDOW: Final = 32
#: Slices (samples) in which long stamp series are worked on, to keep temporaries small.
_SLICE: Final = 1 << 16
#: A counter step back is a restart only when one of the next this many rows continues the
#: restarted counter (a single corrupt counter is no restart).
RESTART_LOOKAHEAD: Final = 8
#: The logger clock may stray from the counter by this fraction of the elapsed time (plus a
#: batch) before a row stops counting as consistent with both.
_CLOCK_RTOL: Final = 1e-3
#: A restarted run is never moved beyond this index (the builder's int64 grid keeps room).
_MAX_INDEX: Final = 1 << 62


def nominal_rate(fs: float) -> float:
    """A rate estimate (Hz) as it is handed on: a round value only when the estimate is close.

    ``fs`` snapped to 3 significant digits when that moves it by at most
    :data:`NICE_RATE_RTOL` (0.1 %); otherwise the shortest decimal (4 to 9 significant
    digits) within :data:`PLAIN_RATE_RTOL` (1 ppm, far below any sensor clock's tolerance),
    so that 199.6999998 Hz reads 199.7 Hz and 199.7 Hz never becomes 200 Hz.

    Examples
    --------
    >>> nominal_rate(400.02), nominal_rate(199.69999986), nominal_rate(199.8)
    (400.0, 199.7, 199.8)
    """
    if not (math.isfinite(fs) and fs > 0.0):
        return float(fs)
    mag = math.floor(math.log10(fs))
    nice = round(fs, 2 - mag)
    if abs(nice - fs) <= NICE_RATE_RTOL * fs:
        return float(nice)
    for digits in range(4, 10):
        plain = round(fs, digits - 1 - mag)
        if abs(plain - fs) <= PLAIN_RATE_RTOL * fs:
            return float(plain)
    return float(fs)


def estimate_rate(sorted_stamps_ns: np.ndarray) -> float | None:
    """Sample rate (Hz) from stamps: 1 / the median positive interval, see :func:`nominal_rate`.

    Parameters
    ----------
    sorted_stamps_ns : numpy.ndarray
        Stamps in ascending order (ns).

    Returns
    -------
    float or None
        None when no two stamps differ.

    Examples
    --------
    >>> estimate_rate(np.array([0, 2_500_000, 5_000_000, 7_600_000]))
    400.0
    """
    d = np.diff(np.asarray(sorted_stamps_ns, np.int64))
    d = d[d > 0]
    if d.size == 0:
        return None
    return nominal_rate(1e9 / float(np.median(d)))


@dataclass(frozen=True)
class StampGrid:
    """Result of :func:`stamp_grid`.

    Attributes
    ----------
    index : numpy.ndarray
        int64 sample index of each message (in the order given), the smallest 0. Two
        messages share an index only when they are duplicates.
    sample_rate_Hz : float
        Nominal rate (Hz): the fitted rate, snapped by :func:`nominal_rate`.
    fitted_rate_Hz : float
        1 / the fitted period (Hz), which placed the messages.
    method : {"order", "grid"}
        ``"order"``: the messages follow each other sample by sample (no gap), the index is
        the message order; ``"grid"``: the stamps were rounded to a fitted grid.
    n_moved : int
        Messages moved to a free neighbouring slot because jitter put them into the slot of
        another message whose stamp is more than :data:`DUPLICATE_FRACTION` of a period away.
    """

    index: np.ndarray
    sample_rate_Hz: float
    fitted_rate_Hz: float
    method: Literal["order", "grid"]
    n_moved: int = 0


def _line(k: np.ndarray, t: np.ndarray, prior: float, prior_se: float) -> tuple[float, float]:
    """``t = a + p k``: least squares, refitted once without stamps half a period off.

    The slope is combined with a ``prior`` slope of standard error ``prior_se`` by inverse
    variance, so a small window cannot spoil a slope already known better.
    """
    p = prior
    km, tm = float(k.mean()), float(t.mean())
    for _ in range(2):
        km, tm = float(k.mean()), float(t.mean())
        dk = k - km
        var = float(dk @ dk)
        if var == 0.0 or k.shape[0] < 3:
            return tm - p * km, p
        slope = float(dk @ (t - tm)) / var
        resid = t - tm - slope * dk
        se = math.sqrt(float(resid @ resid) / (k.shape[0] - 2) / var)
        if se == 0.0 or prior_se == 0.0:
            p = slope if se <= prior_se else prior
        else:
            w_ls, w_prior = 1.0 / se**2, 1.0 / prior_se**2
            p = (slope * w_ls + prior * w_prior) / (w_ls + w_prior)
        keep = np.abs(t - tm - p * dk) < 0.5 * p
        if keep.all() or np.count_nonzero(keep) < 3:
            break
        k, t = k[keep], t[keep]
    return tm - p * km, p


def _pooled_period(ts: np.ndarray, d: np.ndarray, p0: float) -> tuple[float, float]:
    """The period pooled within runs of one-period intervals, and its standard error.

    Runs hiding a lost message (a residual half a period off their line) are left out.
    """
    n = ts.shape[0]
    brk = (d < 0.5 * p0) | (d > 1.5 * p0)
    seg = np.zeros(n, np.int64)
    np.cumsum(brk, out=seg[1:])
    j = np.arange(n) - np.flatnonzero(np.r_[True, brk])[seg]
    use = np.ones(n, bool)
    p, se = p0, math.inf
    for _ in range(2):
        cnt = np.bincount(seg, use)
        safe = np.maximum(cnt, 1)
        dj = np.where(use, j - (np.bincount(seg, j * use) / safe)[seg], 0.0)
        dt = np.where(use, ts - (np.bincount(seg, ts * use) / safe)[seg], 0.0)
        den = float(dj @ dj)
        if den == 0.0:
            return p0, math.inf
        pooled = float(dj @ dt) / den
        if not 0.5 * p0 < pooled < 1.5 * p0:
            return p0, math.inf
        resid = dt - pooled * dj
        dof = int(np.count_nonzero(use)) - int(np.count_nonzero(cnt)) - 1
        p, se = pooled, math.sqrt(float(resid @ resid) / max(dof, 1) / den)
        bad = np.zeros(int(seg[-1]) + 1, bool)
        bad[seg[np.abs(resid) > 0.45 * pooled]] = True
        if not bad.any():
            break
        use &= ~bad[seg]
        if not use.any():
            break
    return p, se


def stamp_grid(stamps_ns: np.ndarray) -> StampGrid | None:
    r"""Lay stamped samples (one per message) on a uniform grid, tolerant of stamp jitter.

    Parameters
    ----------
    stamps_ns : numpy.ndarray
        Stamp of each message (ns), in message order.

    Returns
    -------
    StampGrid or None
        None when fewer than two stamps differ.

    Notes
    -----
    1. *No gap.* The period :math:`P` is a robust slope of the stamps against the message
       order :math:`i`, the median of :math:`(t_{i+h} - t_i)/h` with :math:`h = n/2`; the
       intercept :math:`a` is the median of :math:`t_i - iP`. When every stamp lies within
       half a period of :math:`a + iP` the messages follow each other sample by sample, and
       the index is :math:`i = \mathrm{round}((t - a)/P)`: no jitter below half a period
       can invent a gap or a duplicate.
    2. *Otherwise* (lost, repeated or reordered messages) the stamps are sorted. The period
       starts from the slope pooled within the runs of intervals between 0.5 and 1.5 median
       intervals, and a line :math:`t = a + kP` is fitted by least squares to
       :math:`k = \mathrm{round}((t - a)/P)` over a window of stamps growing by half each
       round (stamps half a period off the line left out), so the rounding never has to
       extrapolate far. The index is :math:`\mathrm{round}((t - a)/P)`. Two stamps in one
       slot are a duplicate only when they lie within :data:`DUPLICATE_FRACTION` of a period
       of each other; otherwise the one leaning out of the slot moves to the free neighbour.
       Stamps jittering by less than about 0.3 period are placed right.

    The rate handed on is the fitted one snapped by :func:`nominal_rate` (3 significant
    digits, only within 0.1 %); the indices always come from the fitted period, so a clock
    that runs a little fast or slow invents no gap.
    """
    s = np.asarray(stamps_ns, np.int64)
    n = s.shape[0]
    if n < 2:
        return None
    smin = s.min()
    if not s.max() > smin:  # fewer than two distinct stamps
        return None

    def rel(lo: int, hi: int) -> np.ndarray:
        """``t = s - min(s)`` as float64 (ns), for samples ``lo .. hi``."""
        return (s[lo:hi] - smin).astype(np.float64)

    # The no-gap test works a slice at a time on t and i p: a per-sample stream of millions
    # of messages costs one temporary the size of the stamps (same arithmetic as whole arrays).
    h = n // 2
    slope = np.empty(n - h, np.float64)
    for lo in range(0, n - h, _SLICE):
        hi = min(n - h, lo + _SLICE)
        np.subtract(rel(h + lo, h + hi), rel(lo, hi), out=slope[lo:hi])
    slope /= h
    p = float(np.median(slope, overwrite_input=True))
    del slope
    if p > 0.0:
        r = np.empty(n, np.float64)
        for lo in range(0, n, _SLICE):  # r = t - i p
            hi = min(n, lo + _SLICE)
            ip = np.arange(lo, hi, dtype=np.float64)
            ip *= p
            np.subtract(rel(lo, hi), ip, out=r[lo:hi])
        a = float(np.median(r, overwrite_input=True))
        for lo in range(0, n, _SLICE):  # r = |t - a - i p|
            hi = min(n, lo + _SLICE)
            ip = np.arange(lo, hi, dtype=np.float64)
            ip *= p
            seg = r[lo:hi]
            np.subtract(rel(lo, hi), a, out=seg)
            seg -= ip
            np.abs(seg, out=seg)
            del seg
        off = r >= 0.5 * p
        # no gap: no stamp a period off the order's line, and the few half a period off
        # stand alone (a lost or repeated message would shift all the stamps after it)
        in_order = float(r.max()) < _ORDER_MAX_OFF * p and (
            not off.any() or (np.count_nonzero(off) <= n // 100
                              and not (off[1:] & off[:-1]).any()))
        del r, off
        if in_order:
            fs = 1e9 / p
            return StampGrid(np.arange(n, dtype=np.int64), nominal_rate(fs), fs, "order")
    t = np.empty(n, np.float64)
    for lo in range(0, n, _SLICE):
        t[lo : lo + _SLICE] = rel(lo, lo + _SLICE)
    order = np.argsort(t, kind="stable")
    ts = t[order]
    d = np.diff(ts)
    p0 = float(np.median(d[d > 0]))
    p, p_se = _pooled_period(ts, d, p0)
    hi = min(n, _FIRST_WINDOW)
    # the grid's phase from the first window: a circular mean, whatever each stamp's jitter
    phase = np.exp(2j * np.pi * (ts[:hi] - ts[0]) / p).mean()
    a = float(ts[0]) + p * float(np.angle(phase)) / (2 * np.pi)
    while True:
        k = np.round((ts[:hi] - a) / p)
        a, p = _line(k, ts[:hi], p, p_se)
        if hi == n:
            break
        hi = min(n, hi + hi // 2 + 1)
    kk = np.round((ts - a) / p).astype(np.int64)
    moved = 0
    for q in (np.flatnonzero(kk[1:] == kk[:-1]) + 1).tolist():
        if kk[q] != kk[q - 1] or ts[q] - ts[q - 1] <= DUPLICATE_FRACTION * p:
            continue  # already resolved, or a duplicate
        after_free = q == n - 1 or kk[q + 1] > kk[q] + 1
        before_free = q == 1 or kk[q - 2] < kk[q - 1] - 1
        lean_after = ts[q] - (a + p * kk[q])
        lean_before = (a + p * kk[q - 1]) - ts[q - 1]
        if after_free and (lean_after >= lean_before or not before_free):
            kk[q] += 1
        elif before_free:
            kk[q - 1] -= 1
        else:
            continue
        moved += 1
    index = np.empty(n, np.int64)
    index[order] = kk - kk.min()
    fs = 1e9 / p
    return StampGrid(index, nominal_rate(fs), fs, "grid", moved)


@dataclass(frozen=True)
class CounterRestart:
    """A counter restart found by :func:`resync_counter_restarts`.

    Attributes
    ----------
    row : int
        Position of the first row of the restarted run.
    counter : int
        Its counter as received.
    index : int
        The sample index it was moved to.
    previous_index : int
        Sample index of the last row before it that agreed with counter and clock.
    stamp_ns : int
        Its stamp (ns).
    """

    row: int
    counter: int
    index: int
    previous_index: int
    stamp_ns: int


def _continued(f: list[int], s: list[int], w: list[int], i: int) -> bool:
    """One of the next :data:`RESTART_LOOKAHEAD` rows continues row ``i``'s counter."""
    want = f[i] + w[i]
    return any(f[j] == want and s[j] > s[i]
               for j in range(i + 1, min(len(f), i + 1 + RESTART_LOOKAHEAD)))


def resync_counter_restarts(
    firsts: np.ndarray, stamps_ns: np.ndarray, widths: np.ndarray, sample_rate_Hz: float
) -> tuple[np.ndarray, list[CounterRestart]]:
    r"""Move runs of rows after a counter restart to where their stamps place them.

    Parameters
    ----------
    firsts : numpy.ndarray
        Counter of the first sample of each row (int64), in arrival order.
    stamps_ns : numpy.ndarray
        Stamp of the first sample of each row (ns, uint64).
    widths : numpy.ndarray
        Samples in each row.
    sample_rate_Hz : float
        Rate of the counter (Hz).

    Returns
    -------
    firsts : numpy.ndarray
        The rows' sample indices: the input itself when no restart was found.
    restarts : list of CounterRestart

    Notes
    -----
    Rows are walked in arrival order against a reference: the last row that either
    continues the reference's counter exactly, or whose counter step agrees with its stamp
    step (within a batch plus 0.1 % of the elapsed time). A row whose counter is behind the
    reference's while its stamp is ahead, and whose counter one of the next
    :data:`RESTART_LOOKAHEAD` rows continues, starts a restarted run. The run is moved to
    index :math:`\max(i_{ref} + \mathrm{round}((t - t_{ref}) f_s), e)` with :math:`e` the end
    of what was received before (so nothing collides); every later row stamped after the
    restart moves by the same offset, rows stamped before it (late rows) keep the offset of
    their time. Anything else (a late row, a single corrupt counter) is left as received, for
    the builder to place or count; a corrupt counter far ahead never becomes the reference.
    """
    f = np.asarray(firsts, np.int64)
    st = np.asarray(stamps_ns, np.uint64)
    n = f.shape[0]
    if n < 2 or not np.any((f[1:] < f[:-1]) & (st[1:] > st[:-1])):
        return f, []
    fl, sl = f.tolist(), st.tolist()
    wl = np.asarray(widths, np.int64).tolist()
    per_ns = float(sample_rate_Hz) * 1e-9
    out = list(fl)
    epochs: list[tuple[int, int]] = [(0, 0)]  # (stamp from which an offset holds, offset)
    restarts: list[CounterRestart] = []
    ref = 0
    run_end = fl[0] + wl[0]
    for i in range(1, n):
        si = sl[i]
        off = next(o for since, o in reversed(epochs) if since <= si)
        a = fl[i] + off
        ra = out[ref]
        dt = si - sl[ref]
        new = max(ra + round(dt * per_ns), run_end) if a < ra and dt > 0 else -1
        if 0 <= new < _MAX_INDEX and _continued(fl, sl, wl, i):
            epochs.append((si, new - fl[i]))
            restarts.append(CounterRestart(i, fl[i], new, ra, si))
            a = new
        elif not (a == ra + wl[ref]
                  or abs((a - ra) - dt * per_ns) <= max(wl[ref], wl[i], 1)
                  + _CLOCK_RTOL * abs(dt * per_ns)):
            out[i] = a
            continue
        out[i] = a
        ref = i
        run_end = max(run_end, a + wl[i])
    if not restarts:
        return f, []
    return np.asarray(out, np.int64), restarts
