"""Shaft speed from a tacho channel: Schmitt-trigger edges and one-revolution speed means.

:func:`tacho_edges` finds the rising edges of a uniformly sampled pulse train with a Schmitt
trigger, timed to a fraction of a sample by linear interpolation of the mid-level crossing;
:func:`speed_from_tacho` turns them into a :class:`~rigtools.analysis.speed_types.SpeedProfile`
with one speed value per pulse, averaged over one whole revolution, never pairing edges across
a gap. Both are re-exported by :mod:`rigtools.analysis.speed`.
"""

from __future__ import annotations

import numpy as np

from rigtools.analysis.signal_checks import as_1d, check_sample_rate, check_valid_1d
from rigtools.analysis.speed_types import SpeedProfile
from rigtools.analysis.windows import true_runs
from rigtools.errors import MissingSpeedError

__all__ = ["speed_from_tacho", "tacho_edges"]


def _edges_in_run(x: np.ndarray, lo: float, mid: float, hi: float) -> np.ndarray:
    """Sub-sample indices of the rising crossings of ``mid`` confirmed by the trigger."""
    n = x.size
    state = np.zeros(n, dtype=np.int8)
    state[x >= hi] = 1
    state[x <= lo] = -1
    # forward-fill the last decided state (Schmitt trigger)
    idx = np.where(state != 0, np.arange(n), 0)
    np.maximum.accumulate(idx, out=idx)
    filled = state[idx]
    filled[(idx == 0) & (state[0] == 0)] = 0  # undecided before the first decision
    rise = np.flatnonzero((filled[1:] == 1) & (filled[:-1] == -1)) + 1
    if rise.size == 0:
        return np.empty(0)
    # last sample at or below the mid level before each confirmed rise
    below = np.where(x <= mid, np.arange(n), -1)
    np.maximum.accumulate(below, out=below)
    j = below[rise]
    ok = (j >= 0) & (j + 1 < n)
    j = j[ok]
    x0, x1 = x[j], x[j + 1]
    return j + (mid - x0) / (x1 - x0)


def tacho_edges(
    values: np.ndarray,
    sample_rate_Hz: float,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    threshold: float | None = None,
    hysteresis: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rising edges of a tacho pulse train, timed to a fraction of a sample.

    A Schmitt trigger confirms an edge when the signal rises from below
    ``threshold - hysteresis / 2`` to above ``threshold + hysteresis / 2``; the edge time is
    the crossing of ``threshold`` found by linear interpolation between the two samples that
    bracket it. Gaps (``valid == False``) end the search: edges on both sides of a gap belong
    to different runs and are never paired.

    Parameters
    ----------
    values : array_like
        Tacho samples (any unit), uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    start_time_s : float
        Time of ``values[0]`` (s, logger clock).
    valid : array_like of bool, optional
        Per-sample validity (``Channel.valid``); default all valid.
    threshold : float, optional
        Mid level. Default: halfway between the 5th and 95th percentiles of the valid samples.
    hysteresis : float, optional
        Width of the trigger's dead band. Default: 20 % of the 5th-95th percentile range.

    Returns
    -------
    edge_time_s : numpy.ndarray
        Edge times (s).
    run : numpy.ndarray
        For each edge, the number of the gap-free run it lies in (int).
    """
    x = as_1d("values", values)
    fs = check_sample_rate(sample_rate_Hz)
    ok = check_valid_1d(valid, x.size) & np.isfinite(x)
    if not np.any(ok):
        return np.empty(0), np.empty(0, dtype=np.int64)
    p5, p95 = np.percentile(x[ok], [5.0, 95.0])
    mid = 0.5 * (p5 + p95) if threshold is None else float(threshold)
    hyst = 0.2 * (p95 - p5) if hysteresis is None else float(hysteresis)
    if not np.isfinite(hyst) or hyst < 0:
        raise ValueError(f"`hysteresis` must be a finite number >= 0, was {hysteresis!r}")
    times, runs = [], []
    for r, (a, b) in enumerate(true_runs(ok)):
        e = _edges_in_run(x[a:b], mid - hyst / 2, mid, mid + hyst / 2)
        times.append(start_time_s + (a + e) / fs)
        runs.append(np.full(e.size, r, dtype=np.int64))
    return np.concatenate(times), np.concatenate(runs)


def speed_from_tacho(
    values: np.ndarray,
    sample_rate_Hz: float,
    pulses_per_rev: int,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    threshold: float | None = None,
    hysteresis: float | None = None,
    name: str = "tacho",
) -> SpeedProfile:
    r"""Speed profile from a tacho channel: one value per pulse, averaged over a revolution.

    With edge times :math:`t_i` (:func:`tacho_edges`) and ``p`` pulses per revolution, the knot

    .. math::

        t = \tfrac12 (t_i + t_{i+p}), \qquad n = \frac{60}{t_{i+p} - t_i}

    is the mean speed over one revolution, placed at its middle: exact for a constant speed
    and for a linear ramp, and blind to the spacing errors of the pulses on the wheel. Each
    gap-free run of the channel is its own segment; within it the speed is known from the
    first to the last edge (the end knots' values are held over the half revolution at each
    end).

    Parameters
    ----------
    values : array_like
        Tacho samples.
    sample_rate_Hz : float
        Sample rate (Hz).
    pulses_per_rev : int
        Pulses per revolution of the shaft.
    start_time_s : float
        Time of ``values[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity.
    threshold, hysteresis : float, optional
        Trigger levels, see :func:`tacho_edges`.
    name : str
        Channel name, for the ``source`` text.

    Returns
    -------
    SpeedProfile

    Raises
    ------
    MissingSpeedError
        When no run holds a whole revolution of pulses.
    """
    if isinstance(pulses_per_rev, bool) or int(pulses_per_rev) != pulses_per_rev or \
            int(pulses_per_rev) < 1:
        raise ValueError(f"`pulses_per_rev` must be a positive integer, was {pulses_per_rev!r}")
    p = int(pulses_per_rev)
    edges, run = tacho_edges(values, sample_rate_Hz, start_time_s=start_time_s, valid=valid,
                             threshold=threshold, hysteresis=hysteresis)
    t_k, n_k, seg_k, c0, c1 = [], [], [], [], []
    n_rejected = 0
    seg = 0
    for r in np.unique(run):
        e = edges[run == r]
        if e.size < p + 1:
            n_rejected += int(e.size)
            continue
        d = e[p:] - e[:-p]
        t_k.append(0.5 * (e[p:] + e[:-p]))
        n_k.append(60.0 / d)
        seg_k.append(np.full(d.size, seg, dtype=np.int64))
        c0.append(e[0])
        c1.append(e[-1])
        seg += 1
    if seg == 0:
        raise MissingSpeedError(
            name, detail=f"no gap-free stretch of the tacho holds {p + 1} rising edges "
                         f"(one revolution at {p} pulses per revolution); {edges.size} found")
    return SpeedProfile(
        time_s=np.concatenate(t_k),
        speed_rpm=np.concatenate(n_k),
        segment=np.concatenate(seg_k),
        cover_start_s=np.asarray(c0),
        cover_stop_s=np.asarray(c1),
        source=(f"tacho {name!r}, {p} pulses/rev, Schmitt trigger, sub-sample edges by linear "
                f"interpolation, one-revolution means, linear between them"),
        n_rejected=n_rejected,
    )
