"""Speed data types: a shaft speed over time and the plateaus of a stepped run-up.

:class:`SpeedProfile` (knots in segments, linear between knots of a segment) and
:class:`SpeedStep` (one plateau of a stepped run-up), re-exported by
:mod:`rigtools.analysis.speed`. Their argument checks are in
:mod:`rigtools.analysis.signal_checks`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SpeedProfile", "SpeedStep"]


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    """Shaft speed as a function of time: knots, linear between knots of one segment.

    Attributes
    ----------
    time_s : numpy.ndarray
        Knot times (s, logger clock), increasing, shape ``(k,)``.
    speed_rpm : numpy.ndarray
        Shaft speed at the knots (rpm), shape ``(k,)``.
    segment : numpy.ndarray
        Segment number of each knot (int, non-decreasing). The speed is interpolated only
        between knots of the same segment.
    cover_start_s, cover_stop_s : numpy.ndarray
        Per segment, the span over which the speed is known (s); the end knots' values are
        held between a segment's first knot and ``cover_start_s`` and between its last knot
        and ``cover_stop_s``.
    source : str
        Where the speed came from and how it is interpolated.
    n_rejected : int
        Input samples not used (non-finite speed values, tacho pulses without a full
        revolution next to them).
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    segment: np.ndarray
    cover_start_s: np.ndarray
    cover_stop_s: np.ndarray
    source: str
    n_rejected: int = 0

    @property
    def n_segments(self) -> int:
        """Number of segments."""
        return int(self.cover_start_s.shape[0])

    def rpm_at(self, t_s: np.ndarray | float) -> np.ndarray:
        """Speed at times ``t_s`` (rpm): linear between knots, NaN where unknown.

        Parameters
        ----------
        t_s : array_like
            Times on the logger clock (s).

        Returns
        -------
        numpy.ndarray
            Speed (rpm), same shape as ``t_s``; NaN outside every segment's cover.
        """
        t = np.asarray(t_s, dtype=np.float64)
        out = np.full(t.shape, np.nan)
        for s in range(self.n_segments):
            sel = (t >= self.cover_start_s[s]) & (t <= self.cover_stop_s[s])
            if not np.any(sel):
                continue
            k = self.segment == s
            out[sel] = np.interp(t[sel], self.time_s[k], self.speed_rpm[k])
        return out

    def frequency_Hz_at(self, t_s: np.ndarray | float) -> np.ndarray:  # noqa: N802 (unit)
        """Shaft rotation frequency ``n / 60`` at times ``t_s`` (Hz), NaN where unknown."""
        return self.rpm_at(t_s) / 60.0


@dataclass(frozen=True)
class SpeedStep:
    """One plateau of a stepped run-up.

    Attributes
    ----------
    start_s, stop_s : float
        First and last knot of the plateau (s, logger clock).
    speed_rpm : float
        Median speed over the plateau's knots (rpm).
    spread_rpm : float
        Largest minus smallest knot speed on the plateau (rpm); at most twice the tolerance.
    tolerance_rpm : float
        The stability half-width used for this plateau (rpm).
    n_knots : int
        Speed knots on the plateau.
    """

    start_s: float
    stop_s: float
    speed_rpm: float
    spread_rpm: float
    tolerance_rpm: float
    n_knots: int

    @property
    def duration_s(self) -> float:
        """``stop_s - start_s`` (s)."""
        return self.stop_s - self.start_s
