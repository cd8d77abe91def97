"""Speed data types, the missing-speed error and the argument checks shared by the speed modules.

Holds :class:`MissingSpeedError`, :class:`SpeedProfile` (knots in segments, linear between
knots of a segment) and :class:`SpeedStep` (one plateau of a stepped run-up), plus the small
private validators (``_as_1d``, ``_check_positive``, ``_check_fs``, ``_check_valid``,
``_check_teeth``) and ``_runs`` that the speed, tacho, resampling and order modules use.
The public names are re-exported by :mod:`rigtools.analysis.speed`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.errors import RigtoolsError


class MissingSpeedError(RigtoolsError, LookupError):
    """Order analysis needs a shaft speed that is absent or covers none of the data.

    Parameters
    ----------
    name : str or None
        The speed signal asked for (``None`` when none was given).
    available : sequence of str
        Slow signals and channels the recording does hold.
    detail : str or None
        What exactly is missing.
    """

    def __init__(
        self, name: str | None, available: Sequence[str] = (), detail: str | None = None
    ) -> None:
        self.name = name
        self.available = tuple(available)
        self.detail = detail
        super().__init__(str(self))

    def __str__(self) -> str:
        what = f"speed signal {self.name!r}" if self.name is not None else "a speed signal"
        msg = f"order analysis needs {what}"
        if self.detail:
            msg += f": {self.detail}"
        if self.available:
            msg += f" (the recording holds: {', '.join(sorted(self.available))})"
        return msg

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.name, self.available, self.detail))


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


# --- validation -------------------------------------------------------------------------------
def _as_1d(name: str, x: Any) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"`{name}` must be one-dimensional, has shape {a.shape}")
    return a


def _check_positive(name: str, value: float) -> float:
    v = float(value)
    if not np.isfinite(v) or v <= 0.0:
        raise ValueError(f"`{name}` must be a positive finite number, was {value!r}")
    return v


def _check_fs(sample_rate_Hz: float) -> float:
    return _check_positive("sample_rate_Hz", sample_rate_Hz)


def _check_valid(valid: Any, n: int) -> np.ndarray:
    if valid is None:
        return np.ones(n, dtype=bool)
    v = np.asarray(valid, dtype=bool)
    if v.shape != (n,):
        raise ValueError(f"`valid` must have shape ({n},) like the values, has {v.shape}")
    return v


def _check_teeth(z1: int) -> int:
    if isinstance(z1, bool) or int(z1) != z1 or int(z1) < 1:
        raise ValueError(f"`z1` must be a positive integer number of teeth, was {z1!r}")
    return int(z1)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges ``[a, b)`` of consecutive ``True`` in ``mask``."""
    m = np.r_[False, mask, False].astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    stops = np.flatnonzero(d == -1)
    return list(zip(starts.tolist(), stops.tolist(), strict=True))
