"""Steps of a stepped run-up: plateaus of a speed profile.

:func:`detect_speed_steps` finds the maximal stretches of a
:class:`~rigtools.analysis.speed_types.SpeedProfile` lasting at least ``min_duration_s`` in
which every knot lies within ``max(abs_tolerance_rpm, rel_tolerance * n)`` of the stretch's
mid-range speed, using a sparse range-min/max table (``_RangeTable``). Re-exported by
:mod:`rigtools.analysis.speed`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rigtools.analysis.signal_checks import check_positive
from rigtools.analysis.speed_types import SpeedProfile, SpeedStep
from rigtools.errors import MissingSpeedError

__all__ = ["detect_speed_steps"]


# --- steps ------------------------------------------------------------------------------------
class _RangeTable:
    """Sparse table for O(1) range minimum and maximum queries."""

    def __init__(self, x: np.ndarray) -> None:
        self.mins = [x]
        self.maxs = [x]
        k = 1
        while 2 * k <= x.size:
            self.mins.append(np.minimum(self.mins[-1][:-k], self.mins[-1][k:]))
            self.maxs.append(np.maximum(self.maxs[-1][:-k], self.maxs[-1][k:]))
            k *= 2

    def query(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Min and max over ``[a, b)`` (``b > a``) elementwise."""
        length = b - a
        lev = np.floor(np.log2(np.maximum(length, 1))).astype(np.int64)
        lo = np.empty(a.shape)
        hi = np.empty(a.shape)
        for level in np.unique(lev):
            s = lev == level
            k = 1 << int(level)
            lo[s] = np.minimum(self.mins[level][a[s]], self.mins[level][b[s] - k])
            hi[s] = np.maximum(self.maxs[level][a[s]], self.maxs[level][b[s] - k])
        return lo, hi


def detect_speed_steps(
    speed: SpeedProfile,
    *,
    rel_tolerance: float = 0.01,
    abs_tolerance_rpm: float = 2.0,
    min_duration_s: float = 1.0,
) -> tuple[SpeedStep, ...]:
    """The plateaus of a stepped run-up.

    A plateau is a stretch of speed knots of one segment, lasting at least
    ``min_duration_s``, whose spread (largest minus smallest knot speed) is at most twice the
    stability tolerance ``tol = max(abs_tolerance_rpm, rel_tolerance * n_mid)``, ``n_mid`` the
    stretch's mid-range speed: every knot lies within ``tol`` of ``n_mid``.

    The search: every window of ``min_duration_s`` whose spread is within ``2 tol`` marks its
    knots as stable; overlapping stable windows merge. A merged stretch whose spread exceeds
    ``2 tol`` first loses end knots farther than ``tol`` from its median (the tail of a ramp);
    if it still spreads too far (a drift slower than the tolerance per ``min_duration_s``) it
    is cut greedily into consecutive pieces within tolerance, and pieces shorter than
    ``min_duration_s`` are left out. Ramps produce no stable window and so no step.

    Parameters
    ----------
    speed : SpeedProfile
        The speed.
    rel_tolerance : float
        Relative half-width of the stability band (default 1 %).
    abs_tolerance_rpm : float
        Smallest half-width of the band (rpm), for low speeds and quantised signals.
    min_duration_s : float
        Shortest plateau (s).

    Returns
    -------
    tuple of SpeedStep
        In time order.
    """
    if speed is None:
        raise MissingSpeedError(None, detail="steps are found from the speed; `speed` is None")
    rel = float(rel_tolerance)
    if not np.isfinite(rel) or rel < 0:
        raise ValueError(f"`rel_tolerance` must be a finite number >= 0, was {rel_tolerance!r}")
    abs_tol = float(abs_tolerance_rpm)
    if not np.isfinite(abs_tol) or abs_tol < 0:
        raise ValueError("`abs_tolerance_rpm` must be a finite number >= 0, was "
                         f"{abs_tolerance_rpm!r}")
    if rel == 0 and abs_tol == 0:
        raise ValueError("`rel_tolerance` and `abs_tolerance_rpm` cannot both be 0")
    dur = check_positive("min_duration_s", min_duration_s)

    def tol(n: np.ndarray | float) -> np.ndarray:
        return np.maximum(abs_tol, rel * np.abs(n))

    steps: list[SpeedStep] = []
    for s in range(speed.n_segments):
        k = speed.segment == s
        t, n = speed.time_s[k], speed.speed_rpm[k]
        if t.size < 2:
            continue
        # rounding allowance of t + dur on the logger clock (UNIX-epoch times lose digits)
        eps = 4.0 * float(np.spacing(max(abs(float(t[0])), abs(float(t[-1]))))) + 1e-9 * dur
        end = np.searchsorted(t, t + dur - eps, side="left")  # first knot at >= t_i + dur
        full = end < t.size
        a = np.flatnonzero(full)
        b = end[full] + 1  # window [a, b) spans at least `dur`
        if a.size == 0:
            continue
        table = _RangeTable(n)
        lo, hi = table.query(a, b)
        stable = (hi - lo) <= 2 * tol(0.5 * (hi + lo))
        a, b = a[stable], b[stable]
        # merge overlapping windows into stretches
        i = 0
        while i < a.size:
            s0, s1 = a[i], b[i]
            i += 1
            while i < a.size and a[i] < s1:
                s1 = max(s1, b[i])
                i += 1
            steps.extend(_cut_stretch(t[s0:s1], n[s0:s1], tol, dur, eps))
    return tuple(sorted(steps, key=lambda st: st.start_s))


def _cut_stretch(t: np.ndarray, n: np.ndarray, tol: Any, dur: float,
                 eps: float) -> list[SpeedStep]:
    # Trim ends that lie outside the band about the median (the tail of a ramp that the
    # stable windows took in), then accept the stretch if its spread is within the band.
    a, b = 0, t.size
    while b - a > 1:
        med = float(np.median(n[a:b]))
        band = float(tol(med))
        if abs(n[a] - med) > band:
            a += 1
        elif abs(n[b - 1] - med) > band:
            b -= 1
        else:
            break
    t, n = t[a:b], n[a:b]
    if t.size == 0:
        return []
    lo, hi = float(n.min()), float(n.max())
    if hi - lo <= 2 * float(tol(0.5 * (lo + hi))):
        if t[-1] - t[0] < dur - eps:
            return []
        return [SpeedStep(float(t[0]), float(t[-1]), float(np.median(n)), hi - lo,
                          float(tol(0.5 * (lo + hi))), int(t.size))]
    # A slow drift: cut greedily into consecutive pieces within the band.
    out = []
    i = 0
    while i < t.size:
        j = i + 1
        lo = hi = float(n[i])
        while j < t.size:
            lo2, hi2 = min(lo, float(n[j])), max(hi, float(n[j]))
            if hi2 - lo2 > 2 * float(tol(0.5 * (lo2 + hi2))):
                break
            lo, hi = lo2, hi2
            j += 1
        if t[j - 1] - t[i] >= dur - eps:
            out.append(SpeedStep(float(t[i]), float(t[j - 1]), float(np.median(n[i:j])),
                                 hi - lo, float(tol(0.5 * (lo + hi))), j - i))
        i = j
    return out
