r"""Shaft speed as a function of time, the mesh frequency, and the steps of a stepped run-up.

A speed reaches rigtools in one of two forms:

* a **slow signal** (``SlowSignal``: irregular samples, e.g. ``"PinionSpeed_rpm"`` at about
  10 Hz). :func:`speed_from_slow_signal` interpolates it **linearly** between samples: exact for
  a constant speed and for a linear ramp, and it never overshoots. It does not interpolate
  across a hole in the samples longer than ``max_gap_s`` (default five median sample
  intervals), and holds the end values for at most ``hold_s`` (default one median interval)
  beyond the first and last sample; elsewhere the speed is unknown (NaN).
* a **tacho channel** (``Channel``: uniform samples of a pulse train, ``pulses_per_rev`` pulses
  per revolution). :func:`tacho_edges` finds the rising edges with a Schmitt trigger and times
  each one to a fraction of a sample by linear interpolation of the crossing of the mid level;
  :func:`speed_from_tacho` turns the edges into one speed value per pulse, each averaged over
  one whole revolution (edges ``i`` and ``i + pulses_per_rev``), so unequal pulse spacing on
  the encoder wheel cancels. Edges are never paired across a gap (``valid == False``).

Both give a :class:`SpeedProfile`: knots ``(time_s, speed_rpm)`` in one or more segments,
linear between the knots of a segment, unknown between segments.

The mesh frequency of a gear with ``z`` teeth on the shaft turning at ``n`` rpm is

.. math::

    f_m = \frac{z\,n}{60}

(ISO 21771 / any gear text; seed 003 Sec. 4: 600-4100 rpm with z = 50 gives 500-3400 Hz).

Steps of a stepped run-up are plateaus of the speed (:func:`detect_speed_steps`): maximal
stretches lasting at least ``min_duration_s`` in which every knot lies within the stability
tolerance ``max(abs_tolerance_rpm, rel_tolerance * n)`` of the stretch's mid-range speed
``n`` (default: 1 % or 2 rpm, whichever is larger, for at least 1 s).

Errors
------
::

    RigtoolsError
    └── MissingSpeedError (LookupError)   no speed signal, or none covering the data analysed

:class:`MissingSpeedError` is defined here (rigtools.errors has no speed error); it carries
``name``, ``available`` and ``detail`` and survives pickling.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.errors import RigtoolsError
from rigtools.ingest.recording import Recording

__all__ = [
    "MissingSpeedError",
    "SpeedProfile",
    "SpeedStep",
    "detect_speed_steps",
    "mesh_frequency_Hz",
    "speed_from_slow_signal",
    "speed_from_tacho",
    "speed_profile",
    "tacho_edges",
]

#: Speed units a slow signal may carry, and the factor to rpm.
_RPM_PER_UNIT: dict[str, float] = {
    "rpm": 1.0,
    "1/min": 1.0,
    "r/min": 1.0,
    "rev/min": 1.0,
    "min^-1": 1.0,
    "min-1": 1.0,
    "hz": 60.0,
    "rev/s": 60.0,
    "r/s": 60.0,
    "1/s": 60.0,
    "rad/s": 60.0 / (2.0 * np.pi),
}


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


def _rpm_factor(unit: str) -> float:
    key = unit.strip().lower().replace(" ", "")
    if key not in _RPM_PER_UNIT:
        raise ValueError(
            f"`unit` must be a speed unit ({', '.join(sorted(_RPM_PER_UNIT))}), was {unit!r}"
        )
    return _RPM_PER_UNIT[key]


# --- mesh frequency ---------------------------------------------------------------------------
def mesh_frequency_Hz(speed_rpm: np.ndarray | float, z1: int) -> np.ndarray:  # noqa: N802
    r"""Mesh frequency of a gear of ``z1`` teeth on a shaft turning at ``speed_rpm``.

    Parameters
    ----------
    speed_rpm : array_like
        Shaft speed (rpm).
    z1 : int
        Teeth of the gear on that shaft (the pinion's z1 for the pinion speed).

    Returns
    -------
    numpy.ndarray
        :math:`f_m = z_1 n_1 / 60` (Hz).

    Examples
    --------
    >>> float(mesh_frequency_Hz(1500.0, 16))  # FZG type C pinion, rigtools.demo
    400.0
    >>> float(mesh_frequency_Hz(600.0, 50))   # Kahraman-Blankenship gears, seed 003 Sec. 4
    500.0
    """
    z = _check_teeth(z1)
    return np.asarray(speed_rpm, dtype=np.float64) * z / 60.0


def _check_teeth(z1: int) -> int:
    if isinstance(z1, bool) or int(z1) != z1 or int(z1) < 1:
        raise ValueError(f"`z1` must be a positive integer number of teeth, was {z1!r}")
    return int(z1)


# --- slow signal ------------------------------------------------------------------------------
def speed_from_slow_signal(
    time_s: np.ndarray,
    values: np.ndarray,
    *,
    unit: str = "rpm",
    max_gap_s: float | None = None,
    hold_s: float | None = None,
    name: str = "speed",
) -> SpeedProfile:
    """Speed profile from an irregularly sampled speed signal, interpolated linearly.

    Parameters
    ----------
    time_s : array_like
        Sample times (s, logger clock), non-decreasing.
    values : array_like
        Speed samples in ``unit``. Non-finite samples are dropped and counted.
    unit : str
        ``"rpm"`` (also ``"1/min"``, ``"r/min"``), ``"Hz"`` (``"rev/s"``) or ``"rad/s"``.
    max_gap_s : float, optional
        Samples farther apart than this are not interpolated across: the profile splits into
        segments and the speed between them is unknown (s). Default: five times the median
        sample interval.
    hold_s : float, optional
        How far beyond each segment's first and last sample the end value is held (s).
        Default: one median sample interval.
    name : str
        Signal name, for the ``source`` text.

    Returns
    -------
    SpeedProfile

    Raises
    ------
    MissingSpeedError
        When no finite sample remains.
    """
    t = _as_1d("time_s", time_s)
    v = _as_1d("values", values)
    if t.shape != v.shape:
        raise ValueError(f"`time_s` and `values` must have the same shape, have {t.shape} "
                         f"and {v.shape}")
    factor = _rpm_factor(unit)
    keep = np.isfinite(t) & np.isfinite(v)
    n_rejected = int(np.count_nonzero(~keep))
    t, rpm = t[keep], v[keep] * factor
    if t.size == 0:
        raise MissingSpeedError(name, detail="it holds no finite sample")
    if np.any(np.diff(t) < 0):
        raise ValueError("`time_s` must be non-decreasing")
    # Repeated time stamps: keep the last value at each time (interp needs increasing x).
    last = np.r_[np.diff(t) > 0, True]
    n_rejected += int(np.count_nonzero(~last))
    t, rpm = t[last], rpm[last]
    dt = np.diff(t)
    median_dt = float(np.median(dt)) if dt.size else 0.0
    gap = 5.0 * median_dt if max_gap_s is None else _check_positive("max_gap_s", max_gap_s)
    hold = median_dt if hold_s is None else float(hold_s)
    if hold < 0 or not np.isfinite(hold):
        raise ValueError(f"`hold_s` must be a finite number >= 0, was {hold_s!r}")
    segment = np.r_[0, np.cumsum(dt > gap)].astype(np.int64)
    n_seg = int(segment[-1]) + 1
    first = np.searchsorted(segment, np.arange(n_seg), side="left")
    lastk = np.searchsorted(segment, np.arange(n_seg), side="right") - 1
    return SpeedProfile(
        time_s=t,
        speed_rpm=rpm,
        segment=segment,
        cover_start_s=t[first] - hold,
        cover_stop_s=t[lastk] + hold,
        source=(f"slow signal {name!r} ({unit}), linear interpolation, not across holes "
                f"> {gap:.3g} s, ends held {hold:.3g} s"),
        n_rejected=n_rejected,
    )


# --- tacho ------------------------------------------------------------------------------------
def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges ``[a, b)`` of consecutive ``True`` in ``mask``."""
    m = np.r_[False, mask, False].astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    stops = np.flatnonzero(d == -1)
    return list(zip(starts.tolist(), stops.tolist(), strict=True))


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
    x = _as_1d("values", values)
    fs = _check_fs(sample_rate_Hz)
    ok = _check_valid(valid, x.size) & np.isfinite(x)
    if not np.any(ok):
        return np.empty(0), np.empty(0, dtype=np.int64)
    p5, p95 = np.percentile(x[ok], [5.0, 95.0])
    mid = 0.5 * (p5 + p95) if threshold is None else float(threshold)
    hyst = 0.2 * (p95 - p5) if hysteresis is None else float(hysteresis)
    if not np.isfinite(hyst) or hyst < 0:
        raise ValueError(f"`hysteresis` must be a finite number >= 0, was {hysteresis!r}")
    times, runs = [], []
    for r, (a, b) in enumerate(_runs(ok)):
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


# --- from a Recording -------------------------------------------------------------------------
def speed_profile(
    recording: Recording,
    name: str | None,
    *,
    pulses_per_rev: int | None = None,
    **kwargs: Any,
) -> SpeedProfile:
    """The speed profile of a Recording's speed signal: a slow signal or a tacho channel.

    Parameters
    ----------
    recording : Recording
        The run.
    name : str or None
        Name of a slow signal (speed in rpm, Hz or rad/s, by its unit) or of a tacho channel.
    pulses_per_rev : int, optional
        Needed when ``name`` is a channel.
    **kwargs
        Passed to :func:`speed_from_slow_signal` or :func:`speed_from_tacho`.

    Returns
    -------
    SpeedProfile

    Raises
    ------
    MissingSpeedError
        When ``name`` is None or names neither a slow signal nor a channel.
    """
    available = [*recording.slow, *recording.channels]
    if name is None:
        raise MissingSpeedError(None, available, "no speed signal was named")
    if name in recording.slow:
        s = recording.slow[name]
        return speed_from_slow_signal(s.time_s, s.values, unit=s.unit, name=name, **kwargs)
    if name in recording.channels:
        if pulses_per_rev is None:
            raise ValueError(f"`pulses_per_rev` is needed: {name!r} is a channel, read as a "
                             "tacho pulse train")
        c = recording.channels[name]
        return speed_from_tacho(c.values, c.sample_rate_Hz, pulses_per_rev,
                                start_time_s=float(c.time_s[0]) if len(c) else c.start_time_s,
                                valid=c.valid, name=name, **kwargs)
    raise MissingSpeedError(name, available,
                            "no slow signal or channel of that name is in the recording")


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
    dur = _check_positive("min_duration_s", min_duration_s)

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
