"""Uniform time bases rebuilt from sample counters, checked against logger timestamps.

A logger stamps each frame or message with its own clock, which jitters and drifts; the
sensor's sample counter does not. The time base of a uniform channel is therefore
``t = t0 + index / fs`` with ``index`` from the unwrapped counter and ``fs`` the nominal rate.
The logger timestamps are used for two things only: to choose, for each counter step, the
number of whole wraps that fits the elapsed time (so a gap longer than one wrap is not
mistaken for a short one), and to report how far the logger clock strays from the counter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["UnwrappedCounter", "indices_from_stamps", "timebase_check", "unwrap_counter"]


@dataclass(frozen=True)
class UnwrappedCounter:
    """Result of :func:`unwrap_counter`.

    Attributes
    ----------
    ticks : numpy.ndarray
        Absolute tick (counter value with wraps added), int64, one per input element.
    keep : numpy.ndarray
        Boolean mask: ``False`` for duplicates and for steps that went backwards.
    n_duplicate : int
        Elements whose tick equals that of an earlier kept element.
    n_backwards : int
        Elements whose tick is below the last kept one (late or reordered frames).
    restarts : numpy.ndarray
        Positions (into the input) where the counter disagreed with the clock by more than the
        tolerance and the tick was resynchronised from the timestamps.
    """

    ticks: np.ndarray
    keep: np.ndarray
    n_duplicate: int
    n_backwards: int
    restarts: np.ndarray


def unwrap_counter(
    counter: np.ndarray,
    modulus: int,
    stamps_s: np.ndarray | None = None,
    tick_rate_Hz: float | None = None,
) -> UnwrappedCounter:
    """Unwrap a modular sample counter into absolute ticks.

    Parameters
    ----------
    counter : numpy.ndarray
        Raw counter values in ``[0, modulus)``, in arrival order.
    modulus : int
        Counter modulus, ``2**bits``.
    stamps_s : numpy.ndarray, optional
        Logger timestamps of the same elements (s). With ``tick_rate_Hz``, used to choose the
        number of wraps between elements and to detect restarts.
    tick_rate_Hz : float, optional
        Nominal counter rate (ticks per second).

    Returns
    -------
    UnwrappedCounter

    Notes
    -----
    Without timestamps each step ``d = (c[i] - c[i-1]) mod M`` is taken as ``d`` ticks forward
    when ``0 < d <= M/2``, a duplicate when ``d == 0``, and a step backwards otherwise.
    With timestamps, the step is ``d + k M`` with ``k`` the whole number of wraps that brings
    it closest to the elapsed time times the tick rate; a step that still disagrees with the
    clock by more than a quarter wrap (and by more than 10 % of the elapsed ticks) is a
    counter restart, and the tick is resynchronised from the clock.
    """
    c = np.asarray(counter).astype(np.int64, copy=False)
    n = c.shape[0]
    if n == 0:
        empty = np.zeros(0, np.int64)
        return UnwrappedCounter(empty, np.zeros(0, bool), 0, 0, empty)
    m = int(modulus)
    d = np.diff(c) % m
    use_clock = stamps_s is not None and tick_rate_Hz is not None and n > 1
    restarts = np.zeros(0, np.int64)
    if use_clock:
        assert stamps_s is not None and tick_rate_Hz is not None
        expected = np.diff(np.asarray(stamps_s, np.float64)) * float(tick_rate_Hz)
        k = np.round((expected - d) / m)
        k = np.maximum(k, 0)
        step = d + k * m
        # Backwards steps look like almost a full wrap forward in no time.
        backwards = (d > m // 2) & (expected < d - m / 4)
        step = np.where(backwards, d - m, step)
        tol = np.maximum(m / 4, 0.1 * np.abs(expected))
        bad = ~backwards & (np.abs(step - expected) > tol) & (expected > m / 2)
        restarts = np.flatnonzero(bad) + 1
        step = np.where(bad, np.round(expected), step).astype(np.int64)
    else:
        step = np.where(d > m // 2, d - m, d).astype(np.int64)
    # A step backwards followed by a steady run is a counter restart (sensor or logger
    # reset), not a late frame: resynchronise there instead of discarding all that follows.
    back = np.flatnonzero(step < 0)
    if back.size:
        typical = int(np.median(d)) if d.size else 1
        run = 8
        new_restarts = []
        for p in back:
            following = d[p + 1 : p + 1 + run]
            if following.size and np.all(following == typical):
                if use_clock:
                    assert stamps_s is not None and tick_rate_Hz is not None
                    dt = float(stamps_s[p + 1] - stamps_s[p]) * float(tick_rate_Hz)
                    step[p] = max(1, round(dt))
                else:
                    step[p] = max(1, typical)
                new_restarts.append(p + 1)
        if new_restarts:
            restarts = np.union1d(restarts, np.asarray(new_restarts, np.int64))
    ticks = np.empty(n, np.int64)
    ticks[0] = c[0]
    np.cumsum(step, out=ticks[1:])
    ticks[1:] += c[0]
    # Keep an element only when it advances past every earlier kept element.
    running_max = np.maximum.accumulate(ticks)
    keep = np.ones(n, bool)
    keep[1:] = ticks[1:] > running_max[:-1]
    dup = np.zeros(n, bool)
    dup[1:] = ticks[1:] == running_max[:-1]
    n_dup = int(dup.sum())
    n_back = int((~keep).sum()) - n_dup
    return UnwrappedCounter(ticks, keep, n_dup, n_back, restarts)


def indices_from_stamps(stamps_s: np.ndarray, sample_rate_Hz: float) -> np.ndarray:
    """Sample indices of irregularly stamped samples on a nominal grid.

    ``round((t - t[0]) * fs)``; used where a source carries no counter (ROS ``Imu`` header
    stamps). Duplicates and gaps then show up as repeated or skipped indices.
    """
    t = np.asarray(stamps_s, np.float64)
    if t.size == 0:
        return np.zeros(0, np.int64)
    return np.round((t - t[0]) * float(sample_rate_Hz)).astype(np.int64)


def timebase_check(
    index: np.ndarray, stamps_s: np.ndarray, sample_rate_Hz: float
) -> tuple[float, dict[str, float]]:
    """Fit the logger clock against the counter time base.

    Parameters
    ----------
    index : numpy.ndarray
        Absolute sample index of the element each stamp belongs to.
    stamps_s : numpy.ndarray
        Logger timestamps (s).
    sample_rate_Hz : float
        Nominal rate (Hz).

    Returns
    -------
    start_time_s : float
        Time of sample index 0: the median of ``stamp - index / fs`` (robust to jitter and to a
        few late frames).
    stats : dict
        ``drift_ppm`` (slope of the residual), ``jitter_s`` (robust spread of the residual),
        ``max_abs_residual_s`` and ``n_stamps_backwards``.
    """
    idx = np.asarray(index, np.float64)
    t = np.asarray(stamps_s, np.float64)
    if t.size == 0:
        return 0.0, {}
    offset = t - idx / float(sample_rate_Hz)
    t0 = float(np.median(offset))
    resid = offset - t0
    stats = {
        "max_abs_residual_s": float(np.max(np.abs(resid))),
        "jitter_s": float(1.4826 * np.median(np.abs(resid - np.median(resid)))),
        "n_stamps_backwards": float(np.count_nonzero(np.diff(t) < 0)),
    }
    if t.size > 2 and np.ptp(idx) > 0:
        slope = np.polyfit(idx / float(sample_rate_Hz), resid, 1)[0]
        stats["drift_ppm"] = float(slope * 1e6)
    return t0, stats
